"""Model checking an explicit transition system: does *every* path satisfy an LTL formula?

The system (RG, explored BT executions, a LOTS table) becomes a Spot Kripke structure
(``spot.make_kripke_graph``): one state per system state, labelled with the full valuation
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

import buddy
import spot

from verification import ltl
from verification.traces import as_formula, check_trace, explain
from verification.verdict import Verdict
from verification.words import Word


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


def to_kripke(
    ts: TransitionSystem, aps: list[str], bdict, *, stutter_unexpanded: bool = True
) -> spot.kripke_graph:
    """The Kripke structure of ``ts`` over ``aps`` (dead ends get a self-loop; unexpanded
    ones only with ``stutter_unexpanded``)."""
    k = spot.make_kripke_graph(bdict)
    varnums = {}
    for name in aps:
        f = spot.formula.ap(name)
        k.register_ap(f)
        varnums[name] = bdict.varnum(f)
    cache: dict[frozenset[str], buddy.bdd] = {}
    for label in ts.labels:
        key = label & frozenset(aps)
        b = cache.get(key)
        if b is None:
            b = buddy.bddtrue
            for name, v in varnums.items():
                b = b & (buddy.bdd_ithvar(v) if name in key else buddy.bdd_nithvar(v))
            cache[key] = b
        k.new_state(b)
    for s, succ in enumerate(ts.succ):
        if not succ and (stutter_unexpanded or s not in ts.unexpanded):
            k.new_edge(s, s)
        for d in dict.fromkeys(succ):
            k.new_edge(s, d)
    k.set_init_state(ts.init)
    return k


def model_check(
    ts: TransitionSystem,
    formula: str | spot.formula,
    *,
    subject: str = "system",
    accepting_word: Word | None = None,
) -> Verdict:
    """Verdict "every path of ``ts`` satisfies ``formula``", with a counterexample run."""
    f = as_formula(formula)
    aps = ltl.ap_names(f)
    bdict = spot.make_bdd_dict()
    k = to_kripke(ts, aps, bdict)
    parts = ltl.conjuncts(f)
    # One product with the automaton of !f. Its translation uses Spot's low optimisation
    # level: the negation of a conjunction is a disjunction whose automaton is small, but
    # the 'high' simplifications take seconds to minutes on it (12 F-conjuncts: ~12 s).
    neg = spot.translate(spot.formula.Not(f), "Buchi", "SBAcc", "any", "low", dict=bdict)
    states = ts.num_states
    lasso = _lasso(k, neg)
    if lasso is not None and len(lasso[1]) == 1 and lasso[1][0] in ts.unexpanded:
        prefix, cycle = lasso
        word = Word.lasso([ts.labels[s] for s in prefix + cycle], [ts.labels[cycle[0]]])
        bad = explain(f, word, finite=False).position
        if bad is None or bad >= len(word.prefix):  # not a bad prefix: stutter at the bound
            k = to_kripke(ts, aps, bdict, stutter_unexpanded=False)
            lasso = _lasso(k, neg)
    if lasso is None:
        return Verdict(subject, str(f), "all paths", True, states)
    prefix, cycle = lasso
    word = Word.lasso([ts.labels[s] for s in prefix], [ts.labels[s] for s in cycle])
    violated = [c for c in parts if not check_trace(c, word).holds] if len(parts) > 1 else [f]
    whole = len(parts) <= ltl.MAX_CONJUNCTS_FOR_WHOLE
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


def _lasso(k: spot.kripke_graph, neg: spot.twa_graph) -> tuple[list[int], list[int]] | None:
    """A run of ``k`` accepted by ``neg`` as (prefix, cycle) state numbers, shortest form."""
    run = k.intersecting_run(neg)
    if run is None:
        return None
    prefix = [k.state_number(st.s) for st in run.prefix]
    cycle = [k.state_number(st.s) for st in run.cycle]
    while prefix and prefix[-1] == cycle[-1]:  # shortest equivalent lasso
        prefix.pop()
        cycle = cycle[-1:] + cycle[:-1]
    return prefix, cycle
