"""`SymbolicWorld`: the one `World` over a `WorldState`, for runs, tests and verification.

- Skills: a skill started at clock ``t`` finishes at the first poll with
  ``clock >= t + ticks`` (``skill_ticks``: one number, or one per action name; 0 finishes on
  the first poll). A skill whose preconditions do not hold when it starts fails at its
  first poll; when it finishes its preconditions are checked again (FAILURE, state
  unchanged, when they no longer hold), then the ``outcomes`` source decides: SUCCESS
  applies the effects in order (``a.eef(s)``, SMP-MRO §IV-C1), FAILURE leaves the state
  unchanged. Sources (`tamp.world.outcomes`): `ScriptedOutcomes` (``Fail`` entries, the
  default: none) and `BranchingOutcomes` (verification explores every outcome).
- Events: `tamp.world.events.Appear` entries. An object that is not in the state appears;
  a known object is put there by a person (dropped from the hand if held). PLACE is a point
  or an area name (its centre in the current state; an unknown area is bad input). WHEN:
  `AtTick` fires when the clock reaches the tick, `AtTime` when ``clock * tick_period``
  reaches the time (``tick_period`` seconds per tick, default 0.1 s: the simulated BT
  period), `AfterAction` right after that skill succeeds (the first time), and None when
  the robot first comes within ``reach`` of the place (SMP-MRO §V-D2, Case 3's O_a at l_1).
  Discovery is checked at each `step` and, with ``discover_on_arrival`` (the default),
  also right after each skill that succeeds, so the robot sees the object in the tick it
  arrives; the verification explorer turns this off (the object is then seen at the next
  tick, which is what its state counts were established with).
- `happen` applies an `Appear` (its WHEN ignored) or a `Remove` now: what a scripted person
  (`tamp.lots.person`) does between ticks.
- ``step()`` advances the clock by one tick, resets the per-tick record and fires the
  timed and reach events that are due; run loops call it before each executor tick.
- Per-tick record (reset by `step`, read by verification labels): ``action_failed`` (a
  skill finished with FAILURE in this tick), ``placed_in_occupied`` (a skill put an object
  into an area that already held another one), `tick_events` (the history of this tick).
- Starting a skill while another runs raises RuntimeError (the protocol's rule) and is
  counted in ``violations``. ``copy.deepcopy`` is cheap: states, events, actions and the
  history entries are immutable and shared.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace

from tamp.errors import InputError
from tamp.world.actions import Action
from tamp.world.events import AfterAction, Appear, AtTick, AtTime, Remove
from tamp.world.geometry import Area, Point, Pose
from tamp.world.interface import Status
from tamp.world.outcomes import OutcomeSource, ScriptedOutcomes
from tamp.world.predicates import DEFAULT_REACH, IsObjectAt
from tamp.world.state import WorldState

#: Seconds per tick used to convert `AtTime` events (the Drake scenarios' BT period).
DEFAULT_TICK_PERIOD = 0.1

_TEXT = {
    "start": "start {s}",
    "success": "{s} -> SUCCESS",
    "failure": "{s} -> FAILURE",
    "cancel": "cancel {s}",
    "appear": "{s} appears at {d}",
    "move": "{s} is moved to {d}",
    "remove": "{s} is taken away",
}


@dataclass(frozen=True)
class WorldEvent:
    """What happened in the world: start/success/failure/cancel of a skill, appear/move/remove.

    ``subject`` is the action or the object; ``detail`` why a skill failed, or where the
    object was put.
    """

    clock: int
    kind: str
    subject: str
    detail: str = ""

    @property
    def what(self) -> str:
        """One line for reports (``tamp plan --execute --json``'s ``world_events``)."""
        if self.kind in ("appear", "move"):
            return f"{self.subject} at {self.detail}"
        return self.subject + (f": {self.detail}" if self.detail else "")

    def to_json(self) -> dict:
        return {"clock": self.clock, "kind": self.kind, "what": self.what}

    def __str__(self) -> str:
        return _TEXT[self.kind].format(s=self.subject, d=self.detail)


@dataclass(frozen=True)
class _Skill:
    """One skill attempt; replaced (never changed) when it ends, so copies share it."""

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
        outcomes: OutcomeSource | None = None,
        events: Iterable[Appear] = (),
        reach: float = DEFAULT_REACH,
        tick_period: float = DEFAULT_TICK_PERIOD,
        discover_on_arrival: bool = True,
    ) -> None:
        self.state = state
        self.clock = 0
        self.skill_ticks = skill_ticks
        self.outcomes: OutcomeSource = outcomes if outcomes is not None else ScriptedOutcomes()
        self.reach = reach
        self.tick_period = tick_period
        self.discover_on_arrival = discover_on_arrival
        self._events = list(events)
        for ev in self._events:
            if isinstance(ev.place, str) and ev.place not in state.areas:
                raise InputError(
                    f"{ev}: unknown area {ev.place!r} (known: {', '.join(sorted(state.areas))})",
                    field="--appear",
                )
        self._skills: dict[int, _Skill] = {}
        self._next_handle = 1
        self._running: int | None = None
        self._tick_start = 0
        self.violations = 0
        self.history: list[WorldEvent] = []
        self.action_failed = False
        self.placed_in_occupied = False

    # -- World protocol --------------------------------------------------------------------
    def observe(self) -> WorldState:
        return self.state

    def start(self, action: Action) -> int:
        if self._running is not None:
            self.violations += 1
            raise RuntimeError(
                f"cannot start {action}: {self._skills[self._running].action} is still running"
            )
        handle = self._next_handle
        self._next_handle += 1
        self._skills[handle] = _Skill(
            action,
            self.clock,
            self._ticks_for(action.name),
            applicable=action.applicable(self.state),
        )
        self._running = handle
        self._record("start", str(action))
        return handle

    def poll(self, handle: int) -> Status:
        skill = self._skills[handle]
        if skill.status is not Status.RUNNING:
            return skill.status
        if not skill.applicable:
            return self._finish(handle, Status.FAILURE, "preconditions did not hold at start")
        if self.clock - skill.started < skill.ticks:
            return Status.RUNNING
        action = skill.action
        if not action.applicable(self.state):
            return self._finish(handle, Status.FAILURE, "preconditions no longer hold")
        if self.outcomes.outcome(action) is Status.FAILURE:
            return self._finish(handle, Status.FAILURE, self.outcomes.reason)
        before = self.state
        self.state = action.apply(before)
        if self._into_occupied(action, before):
            self.placed_in_occupied = True
        status = self._finish(handle, Status.SUCCESS, "")
        self._fire_after(action)
        return status

    def cancel(self, handle: int) -> None:
        skill = self._skills.get(handle)
        if skill is None or skill.status is not Status.RUNNING:
            return
        self._skills[handle] = replace(skill, status=Status.FAILURE)
        if self._running == handle:
            self._running = None
        self._record("cancel", str(skill.action))

    # -- extensions ------------------------------------------------------------------------
    def add_area(self, area: Area) -> None:
        """Make a new area (a free area found by the executor's ring search) known."""
        if area.name not in self.state.areas:
            self.state = self.state.with_area(area)

    def happen(self, ev: Appear | Remove) -> None:
        """Apply ``ev`` now (an `Appear`'s WHEN is ignored): a person acting between ticks.

        An unknown area or object is a `ValueError` (the caller validated its script).
        """
        if isinstance(ev, Remove):
            if ev.obj not in self.state.objects:
                raise ValueError(f"{ev}: unknown object {ev.obj!r}")
            have = self.state.objects[ev.obj].count
            left = 0 if ev.count is None else have - ev.count
            if left < 0:
                raise ValueError(f"{ev}: only {have} in {ev.obj!r}")
            self.state = self.state.with_count(ev.obj, left)
            self._record("remove", ev.obj)
            return
        if isinstance(ev.place, str) and ev.place not in self.state.areas:
            raise ValueError(f"{ev}: unknown area {ev.place!r}")
        self._fire(ev)

    def step(self) -> None:
        """Advance the clock one tick, reset the per-tick record, fire the due events."""
        self.clock += 1
        self.action_failed = False
        self.placed_in_occupied = False
        self._tick_start = len(self.history)
        self._fire_where(self._due)

    @property
    def busy(self) -> bool:
        return self._running is not None

    @property
    def running(self) -> Action | None:
        """The action whose skill runs now, if any."""
        return None if self._running is None else self._skills[self._running].action

    @property
    def pending_events(self) -> tuple[Appear, ...]:
        """The events that have not fired yet, in their given order."""
        return tuple(self._events)

    def executed(self) -> list[Action]:
        """Actions whose skill finished with SUCCESS, in order."""
        return [s.action for s in self._skills.values() if s.status is Status.SUCCESS]

    def tick_events(self) -> list[WorldEvent]:
        """What happened since the last `step` (the history of this tick)."""
        return self.history[self._tick_start :]

    def clear_history(self) -> None:
        """Forget the history (long explorations keep their copies small)."""
        self.history = []
        self._tick_start = 0

    def fingerprint(self) -> tuple:
        """A hashable value of everything that decides what this world does next: the
        state (rounded), the running skill, the outcome source, the pending events, the
        clock when a timed event is pending, and the per-tick record."""
        timed = any(isinstance(ev.when, AtTick | AtTime) for ev in self._events)
        running = self.running
        return (
            state_key(self.state),
            None if running is None else str(running),
            self.outcomes.key(),
            tuple(self._events),
            self.clock if timed else None,
            self.action_failed,
            self.placed_in_occupied,
        )

    def __deepcopy__(self, memo: dict) -> SymbolicWorld:
        new = copy.copy(self)
        memo[id(self)] = new
        new._skills = dict(self._skills)  # skill records are immutable: shared
        new._events = list(self._events)
        new.history = list(self.history)
        new.outcomes = self.outcomes.copy()
        return new

    # -- helpers ---------------------------------------------------------------------------
    def _ticks_for(self, name: str) -> int:
        if isinstance(self.skill_ticks, Mapping):
            return int(self.skill_ticks.get(name, 1))
        return int(self.skill_ticks)

    def _record(self, kind: str, subject: str, detail: str = "") -> None:
        self.history.append(WorldEvent(self.clock, kind, subject, detail))

    def _finish(self, handle: int, status: Status, why: str) -> Status:
        skill = self._skills[handle]
        self._skills[handle] = replace(skill, status=status)
        if self._running == handle:
            self._running = None
        if status is Status.FAILURE:
            self.action_failed = True
        self._record("success" if status is Status.SUCCESS else "failure", str(skill.action), why)
        return status

    def _into_occupied(self, action: Action, before: WorldState) -> bool:
        """Did ``action`` put an object into an area that already held another one?"""
        for e in action.eff:
            if isinstance(e, IsObjectAt) and e.area in before.areas:
                area = before.area(e.area)
                if any(o != e.obj for o in self.state.objects_in(area)):
                    return True
        return False

    def _point(self, ev: Appear) -> Point:
        return self.state.area(ev.place).pos if isinstance(ev.place, str) else ev.place

    def _within_reach(self, ev: Appear) -> bool:
        return self.state.robot.pos.planar_distance(self._point(ev)) <= self.reach + 1e-9

    def _due(self, ev: Appear) -> bool:
        when = ev.when
        if when is None:
            return self._within_reach(ev)
        if isinstance(when, AtTick):
            return self.clock >= when.tick
        if isinstance(when, AtTime):
            return self.clock * self.tick_period >= when.seconds - 1e-9
        return False  # AfterAction: fired by the skill that succeeds

    def _fire_after(self, action: Action) -> None:
        def due(ev: Appear) -> bool:
            when = ev.when
            if isinstance(when, AfterAction):
                return when.matches(action.name, action.args)
            return when is None and self.discover_on_arrival and self._within_reach(ev)

        self._fire_where(due)

    def _fire_where(self, due) -> None:
        if not self._events:
            return
        remaining = []
        for ev in self._events:
            if due(ev):
                self._fire(ev)
            else:
                remaining.append(ev)
        self._events = remaining

    def _fire(self, ev: Appear) -> None:
        p = self._point(ev)
        old = self.state.objects.get(ev.obj)
        orientation = old.pose.orientation if old else Pose.at(0, 0).orientation
        state, obj = self.state, ev.obj
        if old is not None:  # a person moves `count` objects of a pile (all of a single one)
            state, obj = state.split(obj, min(ev.count, old.count))
        if state.held == obj:
            state = state.with_held(None)
        pose = Pose(Point(p.x, p.y, p.z), orientation)
        if old is None:
            self.state = state.with_object_at(obj, pose, ev.kind, ev.count)
        else:
            self.state = state.with_object_at(obj, pose)
        self._record("move" if old else "appear", obj, f"({p.x:g}, {p.y:g})")


def state_key(s: WorldState) -> tuple:
    """A hashable value of a state, positions rounded to a micrometre (merges equal states)."""
    return (
        (round(s.robot.pos.x, 6), round(s.robot.pos.y, 6), round(s.robot.orientation.yaw(), 6)),
        s.held,
        tuple(
            sorted(
                (k, tuple(round(v, 6) for v in o.pos.as_tuple()), o.count)
                for k, o in s.objects.items()
            )
        ),
        tuple(sorted(s.areas)),
    )
