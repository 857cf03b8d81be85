"""Independent oracles for the verification tests (no code from `verification`).

- `ltlf_holds`: a direct recursive LTLf evaluator over finite traces (Spot's LTLf
  conventions: ``X`` is the weak next, ``X[!]`` the strong next, traces are non-empty).
- `lasso_violates`: Spot product emptiness of the word with the automaton of ``!f``
  (the implementation uses the automaton of ``f``, conjunct by conjunct).
"""

from __future__ import annotations

from functools import cache

import spot


def ltlf_holds(f: spot.formula, trace: list[frozenset[str]]) -> bool:
    n = len(trace)
    if n == 0:
        return False

    @cache
    def ev(g: spot.formula, i: int) -> bool:
        k = g.kindstr()
        if k == "tt":
            return True
        if k == "ff":
            return False
        if k == "ap":
            return g.ap_name() in trace[i]
        c = list(g)
        if k == "Not":
            return not ev(c[0], i)
        if k == "And":
            return all(ev(x, i) for x in c)
        if k == "Or":
            return any(ev(x, i) for x in c)
        if k == "Implies":
            return (not ev(c[0], i)) or ev(c[1], i)
        if k == "Equiv":
            return ev(c[0], i) == ev(c[1], i)
        if k == "Xor":
            return ev(c[0], i) != ev(c[1], i)
        if k == "X":
            return i + 1 >= n or ev(c[0], i + 1)
        if k == "strong_X":
            return i + 1 < n and ev(c[0], i + 1)
        if k == "F":
            return any(ev(c[0], j) for j in range(i, n))
        if k == "G":
            return all(ev(c[0], j) for j in range(i, n))
        if k == "U":
            return any(ev(c[1], j) and all(ev(c[0], m) for m in range(i, j)) for j in range(i, n))
        if k == "W":
            return ev(spot.formula.U(c[0], c[1]), i) or all(ev(c[0], j) for j in range(i, n))
        if k == "R":  # a R b = !(!a U !b)
            return all(ev(c[1], j) or any(ev(c[0], m) for m in range(i, j)) for j in range(i, n))
        if k == "M":  # a M b = b U (a & b)
            return any(
                ev(c[0], j) and ev(c[1], j) and all(ev(c[1], m) for m in range(i, j))
                for j in range(i, n)
            )
        raise ValueError(f"operator {k} not supported by the oracle")

    return ev(f, 0)


def _letter(aps: list[str], x: frozenset[str]) -> str:
    if not aps:
        return "1"
    return " & ".join(
        str(spot.formula.ap(a)) if a in x else "!" + str(spot.formula.ap(a)) for a in aps
    )


def lasso_violates(
    f: spot.formula, prefix: list[frozenset[str]], cycle: list[frozenset[str]]
) -> bool:
    """True when prefix·cycle^ω is accepted by the automaton of !f."""
    neg = spot.translate(spot.formula.Not(f), "Buchi", "SBAcc", "small", "high")
    aps = sorted(a.ap_name() for a in spot.atomic_prop_collect(f))
    parts = [_letter(aps, x) for x in prefix]
    parts.append("cycle{" + "; ".join(_letter(aps, x) for x in cycle) + "}")
    word = spot.parse_word("; ".join(parts), neg.get_dict())
    return bool(neg.intersects(word.as_automaton()))


def prefix_is_bad(f: spot.formula, prefix: list[frozenset[str]], *, finite: bool) -> bool:
    """True when no word (finite or infinite) starting with ``prefix`` satisfies ``f``.

    Built as the formula ``f & l0 & X(l1 & X(…))`` (strong nexts in LTLf) and tested for
    satisfiability by Spot, independently of the implementation's automaton walk.
    """
    aps = sorted(a.ap_name() for a in spot.atomic_prop_collect(f))
    nxt = "X[!]" if finite else "X"
    text = "1"
    for x in reversed(prefix):
        text = f"({_letter(aps, x)}) & {nxt}({text})" if text != "1" else f"({_letter(aps, x)})"
    g = spot.formula.And([f, spot.formula(text)])
    if finite:
        g = spot.from_ltlf(g, "alive")
    return spot.translate(g, "Buchi", "SBAcc").is_empty()
