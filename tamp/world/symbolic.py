"""`SymbolicWorld`: the `World` protocol over a `WorldState`, for tests and benchmarks.

- A skill started at clock ``t`` finishes at the first poll with ``clock >= t + ticks``
  (``skill_ticks``: one number, or one per action name; 0 finishes on the first poll).
  When it finishes, its preconditions are checked again; if they hold (and no scripted
  failure applies) its effects are applied in order (``a.eef(s)``, §IV-C1) and the poll
  returns SUCCESS, otherwise FAILURE and the state is unchanged. A skill whose
  preconditions do not hold when it starts fails at its first poll.
- ``failures``: `ScriptedFailure` entries; the first ``times`` attempts of a matching action
  fail (e.g. a pick of O1 that fails once).
- ``events``: `Appear` (an object that was not in the demonstration shows up — Case 3's O_a
  at l_1) and `Move` (a person moves an object). An event with ``at_tick`` fires when the
  clock reaches it; an `Appear` without ``at_tick`` fires as soon as the robot is within
  reach of its position (checked at each `step` and right after each finished skill: the
  robot discovers it when it gets there, §V-D2).
- ``step()`` advances the clock by one tick and fires due events; the run loop calls it
  before each executor tick.
- Starting a skill while another runs raises RuntimeError (the protocol's rule) and is
  counted in ``violations``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from tamp.world.actions import Action
from tamp.world.geometry import Area, Point, Pose
from tamp.world.interface import Status
from tamp.world.predicates import DEFAULT_REACH
from tamp.world.state import WorldState


@dataclass(frozen=True)
class ScriptedFailure:
    """The first ``times`` attempts of ``action`` (with ``args``, if given) fail."""

    action: str
    args: tuple[str, ...] | None = None
    times: int = 1

    def matches(self, action: Action) -> bool:
        return action.name == self.action and (self.args is None or action.args == self.args)


@dataclass(frozen=True)
class Appear:
    """Object ``obj`` appears at ``pos`` at clock ``at_tick``, or when the robot reaches it."""

    obj: str
    pos: Point
    at_tick: int | None = None


@dataclass(frozen=True)
class Move:
    """At clock ``at_tick`` a person puts object ``obj`` at ``pos`` (it is dropped if held)."""

    obj: str
    pos: Point
    at_tick: int


@dataclass
class WorldEvent:
    """What happened in the world, for reports: start/success/failure/cancel/appear/move."""

    clock: int
    kind: str
    what: str


@dataclass
class _Skill:
    action: Action
    started: int
    ticks: int
    status: Status = Status.RUNNING
    applicable: bool = True


class SymbolicWorld:
    """Applies action effects symbolically after a configurable number of ticks."""

    def __init__(
        self,
        state: WorldState,
        *,
        skill_ticks: int | Mapping[str, int] = 1,
        failures: Iterable[ScriptedFailure] = (),
        events: Iterable[Appear | Move] = (),
        reach: float = DEFAULT_REACH,
    ) -> None:
        self.state = state
        self.clock = 0
        self.skill_ticks = skill_ticks
        self.reach = reach
        self._failures = {i: [f, f.times] for i, f in enumerate(failures)}
        self._events = list(events)
        self._skills: dict[int, _Skill] = {}
        self._next_handle = 1
        self._running: int | None = None
        self.violations = 0
        self.history: list[WorldEvent] = []
        self.fired: list[Appear | Move] = []

    # -- World protocol --------------------------------------------------------------------
    def observe(self) -> WorldState:
        return self.state

    def start(self, action: Action) -> int:
        if self._running is not None:
            self.violations += 1
            raise RuntimeError(
                f"cannot start {action}: {self._skills[self._running].action} is still running"
            )
        ticks = self._ticks_for(action.name)
        handle = self._next_handle
        self._next_handle += 1
        self._skills[handle] = _Skill(
            action, self.clock, ticks, applicable=action.applicable(self.state)
        )
        self._running = handle
        self.history.append(WorldEvent(self.clock, "start", str(action)))
        return handle

    def poll(self, handle: int) -> Status:
        skill = self._skills[handle]
        if skill.status is not Status.RUNNING:
            return skill.status
        if not skill.applicable:
            return self._finish(handle, Status.FAILURE, "preconditions did not hold at start")
        if self.clock - skill.started < skill.ticks:
            return Status.RUNNING
        if not skill.action.applicable(self.state):
            return self._finish(handle, Status.FAILURE, "preconditions no longer hold")
        for entry in self._failures.values():
            f, left = entry
            if left > 0 and f.matches(skill.action):
                entry[1] -= 1
                return self._finish(handle, Status.FAILURE, "scripted failure")
        self.state = skill.action.apply(self.state)
        status = self._finish(handle, Status.SUCCESS, "")
        self._fire_due(on_reach_only=True)  # discovered on arrival
        return status

    def cancel(self, handle: int) -> None:
        skill = self._skills.get(handle)
        if skill is None or skill.status is not Status.RUNNING:
            return
        skill.status = Status.FAILURE
        if self._running == handle:
            self._running = None
        self.history.append(WorldEvent(self.clock, "cancel", str(skill.action)))

    # -- extensions ------------------------------------------------------------------------
    def add_area(self, area: Area) -> None:
        """Make a new area (a free area found by the executor's ring search) known."""
        if area.name not in self.state.areas:
            self.state = self.state.with_area(area)

    def step(self) -> None:
        """Advance the clock one tick and fire the events that are due."""
        self.clock += 1
        self._fire_due(on_reach_only=False)

    def _fire_due(self, *, on_reach_only: bool) -> None:
        remaining = []
        for ev in self._events:
            if (not on_reach_only or ev.at_tick is None) and self._due(ev):
                self._fire(ev)
            else:
                remaining.append(ev)
        self._events = remaining

    @property
    def busy(self) -> bool:
        return self._running is not None

    def executed(self) -> list[Action]:
        """Actions whose skill finished with SUCCESS, in order."""
        return [s.action for s in self._skills.values() if s.status is Status.SUCCESS]

    # -- helpers ---------------------------------------------------------------------------
    def _ticks_for(self, name: str) -> int:
        if isinstance(self.skill_ticks, Mapping):
            return int(self.skill_ticks.get(name, 1))
        return int(self.skill_ticks)

    def _finish(self, handle: int, status: Status, why: str) -> Status:
        skill = self._skills[handle]
        skill.status = status
        if self._running == handle:
            self._running = None
        kind = "success" if status is Status.SUCCESS else "failure"
        self.history.append(
            WorldEvent(self.clock, kind, str(skill.action) + (f": {why}" if why else ""))
        )
        return status

    def _due(self, ev: Appear | Move) -> bool:
        if ev.at_tick is not None:
            return self.clock >= ev.at_tick
        return self.state.robot.pos.planar_distance(ev.pos) <= self.reach + 1e-9

    def _fire(self, ev: Appear | Move) -> None:
        old = self.state.objects.get(ev.obj)
        z = ev.pos.z
        pose = Pose(
            Point(ev.pos.x, ev.pos.y, z), old.pose.orientation if old else Pose.at(0, 0).orientation
        )
        state = self.state
        if state.held == ev.obj:
            state = state.with_held(None)
        self.state = state.with_object_at(ev.obj, pose)
        kind = "appear" if isinstance(ev, Appear) else "move"
        self.fired.append(ev)
        self.history.append(
            WorldEvent(self.clock, kind, f"{ev.obj} at ({ev.pos.x:g}, {ev.pos.y:g})")
        )
