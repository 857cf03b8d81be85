"""The task automaton: an LTL formula translated by Spot into a state-based Büchi automaton.

Zhou et al. §III-A, Def. 2: ``B = (Q, Q_0, Σ, δ, F)``. Spot 2.13 translates with
``spot.translate(f, 'Buchi', 'SBAcc', 'small', 'high')``; the plain ``'BA'`` option loses
state-based acceptance in this build (its option parser drops the flag), so it is never used.

The robot does one thing at a time, so only *executable* letters are read: the empty letter
(no delivery this step) and the singletons ``{p}``. :class:`Automaton` precomputes
``δ(q, σ)`` for those letters once, so the planners never touch a BDD in their inner loops.

This wrapper is also what ``verification`` consumes (stable API): ``spot_aut``, ``initial``,
``accepting``, ``edges`` (with readable label formulas), ``ap``, :meth:`successors`,
:meth:`accepts_lasso`.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from tamp.errors import InputError

Letter = frozenset[str]
EMPTY: Letter = frozenset()


@dataclass(frozen=True)
class Edge:
    """One automaton edge ``src --label--> dst`` (``cond`` is Spot's BDD)."""

    src: int
    dst: int
    label: str
    cond: Any


class Automaton:
    """State-based Büchi automaton of an LTL task over propositions ``props``.

    ``props`` fixes the alphabet: a proposition of the task that the formula does not mention
    is still a letter (moving that object leaves the automaton where the formula says).
    """

    def __init__(self, formula: str, props: Sequence[str], *, file: str | None = None):
        import spot  # heavy import kept local (CLI start-up stays fast)

        self.formula = formula
        self.props: tuple[str, ...] = tuple(props)
        try:
            f = spot.formula(formula)
        except SyntaxError as exc:
            first = str(exc).strip().splitlines()
            raise InputError(
                f"formula does not parse: {first[-1] if first else exc}", file=file, field="formula"
            ) from None
        unknown = sorted(str(a) for a in spot.atomic_prop_collect(f) if str(a) not in self.props)
        if unknown:
            raise InputError(
                f"unknown proposition(s) {unknown} (declared: {list(self.props)})",
                file=file,
                field="formula",
            )
        self.spot_formula = f
        aut = _translate(formula, {str(a) for a in spot.atomic_prop_collect(f)})
        for p in self.props:  # every task proposition is part of the alphabet
            aut.register_ap(p)
        self.spot_aut = aut
        self._dict = aut.get_dict()
        self.ap: tuple[str, ...] = tuple(str(a) for a in aut.ap())
        self.num_states: int = aut.num_states()
        self.initial: int = aut.get_init_state_number()
        self.accepting: frozenset[int] = frozenset(
            s for s in range(self.num_states) if aut.state_is_accepting(s)
        )
        self.edges: tuple[Edge, ...] = tuple(
            Edge(e.src, e.dst, spot.bdd_format_formula(self._dict, e.cond), e.cond)
            for s in range(self.num_states)
            for e in aut.out(s)
        )
        #: executable letters, ∅ first then singletons in declaration order
        self.letters: tuple[Letter, ...] = (EMPTY,) + tuple(frozenset({p}) for p in self.props)
        self._succ: list[dict[Letter, tuple[int, ...]]] = [{} for _ in range(self.num_states)]
        import buddy

        for letter in self.letters:
            valuation = self._valuation_bdd(letter)  # a full minterm: meets cond iff implies it
            for edge in self.edges:
                if (valuation & edge.cond) != buddy.bddfalse:
                    cur = self._succ[edge.src].get(letter, ())
                    if edge.dst not in cur:
                        self._succ[edge.src][letter] = tuple(sorted(cur + (edge.dst,)))
        self.live_accepting = self._live_accepting()

    # ------------------------------------------------------------------ letters
    def _valuation_bdd(self, letter: Iterable[str]) -> Any:
        """BDD of the full valuation: the letter's propositions true, all others false."""
        import buddy
        import spot

        true_set = set(letter)
        v = buddy.bddtrue
        for p in self.ap:
            var = buddy.bdd_ithvar(self._dict.varnum(spot.formula.ap(p)))
            v = v & (var if p in true_set else buddy.bdd_not(var))
        return v

    def successors(self, q: int, letter: Letter) -> tuple[int, ...]:
        """``δ(q, σ)`` for an executable letter (sorted; empty when the letter is blocked)."""
        return self._succ[q].get(letter, ())

    def _live_accepting(self) -> frozenset[int]:
        """Accepting states on a cycle of executable letters (a lasso can close there)."""
        live = set()
        for f in self.accepting:
            seen, stack = set(), [f]
            while stack:
                q = stack.pop()
                for letter in self.letters:
                    for n in self.successors(q, letter):
                        if n == f:
                            live.add(f)
                            stack.clear()
                            break
                        if n not in seen:
                            seen.add(n)
                            stack.append(n)
                    if f in live:
                        break
        return frozenset(live)

    # ------------------------------------------------------------------ checks
    def word(self, prefix: Sequence[Letter], cycle: Sequence[Letter]) -> str:
        """Spot's ω-word syntax for ``prefix · cycle^ω`` (full valuations over ``ap``)."""

        def lit(letter: Letter) -> str:
            return " & ".join(p if p in letter else f"!{p}" for p in self.ap) or "1"

        pre = "; ".join(lit(x) for x in prefix)
        cyc = "; ".join(lit(x) for x in cycle)
        return f"{pre}; cycle{{{cyc}}}" if pre else f"cycle{{{cyc}}}"

    def accepts_lasso(self, prefix: Sequence[Letter], cycle: Sequence[Letter]) -> bool:
        """True when the ω-word ``prefix · cycle^ω`` satisfies the task (Spot's own check)."""
        import spot

        if not cycle:
            raise ValueError("a lasso needs a non-empty cycle")
        w = spot.parse_word(self.word(prefix, cycle), self._dict)
        return bool(self.spot_aut.intersects(w.as_automaton()))

    # ------------------------------------------------------------------ views
    def to_networkx(self) -> Any:
        """``networkx.MultiDiGraph``: node attrs ``accepting``/``initial``; edge ``label``."""
        import networkx as nx

        g = nx.MultiDiGraph(formula=self.formula)
        for s in range(self.num_states):
            g.add_node(s, accepting=s in self.accepting, initial=s == self.initial)
        for e in self.edges:
            g.add_edge(e.src, e.dst, label=e.label, cond=e.cond)
        return g

    def to_dot(self) -> str:
        """Graphviz DOT text (accepting states double circles, initial state marked)."""
        lines = [
            "digraph automaton {",
            "  rankdir=LR;",
            f'  label="{_esc(self.formula)}"; labelloc=t;',
            '  init [shape=point, label=""];',
        ]
        for s in range(self.num_states):
            shape = "doublecircle" if s in self.accepting else "circle"
            lines.append(f'  q{s} [shape={shape}, label="q{s}"];')
        lines.append(f"  init -> q{self.initial};")
        for e in self.edges:
            lines.append(f'  q{e.src} -> q{e.dst} [label="{_esc(e.label)}"];')
        lines.append("}")
        return "\n".join(lines) + "\n"

    def summary(self) -> dict[str, Any]:
        """JSON-ready description: states, initial, accepting, edges with readable labels."""
        return {
            "formula": self.formula,
            "ap": list(self.ap),
            "states": self.num_states,
            "initial": self.initial,
            "accepting": sorted(self.accepting),
            "edges": [{"src": e.src, "dst": e.dst, "label": e.label} for e in self.edges],
        }


_FRESH = itertools.count()
_IDENT = re.compile(r"\b[a-z_][a-z0-9_]*\b")


def _translate(text: str, aps: set[str]) -> Any:
    """Spot translation that does not depend on what this process translated before.

    Spot orders the operands of ``&`` by the creation order of their subformulas (atomic
    propositions are interned process-wide), and that order decides in which order the
    degeneralized automaton serves the conjuncts of ``GF p1 & GF p2 & …``. Translating a copy
    whose propositions are brand-new names, created in order of first appearance in the text,
    and a fresh BDD dictionary makes the automaton a function of the formula text only; the
    names are then relabelled back.
    """
    import spot

    tag = next(_FRESH)
    order: list[str] = []
    for m in _IDENT.finditer(text):
        if m.group(0) in aps and m.group(0) not in order:
            order.append(m.group(0))
    fresh = {name: f"lotsap{tag}x{i}" for i, name in enumerate(order)}
    renamed = _IDENT.sub(lambda m: fresh.get(m.group(0), m.group(0)), text)
    for name in order:  # create the fresh atoms in text order
        spot.formula.ap(fresh[name])
    aut = spot.translate(
        spot.formula(renamed), "Buchi", "SBAcc", "small", "high", dict=spot.make_bdd_dict()
    )
    back = spot.relabeling_map()
    for name, new in fresh.items():
        back[spot.formula.ap(new)] = spot.formula.ap(name)
    spot.relabel_here(aut, back)
    return aut


def _esc(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"')
