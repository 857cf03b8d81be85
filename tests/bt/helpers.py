"""Helpers for the behavior-tree tests: a scripted world for node semantics, hand-built worlds."""

from __future__ import annotations

from dataclasses import dataclass

from tamp.world import Area, ObjectState, Point, Pose, WorldState
from tamp.world.actions import Action, ActionTemplate
from tamp.world.interface import Status
from tamp.world.predicates import Predicate


@dataclass(frozen=True)
class Flag(Predicate):
    """A predicate read from a dict state (node-semantics tests only)."""

    flag: str
    name = "Flag"

    def holds(self, state) -> bool:
        return bool(state[self.flag])


def act(name: str) -> Action:
    return Action(ActionTemplate(name, (), (), ()), (), (), ())


class ScriptWorld:
    """Records start/poll/cancel in order; skills return scripted statuses, else RUNNING."""

    def __init__(self, **flags: bool) -> None:
        self.flags = dict(flags)
        self.calls: list[tuple[str, str]] = []
        self.outcome: dict[str, Status] = {}
        self._handles: dict[int, str] = {}
        self._running: int | None = None
        self._next = 1

    def observe(self):
        return dict(self.flags)

    def start(self, action: Action) -> int:
        if self._running is not None:
            raise RuntimeError(f"start {action.name} while {self._handles[self._running]} runs")
        h = self._next
        self._next += 1
        self._handles[h] = action.name
        self._running = h
        self.calls.append(("start", action.name))
        return h

    def poll(self, handle: int) -> Status:
        name = self._handles[handle]
        st = self.outcome.get(name, Status.RUNNING)
        if st is not Status.RUNNING and self._running == handle:
            self._running = None
        return st

    def cancel(self, handle: int) -> None:
        self.calls.append(("cancel", self._handles[handle]))
        if self._running == handle:
            self._running = None


class Ctx:
    """A minimal tick context (what PaBtExecutor provides) for hand-built trees."""

    def __init__(self, world: ScriptWorld) -> None:
        from tamp.bt.executor import PaBtExecutor

        self.ex = PaBtExecutor.__new__(PaBtExecutor)
        PaBtExecutor.__init__(self.ex, [Flag("unused")])
        self.world = world

    def tick(self, root) -> Status:
        ex = self.ex
        ex.tick_id += 1
        ex.state = self.world.observe()
        ex.world = self.world
        ex.cache.clear()
        try:
            return root.tick(ex)
        finally:
            ex.world = None
            ex.preempt.clear()

    def halt(self, root) -> None:
        self.ex.world = self.world
        root.halt(self.ex)
        self.ex.world = None


def case3_by_hand() -> tuple[WorldState, list[str]]:
    """Case 3 built directly (robot frame): the objects and goal areas of
    tamp/scenarios/case3.yaml, with free areas placed so that every move needs a MoveTo
    (free2 is 0.92 m from l_1, just out of reach)."""
    r = 0.15
    areas = {
        "L0": Area("L0", Point(1.6, -1.1), r),
        "L1": Area("L1", Point(2.2, 0.8), r),
        "free1": Area("free1", Point(0.8, 1.7), r),
        "free2": Area("free2", Point(2.4, 1.7), r),
    }
    objects = {
        "O0": ObjectState("O0", Pose.at(1.0, -0.5, 0.1)),
        "O1": ObjectState("O1", Pose.at(1.2, 0.5, 0.1)),
    }
    return WorldState(robot=Pose.at(0.0, 0.0), objects=objects, areas=areas), ["free1", "free2"]
