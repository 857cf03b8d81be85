"""The task automaton: an LTL formula as a state-based Büchi automaton (Zhou et al. Def. 2).

``B = (Q, Q_0, Σ, δ, F)``, translated by `tamp.ltl` (cached, guarded; fresh proposition
names so that the automaton depends on the formula text only, see `tamp.ltl.translate`).

The robot does one thing at a time, so only *executable* letters are read: the empty letter
(no delivery this step) and the singletons ``{p}``. :class:`Automaton` precomputes
``δ(q, σ)`` for those letters once, so the planners never touch a BDD in their inner loops.

This wrapper is also what ``tamp.verification`` consumes (stable API): ``spot_aut``, ``initial``,
``accepting``, ``edges`` (with readable label formulas), ``ap``, :meth:`successors`,
:meth:`accepts_lasso`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from tamp import ltl
from tamp.ltl import automata, letters
from tamp.ltl.formula import check_aps
from tamp.ltl.letters import EMPTY, Letter

__all__ = ["EMPTY", "Automaton", "Edge", "Letter"]


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
        self.formula = formula
        self.props: tuple[str, ...] = tuple(props)
        f = ltl.parse(formula, file=file)
        check_aps(f, self.props, file=file)
        self.spot_formula = f
        aut = automata.copy(ltl.translate(formula, ltl.Options(fresh=True), file=file))
        automata.register_aps(aut, self.props)  # every task proposition is in the alphabet
        self.spot_aut = aut
        self.ap: tuple[str, ...] = tuple(letters.aps(aut))
        self.num_states: int = aut.num_states()
        self.initial: int = aut.get_init_state_number()
        self.accepting: frozenset[int] = automata.accepting_states(aut)
        self.edges: tuple[Edge, ...] = tuple(
            Edge(src, dst, letters.label(aut, cond), cond) for src, dst, cond in automata.edges(aut)
        )
        #: executable letters, ∅ first then singletons in declaration order
        self.letters: tuple[Letter, ...] = (EMPTY,) + tuple(frozenset({p}) for p in self.props)
        self._succ: list[dict[Letter, tuple[int, ...]]] = [{} for _ in range(self.num_states)]
        for letter in self.letters:
            valuation = letters.letter_bdd(aut, letter)  # a full minterm: meets cond iff implies
            for edge in self.edges:
                if letters.meets(valuation, edge.cond):
                    cur = self._succ[edge.src].get(letter, ())
                    if edge.dst not in cur:
                        self._succ[edge.src][letter] = tuple(sorted(cur + (edge.dst,)))
        self.live_accepting = self._live_accepting()

    # ------------------------------------------------------------------ letters
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
    def accepts_lasso(
        self, prefix: Sequence[Letter], cycle: Sequence[Letter], *, start: int | None = None
    ) -> bool:
        """True when ``prefix · cycle^ω`` is accepted from ``start`` (default ``q_0``)."""
        return automata.accepts_lasso(self.spot_aut, prefix, cycle, start=start)[0]

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


def _esc(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"')
