"""LOTS plans (Zhou et al. §IV, Alg. 1-3): every table T the controller builds, where it starts.

A table is built from a planned run that starts at a pair ``(q, s^B)``: ``(q_0, s^B_0)`` for
the initial table, the automaton state and observed W^B counts of a replan otherwise
(`tamp.lots.controller.Build`). Two checks per build, both on infinite words:

1. The planned run ``prefix · cycle^ω`` (letters = the propositions delivered at each step,
   ∅ for idle/removal steps) is accepted by the task automaton *from q* (Spot product
   emptiness on a copy started in q). It is cross-checked against the formula itself by our
   own translation (`check_trace`), on ``history · prefix · cycle^ω`` where ``history`` is
   a word leading the automaton from ``q_0`` to ``q``: the verdict then does not rely on the
   planner's automaton. A disagreement is reported as a violation.
2. Every entry of T leads, when followed, to acceptance: from W^B state ``b`` the robot
   follows T (each action changes W^B, the next state's entry is looked up) until ``done``;
   then the plan's accepting cycle repeats. The letters produced, read from the automaton
   state ``q`` the entry is paired with, must be accepted (product emptiness on a copy
   started in ``q``). Following T into a W^B state that T does not cover, or around a loop
   that never reaches ``done``, is a violation too.

Idle steps of a plan (∅ letters where nothing moves) are not entries of T, so a followed
entry produces only the letters of actions, exactly like ``tamp.lots.planner.follow_table``.

A finished run is judged on what happened (`judge_word`): the run's word — the robot's
deliveries and the W^B states its camera saw, in order (`tamp.lots.word.RunWord`) — followed
by the accepting cycle of the round it completed, must be accepted by the task automaton;
the witness word is cross-checked against the formula by our own translation.

Entry points: `judge_word` (a finished run), `check_build` (one table, typed),
`check_controller` (the table in use), `check_run` / `check_table` (the two checks),
`check_task_file` (``tamp-verify lots``: the controller run over the symbolic world with an
interference script, every table checked).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from tamp.ltl.automata import accepts_lasso, started_at
from tamp.verification.traces import check_trace, explain_on
from tamp.verification.verdict import Counterexample, Report, Verdict
from tamp.verification.words import Word

if TYPE_CHECKING:
    from tamp.lots.automaton import Automaton, Letter
    from tamp.lots.controller import Build, LotsController
    from tamp.lots.lots import Lots
    from tamp.lots.planner import Table
    from tamp.lots.task import Event


def check_run(
    aut: Automaton,
    prefix: Sequence[Letter],
    cycle: Sequence[Letter],
    *,
    start: int | None = None,
    history: Sequence[Letter] = (),
    subject: str = "LOTS planned run",
) -> Verdict:
    """The planned lasso read from automaton state ``start`` (default ``q_0``).

    ``history`` leads ``aut`` from ``q_0`` to ``start``; the formula is checked on
    ``history · prefix · cycle^ω`` by our own translation (see module docstring).
    """
    q = aut.initial if start is None else start
    accepted, explored = accepts_lasso(aut.spot_aut, prefix, cycle, start=q)
    reached = _read(aut, history)
    ours = check_trace(aut.spot_formula, Word.lasso([*history, *prefix], cycle), subject=subject)
    ours.states_explored += explored
    if q in reached and accepted == ours.holds:
        return ours
    word = Word.lasso(prefix, cycle)
    if not accepted:
        ce = explain_on(started_at(aut.spot_aut, q), word, finite=False)
    elif not ours.holds:
        # check_trace is exact: a verdict that does not hold carries its counterexample
        assert ours.counterexample is not None
        ce = ours.counterexample
    else:
        ce = Counterexample(word, "", accepting_word=None)
    if q not in reached:
        ce.reason = (
            f"the run starts in automaton state q{q}, which the recorded history does not "
            f"reach (it reaches {sorted(reached)}): " + ce.reason
        )
    else:
        ce.reason = (
            f"the task automaton {'rejects' if not accepted else 'accepts'} the run from q{q} "
            f"but the formula {'holds' if ours.holds else 'does not hold'} on it: " + ce.reason
        )
    ce.aps = list(aut.ap)
    return Verdict(subject, str(aut.spot_formula), "infinite", False, ours.states_explored, ce)


def _read(aut: Automaton, letters: Sequence[Letter]) -> set[int]:
    """Automaton states reached from ``q_0`` by executable ``letters``."""
    cur = {aut.initial}
    for x in letters:
        cur = {n for q in cur for n in aut.successors(q, frozenset(x))}
    return cur


def follow(table: Table, lots: Lots, b) -> tuple[list, list[str], str | None]:
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
            # the planner gives every move entry its proposition and class (planner.Entry)
            assert e.prop is not None and e.cls is not None
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
            assert e.cls is not None  # a remove entry names the class it takes out
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


def check_table(
    aut: Automaton,
    table: Table,
    lots: Lots,
    cycle: Sequence[Letter],
    *,
    subject: str = "LOTS table T",
) -> Verdict:
    """Every entry of ``table`` leads to acceptance from its own automaton state."""
    aps = list(aut.ap)
    explored = 0
    for b, e in sorted(table.entries.items()):
        letters, steps, problem = follow(table, lots, b)
        if problem is None:
            ok, n = accepts_lasso(aut.spot_aut, letters, cycle, start=e.q)
            explored += n
            if ok:
                continue
            word = Word.lasso(letters, cycle)
            ce = explain_on(started_at(aut.spot_aut, e.q), word, finite=False)
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


def check_build(aut: Automaton, lots: Lots, build: Build) -> Report:
    """One table the controller built: its planned run from where it starts, and every entry.

    The initial build keeps the subjects ``LOTS planned run`` / ``LOTS table T``; a replan's
    subjects name it (``… (replan 1 at W^B …)``).
    """
    tag = "" if build.label == "initial" else f" ({build.label})"
    q, _ = build.start
    plan = build.plan
    return Report(
        [
            check_run(
                aut,
                plan.prefix,
                plan.cycle,
                start=q,
                history=build.history,
                subject="LOTS planned run" + tag,
            ),
            check_table(aut, build.table, lots, plan.cycle, subject="LOTS table T" + tag),
        ]
    )


def judge_word(controller: LotsController) -> Verdict:
    """The run's word (what happened) followed by its round's cycle: accepted by the task?

    `RunWord` reads every attribution of the objects a person brought into W^B; the witness
    it gives (the accepted one, if any) is checked again from ``q_0`` by Spot and against the
    formula itself by `check_trace`: all three must agree for the verdict to hold.
    """
    aut, word = controller.aut, controller.word
    cycle = list(controller.plan.cycle)
    letters, _ = word.witness(cycle)
    q = word.accepting(cycle)
    subject = "LOTS run's word"
    lasso = Word.lasso(letters, cycle)
    spot_ok, explored = accepts_lasso(aut.spot_aut, letters, cycle)
    ours = check_trace(aut.spot_formula, lasso, subject=subject)
    ours.states_explored += explored
    if q is not None and spot_ok and ours.holds:
        return ours
    if ours.holds:  # the formula holds but the automaton disagrees: say so, never pass it
        ce = Counterexample(lasso, "", accepting_word=None)
        ce.reason = "the task automaton rejects the run's word but the formula holds on it"
        ce.aps = list(aut.ap)
        return Verdict(subject, str(aut.spot_formula), "infinite", False, explored, ce)
    ce = ours.counterexample
    assert ce is not None  # check_trace is exact: a verdict that does not hold has one
    ce.reason = (
        "what happened (robot deliveries, then the round's cycle forever) does not satisfy "
        "the task: " + ce.reason
    )
    ce.steps = [f"{who}: {what}" for who, what in word.events]
    return ours


def judge_verdict(controller: LotsController) -> tuple[bool, dict]:
    """`judge_word` as ``tamp.lots.run.run_task``'s ``judge``: (holds, the verdict's JSON)."""
    v = judge_word(controller)
    # the task's own text, and no count of explored states: Spot's printing of a commutative
    # formula and its automata's sizes depend on what else the process has built
    data = {k: x for k, x in v.to_json().items() if k != "states_explored"}
    return v.holds, data | {"formula": controller.task.formula}


def check_controller(controller: LotsController) -> Report:
    """The controller's table in use (`LotsController.build`), from where it was built."""
    return check_build(controller.aut, controller.lots, controller.build)


