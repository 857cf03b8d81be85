"""Run a grown behavior tree in the symbolic world: ``execute_plan`` and its report.

This is what ``tamp plan DEMO.yaml --execute`` does after the RG layer chose the goal
order: build `PaBtExecutor` from C_goal, a `SymbolicWorld` from the demonstration's
initial state (plus the scripted events, `Appear`, and failures, `Fail`), tick until the
root succeeds or the executor stops, and report the executed actions, the growth statistics
and the final world.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from tamp.bt.executor import PaBtExecutor
from tamp.world.actions import Action, Domain
from tamp.world.events import Appear, Fail
from tamp.world.interface import Status
from tamp.world.outcomes import ScriptedOutcomes
from tamp.world.predicates import DEFAULT_REACH, Predicate
from tamp.world.state import WorldState
from tamp.world.symbolic import SymbolicWorld


@dataclass
class ExecutionReport:
    """Outcome of one symbolic execution (``to_json`` is what ``--json`` prints)."""

    status: Status
    reason: str
    executed: list[Action]
    c_goal: list[Predicate]
    goals_reached: int
    final: WorldState
    ticks: int
    tree_size: int
    stats: dict[str, Any]
    growth: list[dict]
    world_events: list[dict]
    attempts: list[dict]
    executor: PaBtExecutor | None = field(default=None, repr=False)
    world: SymbolicWorld | None = field(default=None, repr=False)

    @property
    def reached(self) -> bool:
        return self.status is Status.SUCCESS

    def to_json(self) -> dict:
        return {
            "status": self.status.value,
            "reached": self.reached,
            "reason": self.reason,
            "executed": [{"action": a.name, "args": list(a.args)} for a in self.executed],
            "c_goal": [str(c) for c in self.c_goal],
            "goals_reached": self.goals_reached,
            "expansions": self.stats["expansions"],
            "recoveries": self.stats["recoveries"],
            "conflicts": self.stats["conflicts"],
            "conflict_moves": self.stats["conflict_moves"],
            "retries": self.stats["retries"],
            "ticks": self.ticks,
            "tree_size": self.tree_size,
            "free_areas_found": self.stats["free_areas_found"],
            "final_world": self.final.summary(),
            "growth": self.growth,
            "world_events": self.world_events,
            "attempts": self.attempts,
        }

    def text(self) -> str:
        """Human-readable summary (what the CLI prints without --json)."""
        lines = [f"execution: {self.status.value} ({self.reason})"]
        for k, a in enumerate(self.executed, 1):
            lines.append(f"  {k:2d}. {a}")
        s = self.stats
        lines.append(
            f"expansions {s['expansions']}, recoveries {s['recoveries']}, conflicts "
            f"{s['conflicts']} ({s['conflict_moves']} moves), retries {s['retries']}, "
            f"ticks {self.ticks}, tree size {self.tree_size}"
        )
        notes = [
            (e["clock"], f"  [tick {e['clock']}] {e['kind']}: {e['what']}")
            for e in self.world_events
            if e["kind"] in ("appear", "move")
        ] + [
            (e["tick"], f"  [tick {e['tick']}] {e['kind']} {e['condition']}: {e['why']}")
            for e in self.growth
            if e["kind"] in ("recovery", "conflict", "retry", "stop")
        ]
        lines += [text for _, text in sorted(notes, key=lambda n: n[0])]
        summary = self.final.summary()
        lines.append(f"final world: held {summary['held']}, robot {summary['robot'][:2]}")
        for uid, pos in summary["objects"].items():
            lines.append(f"  {uid}: {pos}")
        return "\n".join(lines)


def execute(
    state: WorldState,
    c_goal: Sequence[Predicate],
    *,
    free_areas: Iterable[str] = (),
    events: Iterable[Appear] = (),
    failures: Iterable[Fail] = (),
    skill_ticks: int | Mapping[str, int] = 1,
    domain: Domain | None = None,
    max_ticks: int = 5000,
    **executor_options: Any,
) -> ExecutionReport:
    """Tick a fresh executor for ``c_goal`` against a `SymbolicWorld` starting at ``state``."""
    world = SymbolicWorld(
        state,
        skill_ticks=skill_ticks,
        outcomes=ScriptedOutcomes(failures),
        events=events,
        reach=domain.reach if domain is not None else DEFAULT_REACH,
    )
    ex = PaBtExecutor(c_goal, domain, free_areas=free_areas, **executor_options)
    status = ex.run(world, max_ticks=max_ticks, step=world.step)
    stats = ex.stats
    return ExecutionReport(
        status=status,
        reason=ex.reason,
        executed=ex.executed,
        c_goal=list(c_goal),
        goals_reached=ex.goals_done(),
        final=world.observe(),
        ticks=stats.ticks,
        tree_size=ex.size(),
        stats={
            "expansions": stats.expansions,
            "recoveries": stats.recoveries,
            "conflicts": stats.conflicts,
            "conflict_moves": stats.conflict_moves,
            "retries": stats.retries,
            "implicit_preemptions": stats.implicit_preemptions,
            "free_areas_found": list(stats.free_areas_found),
        },
        growth=[e.to_json() for e in ex.log],
        world_events=[e.to_json() for e in world.history],
        attempts=[r.to_json() for r in ex.attempts],
        executor=ex,
        world=world,
    )


def execute_plan(
    demo: Any,
    c_goal: Sequence[Predicate],
    *,
    events: Iterable[Appear] = (),
    failures: Iterable[Fail] = (),
    skill_ticks: int | Mapping[str, int] = 1,
    domain: Domain | None = None,
    max_ticks: int = 5000,
    **executor_options: Any,
) -> ExecutionReport:
    """Execute the RG layer's C_goal for a `Demonstration` (its initial world and free areas)."""
    return execute(
        demo.initial_world(),
        c_goal,
        free_areas=[a.name for a in demo.free_areas],
        events=events,
        failures=failures,
        skill_ticks=skill_ticks,
        domain=domain,
        max_ticks=max_ticks,
        **executor_options,
    )
