"""Model checking an explicit transition system: does *every* path satisfy an LTL formula?

The system (RG, explored BT executions, a LOTS table) becomes a Kripke structure
(`tamp.ltl.kripke`): one state per system state, labelled with the full valuation
of the formula's propositions there. It satisfies ``f`` on all paths iff it has no run
accepted by the Büchi automaton of ``!f``; Spot's ``intersecting_run`` returns such a run
as a lasso of Kripke states, which is the counterexample.

Choices written down here:
- A state without successors (the system stops: all goals reached, the tree returned
  SUCCESS or FAILURE) repeats forever, the usual stutter extension of finite behaviour.
  States in ``unexpanded`` (a bounded exploration stopped before computing their
  successors) do not stop the system. A counterexample that only stutters at such a state
  is kept only when the path up to it is already a bad prefix (no continuation could
  satisfy the formula: a safety violation); otherwise it is an artefact of the bound (e.g.
  ``F goal`` "violated" because the exploration stopped) and the run is searched again
  with those states as dead ends, which leaves only real lassos.
- ``!f`` is translated with Spot's *low* optimisation level: the negation of a large
  conjunction is a disjunction with a small automaton, but the 'high' simplifications take
  seconds to minutes on it (``!(F g0 & … & F g11)``: 13 states in 15 ms at 'low', ~12 s at
  'high'). The counterexample names the conjuncts the returned run violates.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from tamp import ltl
from tamp.ltl.formula import Formula
from tamp.ltl.kripke import intersecting_lasso, kripke
from tamp.verification.traces import MAX_CONJUNCTS_FOR_WHOLE, as_formula, check_trace, explain
from tamp.verification.verdict import Verdict
from tamp.verification.words import Word


@dataclass
class TransitionSystem:
    """Explicit states with labels (true propositions), successor lists and descriptions."""

    labels: list[frozenset[str]] = field(default_factory=list)
    succ: list[list[int]] = field(default_factory=list)
    names: list[str] = field(default_factory=list)
    init: int = 0
    #: states whose successors were never computed (a bounded exploration's frontier)
    unexpanded: set[int] = field(default_factory=set)

    def add_state(self, label: frozenset[str], name: str) -> int:
        self.labels.append(frozenset(label))
        self.succ.append([])
        self.names.append(name)
        return len(self.labels) - 1

    def add_edge(self, src: int, dst: int) -> None:
        self.succ[src].append(dst)

    @property
    def num_states(self) -> int:
        return len(self.labels)

    @property
    def num_edges(self) -> int:
        return sum(len(s) for s in self.succ)


def to_kripke(ts: TransitionSystem, aps: list[str], aut, *, stutter_unexpanded: bool = True):
    """The Kripke structure of ``ts`` over ``aps`` in ``aut``'s BDD dictionary (dead ends
    get a self-loop; unexpanded ones only with ``stutter_unexpanded``)."""
    stutter = None if stutter_unexpanded else set(range(ts.num_states)) - ts.unexpanded
    return kripke(ts.labels, ts.succ, aps, aut, init=ts.init, stutter=stutter)


def model_check(
    ts: TransitionSystem,
    formula: str | Formula,
    *,
    subject: str = "system",
    accepting_word: Word | None = None,
) -> Verdict:
    """Verdict "every path of ``ts`` satisfies ``formula``", with a counterexample run."""
    f = as_formula(formula)
    aps = ltl.ap_names(f)
    parts = ltl.conjuncts(f)
    # One product with the automaton of !f. Its translation uses Spot's low optimisation
    # level: the negation of a conjunction is a disjunction whose automaton is small, but
    # the 'high' simplifications take seconds to minutes on it (12 F-conjuncts: ~12 s).
    neg = ltl.translate(ltl.negate(f), ltl.NEGATION)
    k = to_kripke(ts, aps, neg)
    states = ts.num_states
    lasso = intersecting_lasso(k, neg)
    if lasso is not None and len(lasso[1]) == 1 and lasso[1][0] in ts.unexpanded:
        prefix, cycle = lasso
        word = Word.lasso([ts.labels[s] for s in prefix + cycle], [ts.labels[cycle[0]]])
        bad = explain(f, word, finite=False).position
        if bad is None or bad >= len(word.prefix):  # not a bad prefix: stutter at the bound
            k = to_kripke(ts, aps, neg, stutter_unexpanded=False)
            lasso = intersecting_lasso(k, neg)
    if lasso is None:
        return Verdict(subject, str(f), "all paths", True, states)
    prefix, cycle = lasso
    word = Word.lasso([ts.labels[s] for s in prefix], [ts.labels[s] for s in cycle])
    violated = [c for c in parts if not check_trace(c, word).holds] if len(parts) > 1 else [f]
    whole = len(parts) <= MAX_CONJUNCTS_FOR_WHOLE
    ce = explain(f if whole else violated[0], word, finite=False)
    if not whole:
        ce.accepting_word = None
    if accepting_word is not None:
        ce.accepting_word = accepting_word
    ce.violated = [str(c) for c in violated] if len(parts) > 1 else []
    ce.steps = [ts.names[s] for s in prefix + cycle]
    ce.aps = aps
    ce.reason = f"a path of {subject} violates the formula: " + ce.reason
    return Verdict(subject, str(f), "all paths", False, states, ce)
