"""Run a LOTS task against the symbolic world and summarise it (what ``tamp lots`` prints)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from tamp.errors import InfeasibleError
from tamp.lots.automaton import Letter
from tamp.lots.controller import ActionRecord, LotsController
from tamp.lots.task import Event, Task
from tamp.lots.world import SymbolicLotsWorld


@dataclass
class Report:
    """A finished run: controller (automaton, table, tree), world, actions, verdict."""

    task: Task
    controller: LotsController
    world: SymbolicLotsWorld
    actions: list[ActionRecord]
    satisfied: bool
    reason: str = ""
    tables: list[tuple[str, list[dict]]] = field(default_factory=list)

    @property
    def replans(self) -> int:
        return self.controller.replans

    def to_json(self) -> dict[str, Any]:
        c, lots = self.controller, self.controller.lots
        counts = self.world.counts()
        return {
            "task": self.task.name,
            "formula": self.task.formula,
            "automaton": c.aut.summary(),
            "w_b_states": lots.num_wb_states(),
            "final_w_b": lots.named(lots.final),
            "plan": {
                "prefix": [_letter(x) for x in c.initial_plan.prefix],
                "cycle": [_letter(x) for x in c.initial_plan.cycle],
            },
            "table": c.table.rows(),
            "actions": [a.to_json() for a in self.actions],
            "interference": [
                {"after": n, "phase": phase, "event": e.describe()}
                for n, phase, e in self.world.log
            ],
            "replans": c.replans,
            "final": counts,
            "satisfied": self.satisfied,
            "verdict": "satisfied" if self.satisfied else "infeasible",
            "reason": self.reason,
        }


def _letter(letter: Letter) -> list[str]:
    return sorted(letter)


def run_task(
    task: Task,
    events: list[Event] | tuple[Event, ...] = (),
    *,
    mode: str = "bfs",
    seed: int = 0,
    max_waits: int = 3,
    max_actions: int | None = None,
    policy: Any = None,
    check: Callable[[LotsController], Any] | None = None,
) -> Report:
    """Run Alg. 1 to the end. Infeasibility is reported (``satisfied`` False, ``reason``).

    ``check`` is called with the controller after every table it builds (the initial one and
    each replan), before the robot acts on it: the front ends pass `verification.gate`, which
    raises when the planned run or a table entry does not lead to acceptance (the
    verification gate of the architecture). What ``check`` raises propagates, even an
    `InfeasibleError` such as `VerificationError`: a rejected table is not an infeasible task.
    """
    rejected: list[BaseException] = []

    def guarded(c: LotsController) -> None:
        try:
            check(c)
        except BaseException as exc:
            rejected.append(exc)
            raise

    controller = LotsController(
        task,
        mode=mode,
        seed=seed,
        max_waits=max_waits,
        check=guarded if check is not None else None,
    )
    world = SymbolicLotsWorld(task, events, policy=policy)
    limit = max_actions if max_actions is not None else controller.default_limit(len(events) + 4)
    actions: list[ActionRecord] = []
    try:
        outcome = controller.run(world, max_actions=limit, record_into=actions)
    except InfeasibleError as exc:
        if rejected:
            raise
        return Report(task, controller, world, actions, False, str(exc), controller.tables)
    truth = controller.lots.vector(world.observe("B"))  # ground truth, not the belief
    ok = outcome.satisfied and truth == controller.lots.final
    return Report(task, controller, world, actions, ok, "", controller.tables)
