"""Helpers for the behavior-tree tests: the SymbolicWorld set up for node semantics, hand-built
worlds."""

from __future__ import annotations

from dataclasses import dataclass

from tamp.world import Area, ObjectState, Point, Pose, WorldState
from tamp.world.actions import Action, ActionTemplate
from tamp.world.events import Fail, parse_call
from tamp.world.interface import Status
from tamp.world.outcomes import ScriptedOutcomes
from tamp.world.predicates import Predicate
from tamp.world.symbolic import SymbolicWorld


@dataclass(frozen=True)
class Flag(Predicate):
    """A flag for node-semantics tests: set while an object of that name exists."""

    flag: str
    name = "Flag"

    def holds(self, state: WorldState) -> bool:
        return self.flag in state.objects


def act(name: str) -> Action:
    return Action(ActionTemplate(name, (), (), ()), (), (), ())


def flag_state(**flags: bool) -> WorldState:
    """A state whose set flags are objects (see `Flag`)."""
    objects = {f: ObjectState(f, Pose.at(0.0, 0.0)) for f, on in flags.items() if on}
    return WorldState(robot=Pose.at(0.0, 0.0), objects=objects)


def flag_world(outcomes: dict[str, Status] | None = None, **flags: bool) -> SymbolicWorld:
    """The SymbolicWorld for node semantics: skills stay RUNNING (`Ctx` never steps the
    clock and a skill takes one tick), except those given a scripted FAILURE in
    ``outcomes``, which fail at their first poll, every time."""
    outcomes = outcomes or {}
    assert set(outcomes.values()) <= {Status.FAILURE}, "only scripted failures are needed"
    return SymbolicWorld(
        flag_state(**flags),
        skill_ticks={name: 0 for name in outcomes},
        outcomes=ScriptedOutcomes(Fail(name, None, 10**9) for name in outcomes),
    )


def set_flags(world: SymbolicWorld, **flags: bool) -> None:
    """Change flags between ticks (what a person or a skill would do to the state)."""
    on = {f: True for f in world.state.objects}
    on.update(flags)
    world.state = flag_state(**on)


def calls(world: SymbolicWorld) -> list[tuple[str, str]]:
    """Skill starts and cancels, in order, as (kind, action name)."""
    return [
        (e.kind, parse_call(e.subject)[0]) for e in world.history if e.kind in ("start", "cancel")
    ]


class Ctx:
    """A minimal tick context (what PaBtExecutor provides) for hand-built trees."""

    def __init__(self, world: SymbolicWorld) -> None:
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
