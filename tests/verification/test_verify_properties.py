"""Property tests: our verdicts against independent oracles on random formulas and traces.

- lasso traces: Spot product emptiness with the automaton of the *negated* formula, built
  in the test (the implementation uses the automaton of the formula, conjunct by conjunct);
- finite traces: a direct recursive LTLf evaluator written in the test;
- explanations: the reported bad prefix is bad and the one before it is not (both decided
  by Spot satisfiability of ``f & prefix``), and the comparison word satisfies ``f``.
"""

from __future__ import annotations

import os

import spot
from hypothesis import given, settings
from hypothesis import strategies as st

from tamp import ltl
from tamp.verification.traces import check_trace
from tamp.verification.words import Word
from tests.verification.ltlf_oracle import lasso_violates, ltlf_holds, prefix_is_bad

#: Examples per property (raise with VERIFY_EXAMPLES=2000 for a longer sweep).
EXAMPLES = int(os.environ.get("VERIFY_EXAMPLES", "150"))

UNARY = ["!", "X", "F", "G"]
BINARY = ["&", "|", "U", "R", "->", "W"]


@st.composite
def formulas(draw, props: list[str], depth: int = 3, *, next_free: bool = False) -> str:
    if depth == 0 or draw(st.integers(0, 3)) == 0:
        return draw(st.sampled_from(props + ["1", "0"] if draw(st.booleans()) else props))
    if draw(st.booleans()):
        op = draw(st.sampled_from([u for u in UNARY if not (next_free and u == "X")]))
        return f"{op}({draw(formulas(props, depth - 1, next_free=next_free))})"
    op = draw(st.sampled_from(BINARY))
    a = draw(formulas(props, depth - 1, next_free=next_free))
    b = draw(formulas(props, depth - 1, next_free=next_free))
    return f"({a}) {op} ({b})"


@st.composite
def cases(draw, *, finite: bool, next_free: bool = False):
    n = draw(st.integers(2, 4))
    props = [f"p{i}" for i in range(n)]
    f = draw(formulas(props, next_free=next_free))
    letter = st.frozensets(st.sampled_from(props + ["extra"]))
    if finite:
        prefix = draw(st.lists(letter, min_size=0, max_size=7))
        return f, prefix, None
    prefix = draw(st.lists(letter, min_size=0, max_size=5))
    cycle = draw(st.lists(letter, min_size=1, max_size=4))
    return f, prefix, cycle


@settings(max_examples=EXAMPLES)
@given(cases(finite=False))
def test_lasso_verdict_matches_negated_product(case) -> None:
    text, prefix, cycle = case
    f = spot.formula(text)
    v = check_trace(f, Word.lasso(prefix, cycle))
    assert v.holds == (not lasso_violates(f, prefix, cycle))
    if not v.holds:
        ce = v.counterexample
        if ce.accepting_word is not None:
            acc = ce.accepting_word
            assert not lasso_violates(f, list(acc.prefix), list(acc.cycle))
        if ce.position is not None:
            w = ce.word
            bad = [w.letter(i) for i in range(ce.position + 1)]
            assert prefix_is_bad(f, bad, finite=False)
            assert not prefix_is_bad(f, bad[:-1], finite=False)
            if ce.accepting_word is not None:
                aps = set(ce.aps)
                assert [acc.letter(i) & aps for i in range(ce.position)] == [
                    x & aps for x in bad[:-1]
                ]


@settings(max_examples=EXAMPLES)
@given(cases(finite=True))
def test_finite_verdict_matches_explicit_ltlf_evaluator(case) -> None:
    text, prefix, _ = case
    f = spot.formula(text)
    v = check_trace(f, Word.finite(prefix), finite=True)
    assert v.holds == ltlf_holds(f, prefix)
    if not v.holds and v.counterexample.accepting_word is not None:
        ce = v.counterexample
        assert ltlf_holds(f, list(ce.accepting_word.prefix))
        if ce.position is not None:
            assert prefix_is_bad(f, prefix[: ce.position + 1], finite=True)
            assert not prefix_is_bad(f, prefix[: ce.position], finite=True) or ce.position == 0


@settings(max_examples=EXAMPLES // 2)
@given(cases(finite=False, next_free=True), st.data())
def test_stutter_invariance_without_next(case, data) -> None:
    text, prefix, cycle = case
    word = Word.lasso(prefix, cycle)
    i = data.draw(st.integers(0, len(prefix) + len(cycle) - 1))
    k = data.draw(st.integers(1, 3))
    if i < len(prefix):
        stuttered = Word.lasso(prefix[:i] + [prefix[i]] * (k + 1) + prefix[i + 1 :], cycle)
    else:
        j = i - len(prefix)
        stuttered = Word.lasso(prefix, cycle[:j] + [cycle[j]] * (k + 1) + cycle[j + 1 :])
    assert check_trace(text, word).holds == check_trace(text, stuttered).holds


@st.composite
def systems(draw):
    n_props = draw(st.integers(2, 3))
    props = [f"p{i}" for i in range(n_props)]
    n = draw(st.integers(1, 6))
    labels = [draw(st.frozensets(st.sampled_from(props))) for _ in range(n)]
    succ = [draw(st.lists(st.integers(0, n - 1), max_size=3, unique=True)) for _ in range(n)]
    f = draw(formulas(props))
    return props, labels, succ, f


def _hoa_violates(props, labels, succ, f: spot.formula) -> bool:
    """Oracle: the system as a HOA automaton (all runs accepting), product with A(!f)."""
    neg = ltl.translate(ltl.negate(f), ltl.Options(level="high", pref="small"))
    ap = sorted(props)

    def lab(x):
        return "&".join(str(i) if p in x else f"!{i}" for i, p in enumerate(ap))

    lines = [
        "HOA: v1",
        f"States: {len(labels)}",
        "Start: 0",
        f"AP: {len(ap)} " + " ".join(f'"{p}"' for p in ap),
        "acc-name: all",
        "Acceptance: 0 t",
        "--BODY--",
    ]
    for s, x in enumerate(labels):
        lines.append(f"State: {s}")
        for d in succ[s] or [s]:  # a dead end repeats forever
            lines.append(f"[{lab(x)}] {d}")
    lines.append("--END--")
    system = spot.automaton("\n".join(lines) + "\n")
    return not spot.product(system, neg).is_empty()


@settings(max_examples=EXAMPLES // 2)
@given(systems())
def test_model_check_matches_hoa_product_oracle(case) -> None:
    from tamp.verification.kripke import TransitionSystem, model_check

    props, labels, succ, text = case
    f = spot.formula(text)
    ts = TransitionSystem()
    for i, x in enumerate(labels):
        ts.add_state(x, f"s{i}")
    for i, ds in enumerate(succ):
        for d in ds:
            ts.add_edge(i, d)
    v = model_check(ts, f)
    assert v.holds == (not _hoa_violates(props, labels, succ, f))
    if not v.holds:
        ce = v.counterexample
        assert lasso_violates(f, list(ce.word.prefix), list(ce.word.cycle))
        # the run is a path of the system, starting in its initial state
        path = [int(s[1:]) for s in ce.steps]
        assert path[0] == 0
        loop = path + [path[len(ce.word.prefix)]]
        for a, b in zip(loop, loop[1:], strict=False):
            assert b in succ[a] or (not succ[a] and a == b)
