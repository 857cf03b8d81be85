"""LOTS plans (Zhou et al. §IV, Alg. 1-3): the planned run and every entry of the table T.

Two checks, both on infinite words (the task is an ω-regular LTL formula):

1. The planned run ``prefix · cycle^ω`` (`tamp.lots.planner.Plan`, letters = the
   propositions delivered at each step, ∅ for idle/removal steps) satisfies the task
   formula. The verdict is computed from the formula by our own translation, so it does not
   rely on the planner's automaton.
2. Every entry of T leads, when followed, to acceptance: from W^B state ``b`` the robot
   executes ``T[b]`` (a delivery changes ``b`` by one object of the proposition's class, a
   removal takes one out), looks the new state up (the run's next entry while W^B is where
   the run expects it, else ``T[b']`` — the controller's own rule, Alg. 1 line 12), and so
   on until ``done``; then the plan's accepting cycle repeats. The letters produced,
   read from the automaton state ``q`` the entry is paired with, must be accepted by the
   task automaton (Spot product emptiness on a copy of it started in ``q``). Following T
   into a W^B state that T does not cover, or around a loop that never reaches ``done``,
   is a violation too: the table does not lead the robot to acceptance by itself.

Idle steps of a plan (∅ letters where nothing moves) are not entries of T, so a followed
entry produces only the letters of actions, exactly like ``tamp.lots.planner.follow_table``.
"""

from __future__ import annotations

import spot

from verification import ltl
from verification.traces import check_trace, explain_on, word_automaton
from verification.verdict import Counterexample, Report, Verdict
from verification.words import Word


def check_run(aut, prefix, cycle, *, subject: str = "LOTS planned run") -> Verdict:
    """The planned lasso against the task automaton (``aut``: `tamp.lots.automaton.Automaton`).

    The verdict is Spot's product emptiness with the planner's own automaton; it is
    cross-checked against our translation of the formula (`check_trace`), which also gives
    the explanation (violated conjuncts, shortest bad prefix). A disagreement between the
    two automata is reported as a violation: the planner's automaton is then not the task.
    """
    word = Word.lasso(prefix, cycle)
    prod = spot.product(aut.spot_aut, word_automaton(word, aut.spot_aut))
    accepted = not prod.is_empty()
    ours = check_trace(aut.spot_formula, word, subject=subject)
    ours.states_explored += prod.num_states()
    if accepted == ours.holds:
        return ours
    ce = explain_on(aut.spot_aut, word, finite=False) if not accepted else ours.counterexample
    ce.reason = (
        f"the task automaton {'rejects' if not accepted else 'accepts'} the run but the "
        f"formula {'holds' if ours.holds else 'does not hold'} on it: " + ce.reason
    )
    ce.aps = list(aut.ap)
    return Verdict(subject, str(aut.spot_formula), "infinite", False, ours.states_explored, ce)


def _started_at(spot_aut: spot.twa_graph, q: int) -> spot.twa_graph:
    copy = spot.make_twa_graph(spot_aut, spot.twa_prop_set.all())
    copy.set_init_state(q)
    return copy


def follow(table, lots, b) -> tuple[list, list[str], str | None]:
    """Follow T from W^B state ``b``: (letters, step descriptions, problem or None)."""
    e = table.get(b)
    if e is None:
        return [], [], f"T has no entry for W^B {lots.format(b)}"
    letters: list[frozenset[str]] = []
    steps: list[str] = []
    seen: set[int] = set()
    while e.kind != "done":
        if e.index in seen:
            return letters, steps, f"following T loops at W^B {lots.format(e.b)} without done"
        seen.add(e.index)
        if e.kind == "move":
            nb = lots.deliver(e.b, frozenset({e.prop}))
            if nb is None:
                return (
                    letters,
                    steps,
                    (
                        f"T[{lots.format(e.b)}] = {e.prop} delivers more {lots.classes[e.cls]} "
                        "than the task needs"
                    ),
                )
        else:
            nb = lots.remove(e.b, e.cls)
            if nb is None:
                return letters, steps, f"T[{lots.format(e.b)}] removes an object W^B lacks"
        letters.append(e.letter)
        steps.append(f"W^B {lots.format(e.b)}: {e.label(lots)}")
        nxt = table.next_after(e, nb)
        if nxt is None:
            nxt = table.get(nb)
        if nxt is None:
            return letters, steps, f"T has no entry for W^B {lots.format(nb)} (reached by T)"
        e = nxt
    return letters, steps, None


def check_table(aut, table, lots, cycle, *, subject: str = "LOTS table T") -> Verdict:
    """Every entry of ``table`` leads to acceptance (see module docstring)."""
    aps = list(aut.ap)
    explored = 0
    for b, e in sorted(table.entries.items()):
        letters, steps, problem = follow(table, lots, b)
        start = _started_at(aut.spot_aut, e.q)
        if problem is None:
            word = Word.lasso(letters, cycle)
            prod = spot.product(start, word_automaton(word, start))
            explored += prod.num_states()
            if not prod.is_empty():
                continue
            ce = explain_on(start, word, finite=False)
            ce.reason = (
                f"following T from W^B {lots.format(b)} (automaton state q{e.q}) is not "
                "accepted: " + ce.reason
            )
            ce.steps = steps + [f"cycle {sorted(x) or '{}'}" for x in cycle]
        else:
            word = Word.lasso(letters, [frozenset()])
            ce = Counterexample(
                word,
                f"following T from W^B {lots.format(b)} (automaton state q{e.q}): {problem}",
                accepting_word=None,
            )
            ce.steps = steps + ["(stuck: T gives no action)"]
            explored += len(letters) + 1
        ce.aps = aps
        return Verdict(subject, str(aut.spot_formula), "infinite", False, explored, ce)
    name = f"{subject} ({len(table.entries)} entries)"
    return Verdict(name, str(aut.spot_formula), "infinite", True, explored)


def check_controller(controller) -> Report:
    """A `tamp.lots.controller.LotsController`: its current plan and its table T."""
    prefix, cycle = controller.plan_letters()
    return Report(
        [
            check_run(controller.aut, prefix, cycle),
            check_table(controller.aut, controller.table, controller.lots, cycle),
        ]
    )


def check_task_file(path) -> Report:
    """``tamp-verify lots TASK.yaml``: build the LOTS controller of a task file and check it."""
    from tamp.lots.controller import LotsController
    from tamp.lots.task import load_task

    return check_controller(LotsController(load_task(path)))


__all__ = ["check_controller", "check_run", "check_table", "check_task_file", "follow", "ltl"]
