"""Run a LOTS task on the symbolic world and summarise it (what ``tamp lots`` prints).

The controller ticks against the one `tamp.world.SymbolicWorld` holding the workcell of
`tamp.lots.cell` (skills take ``skill_ticks`` ticks); before each tick the world's clock
advances and the scripted person (`tamp.lots.person`) does what is due.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from tamp.lots.automaton import Letter
from tamp.lots.cell import initial_state, side_counts
from tamp.lots.controller import ActionRecord, LotsController
from tamp.lots.person import Policy, ScriptedPerson
from tamp.lots.task import Event, Task
from tamp.world.interface import Status
from tamp.world.symbolic import SymbolicWorld


@dataclass
class Report:
    """A finished run: controller (automaton, table, tree), world, person, verdict."""

    task: Task
    controller: LotsController
    world: SymbolicWorld
    person: ScriptedPerson
    actions: list[ActionRecord]
    satisfied: bool
    reason: str = ""
    tables: list[tuple[str, list[dict]]] = field(default_factory=list)
    #: the automaton's verdict on the run's word (`judge_run`): accepted, and its JSON
    word_accepted: bool = False
    word_verdict: dict[str, Any] = field(default_factory=dict)

    @property
    def unfired_events(self) -> list[Event]:
        """Scripted events the run ended before (timed after more actions than it took)."""
        return self.person.unfired()

    @property
    def replans(self) -> int:
        return self.controller.replans

    def counts(self) -> dict[str, dict[str, int]]:
        """Ground truth at the end: counts per class in W^A, W^B and the waste basket."""
        return side_counts(self.world.state)

    def to_json(self) -> dict[str, Any]:
        c, lots = self.controller, self.controller.lots
        return {
            "task": self.task.name,
            "formula": self.task.formula,
            "automaton": c.aut.summary(),
            "w_b_states": lots.num_wb_states(),
            "final_w_b": lots.named(c.plan.end[1]),  # the plan in use (follows a replan)
            "returns": self.task.returns,
            "plan": {
                "prefix": [_letter(x) for x in c.initial_plan.prefix],
                "cycle": [_letter(x) for x in c.initial_plan.cycle],
            },
            "table": c.table.rows(),
            "actions": [a.to_json() for a in self.actions],
            "interference": [
                {"after": n, "phase": phase, "event": e.describe()}
                for n, phase, e in self.person.log
            ],
            "unfired_events": [e.unfired_json() for e in self.unfired_events],
            "replans": c.replans,
            "final": self.counts(),
            "word": run_word_json(c),
            "word_accepted": self.word_accepted,
            "word_verdict": self.word_verdict,
            "satisfied": self.satisfied,
            "verdict": "satisfied" if self.satisfied else "infeasible",
            "reason": self.reason,
        }


def _letter(letter: Letter) -> list[str]:
    return sorted(letter)


def run_word_json(c: LotsController) -> dict[str, Any]:
    """The run's word: what happened (in order), one word of it and the round's cycle."""
    letters, _ = c.word.witness(list(c.plan.cycle))
    return {
        "events": c.word.to_json(),
        "trace": [_letter(x) for x in letters],
        "cycle": [_letter(x) for x in c.plan.cycle],
    }


def judge_run(c: LotsController) -> tuple[bool, dict[str, Any]]:
    """The automaton's verdict on the run's word, without the verification module (a front
    end passes ``tamp.verification.lots.judge_word`` instead, which also checks the formula)."""
    ok = c.word.accepting(list(c.plan.cycle)) is not None
    return ok, {"holds": ok, "subject": "LOTS run's word"}


def lots_world(task: Task, *, skill_ticks: int | Mapping[str, int] = 1) -> SymbolicWorld:
    """The symbolic workcell of ``task`` with its initial counts in W^A and W^B."""
    state = initial_state({"A": task.initial_a, "B": task.initial_b})
    return SymbolicWorld(state, skill_ticks=skill_ticks)


def run_task(
    task: Task,
    events: Sequence[Event] = (),
    *,
    mode: str = "bfs",
    seed: int = 0,
    max_waits: int = 3,
    max_actions: int | None = None,
    policy: Policy | None = None,
    check: Callable[[LotsController], Any] | None = None,
    skill_ticks: int | Mapping[str, int] = 1,
    judge: Callable[[LotsController], tuple[bool, dict[str, Any]]] | None = None,
) -> Report:
    """Run Alg. 1 to the end. Infeasibility is reported (``satisfied`` False, ``reason``).

    ``check`` is called with the controller after every table it builds (the initial one and
    each replan), before the robot acts on it: the front ends pass `tamp.verification.gate`, which
    raises when the planned run or a table entry does not lead to acceptance (the
    verification gate of the architecture). What ``check`` raises propagates, even an
    `InfeasibleError` such as `VerificationError`: a rejected table is not an infeasible task
    (the controller itself reports infeasibility by stopping with FAILURE, never by raising).

    The run is satisfied when the controller completed its round, W^B holds the end of a
    round (ground truth), and the run's word is accepted: ``judge`` (default `judge_run`)
    gives the verdict on it; the front ends pass `tamp.verification.lots.judge_verdict`.
    """
    controller = LotsController(task, mode=mode, seed=seed, max_waits=max_waits, check=check)
    controller.max_actions = (
        max_actions if max_actions is not None else controller.default_limit(len(events) + 4)
    )
    world = lots_world(task, skill_ticks=skill_ticks)
    person = ScriptedPerson(events, policy=policy)

    def step() -> None:
        world.step()
        person.act(world)

    status = controller.run(world, step=step)
    truth = controller.lots.vector(side_counts(world.state)["B"])  # ground truth, not belief
    word_ok, word_json = (judge or judge_run)(controller)
    ok = status is Status.SUCCESS and controller.lots.is_goal(truth) and word_ok
    reason = "" if status is Status.SUCCESS else controller.reason
    if status is Status.SUCCESS and not word_ok:
        reason = (
            "the round looked complete but the run's word is not accepted by the task "
            "automaton (what happened does not satisfy the formula)"
        )
    return Report(
        task,
        controller,
        world,
        person,
        controller.actions,
        ok,
        reason,
        controller.tables,
        word_ok,
        word_json,
    )