def check_task_file(path, interference=None) -> Report:
    """``tamp-verify lots TASK.yaml [--interference EVENTS.yaml]``.

    Runs the controller over the symbolic world with the interference script and checks
    every table it builds, each before it is used; the run stops at the first that fails.
    """
    from tamp.lots.task import load_events, load_task

    task = load_task(path)
    events = load_events(interference, task) if interference is not None else []
    return check_run_of(task, events)


@dataclass
class LotsReport(Report):
    """The verdicts of a run's tables, and the scripted events the run ended before.

    An event that never happened did not disturb the run: the verdicts hold for what ran,
    and the report says which interference was not exercised (text and JSON).
    """

    unfired_events: list[Event] = field(default_factory=list)

    def to_json(self) -> dict:
        data = super().to_json()
        data["unfired_events"] = [e.unfired_json() for e in self.unfired_events]
        return data

    def text(self) -> str:
        lines = [super().text()] + [e.never_happened() for e in self.unfired_events]
        return "\n".join(lines)


def check_run_of(task, events: Sequence[Event] = ()) -> LotsReport:
    """Every table the controller builds while running ``task`` against ``events``."""
    from tamp.lots.run import run_task

    verdicts: list[Verdict] = []

    class _Stop(Exception):
        pass

    def check(controller: LotsController) -> None:
        report = check_controller(controller)
        verdicts.extend(report.verdicts)
        if not report.holds:
            raise _Stop

    unfired: list[Event] = []  # a run stopped at a failing table: the violation is the news
    try:
        unfired = run_task(task, events, check=check).unfired_events
    except _Stop:
        pass
    return LotsReport(verdicts, unfired_events=unfired)


__all__ = [
    "LotsReport",
    "check_build",
    "check_controller",
    "check_run",
    "check_run_of",
    "check_table",
    "check_task_file",
    "follow",
    "judge_verdict",
    "judge_word",
]
