"""BtExecutor: a LeafSystem that ticks the very behavior tree of `tamp.bt` in the diagram.

The tree (a `tamp.bt.PaBtExecutor`, or any object with ``tick(world) -> Status``) lives in
the system's abstract state. A periodic unrestricted update (the BT period, e.g. 100 ms)
ticks it once against `PortWorld`, an implementation of the `tamp.world.World` protocol
over the system's ports and state:

- ``observe()``  -> the ``world_state`` input (from the `WorldStateEstimator`);
- ``start(a)``   -> a new `SkillCommand` with the next id, kept in state and sent on the
  ``skill_command`` output to the cell's skill controller (e.g. `YouBotSkillController`);
- ``poll(h)``    -> the ``skill_status`` input when it reports command ``h`` (RUNNING until
  the controller picks the command up and finishes it; the result is sticky);
- ``cancel(h)``  -> the same command with ``cancel=True``. The log says why: HALTED when the
  action's effects already hold in the observed world (the reactive tree halts a running
  ``MoveTo(x)`` as soon as ``IsRobotCloseTo(x)`` holds: its goal is reached), CANCELLED
  otherwise (the skill was stopped short of its goal);
- ``add_area(a)`` -> an area the tree found at run time (ring search), kept in the state.

Everything a run changes lives in the Context (the abstract state): the tree, the current
command and action, the log, and the areas found at run time. The System object holds only
what the diagram was built with, so one diagram can run twice (two contexts) without one
run leaking into the other. The state also keeps the action log with sim start/end times.
Once the tree returns SUCCESS or FAILURE the executor stops ticking and reports ``done``.

Cost. Drake deep-copies abstract state on every update (twice: into the scratch state and
back). A grown tree of ~60 nodes takes ~4 ms to deep-copy, so the tree is kept in the
state as its pickled bytes (immutable: copying them is free) and the system memoises the
live tree that belongs to the latest bytes, so a tick costs one ``pickle.dumps``. If the
simulator ever hands back older state (a cloned or reset context), the memo misses and
the tree is rebuilt from the bytes, so the state alone always determines the behaviour.
"""

from __future__ import annotations

import copy
import pickle
from dataclasses import dataclass, field
from typing import Any, Protocol

from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, LeafSystem

from tamp.sim.core.messages import SkillCommand, SkillStatus
from tamp.world.actions import Action
from tamp.world.geometry import Area, Point, Pose
from tamp.world.interface import Status
from tamp.world.state import WorldState


class Policy(Protocol):
    """What the executor ticks: `tamp.bt.PaBtExecutor` (or a scripted stand-in in tests)."""

    def tick(self, world: Any) -> Status: ...


@dataclass
class ActionLog:
    """One skill run in sim time."""

    id: int
    action: str
    start: float
    end: float | None = None
    status: str | None = None  # SUCCESS | FAILURE | HALTED (goal reached) | CANCELLED
    detail: str = ""
    cause: str | None = None  # a FAILURE's `tamp.sim.core.outcome.CAUSES` code (the skill's)

    @property
    def outcome(self) -> str:
        """What happened, for the action table: ``done (halted)`` for a skill halted at its
        goal, else the status (RUNNING while it runs)."""
        if self.status == "HALTED":
            return "done (halted)"
        return self.status or "RUNNING"

    def to_json(self) -> dict:
        return {
            "id": self.id,
            "action": self.action,
            "start": round(self.start, 3),
            "end": None if self.end is None else round(self.end, 3),
            "status": self.status,
            "detail": self.detail,
            "cause": self.cause,
        }


@dataclass
class ExecutorState:
    """The executor's abstract state: the tree (pickled), the current command, the log."""

    policy_blob: bytes
    command: SkillCommand = field(default_factory=SkillCommand)
    next_id: int = 1
    log: list[ActionLog] = field(default_factory=list)
    extra_areas: dict[str, Area] = field(default_factory=dict)
    result: Status | None = None
    finished_at: float | None = None
    ticks: int = 0
    action: Action | None = None  # the action of ``command`` (its effects tell HALTED)

    def __deepcopy__(self, memo: dict) -> ExecutorState:
        # the tree is copied by its own __deepcopy__ (tamp.bt shares predicates and
        # actions); log records are small and copied one by one; messages are immutable.
        return ExecutorState(
            self.policy_blob,
            self.command,
            self.next_id,
            [copy.copy(r) for r in self.log],
            dict(self.extra_areas),
            self.result,
            self.finished_at,
            self.ticks,
            self.action,
        )


class PortWorld:
    """The `World` protocol over the BtExecutor's input ports and (mutable) state."""

    def __init__(self, state: ExecutorState, world: WorldState, status: SkillStatus, t: float):
        self._s = state
        self._world = world
        self._status = status
        self._t = t

    def observe(self) -> WorldState:
        w = self._world
        for area in self._s.extra_areas.values():
            if area.name not in w.areas:
                w = w.with_area(area)
        return w

    def start(self, action: Action) -> int:
        s = self._s
        if s.log and s.log[-1].status is None:
            raise RuntimeError(f"{action} started while {s.log[-1].action} runs")
        areas = tuple(
            s.extra_areas[a] for a in action.args if a in s.extra_areas
        )  # areas found at run time travel with the command
        s.command = SkillCommand(s.next_id, action.name, tuple(action.args), areas=areas)
        s.action = action
        s.log.append(ActionLog(s.next_id, str(action), self._t))
        s.next_id += 1
        return s.command.id

    def poll(self, handle: int) -> Status:
        for rec in reversed(self._s.log):
            if rec.id == handle and rec.status is not None:
                if rec.status in ("CANCELLED", "HALTED"):
                    return Status.FAILURE
                return Status(rec.status)
        st = self._status
        if st.id == handle and st.status is not Status.RUNNING:
            for rec in reversed(self._s.log):
                if rec.id == handle:
                    rec.end, rec.status, rec.detail, rec.cause = (
                        self._t,
                        st.status.value,
                        st.detail,
                        st.cause,
                    )
            return st.status
        return Status.RUNNING

    def cancel(self, handle: int) -> None:
        s = self._s
        st = self._status
        if st.id == handle and st.status is not Status.RUNNING:
            # the skill had already ended (the tree saw its effect before polling it)
            for rec in reversed(s.log):
                if rec.id == handle and rec.status is None:
                    rec.end, rec.status, rec.detail, rec.cause = (
                        self._t,
                        st.status.value,
                        st.detail,
                        st.cause,
                    )
            return
        reached = self._goal_reached(handle)
        if s.command.id == handle:
            s.command = SkillCommand(
                handle, s.command.name, s.command.args, cancel=True, areas=s.command.areas
            )
        for rec in reversed(s.log):
            if rec.id == handle and rec.status is None:
                rec.end = self._t
                if reached:
                    rec.status, rec.detail = "HALTED", f"goal reached: {reached}"
                else:
                    rec.status = "CANCELLED"

    def _goal_reached(self, handle: int) -> str:
        """The effects of command ``handle``'s action, when all hold in the observed world
        (the tree halted it at its goal); "" otherwise."""
        s = self._s
        action = s.action if s.command.id == handle else None
        if action is None or not action.eff:
            return ""
        world = self.observe()
        if all(e.holds(world) for e in action.eff):
            return ", ".join(str(e) for e in action.eff)
        return ""

    def add_area(self, area: Area) -> None:
        """An l_free found at run time by the tree (ring search): places can use it."""
        self._s.extra_areas[area.name] = area


class ControllerSystem(LeafSystem):
    """A tick-based controller in the diagram (BT executor, LOTS controller).

    Ports: the subclass's observation input, ``skill_status`` in, ``skill_command`` out.
    The controller's state lives in the Context (abstract state, holding ``command``,
    ``result``, ``finished_at`` and ``ticks``); a periodic unrestricted update calls
    `_tick` on Drake's copy of it until the controller stops, and the output is computed
    from that state only.
    """

    def __init__(self, name: str, observation: tuple[str, Any], initial: Any, *, period: float):
        super().__init__()
        self.set_name(name)
        self.observation_port = self.DeclareAbstractInputPort(
            observation[0], AbstractValue.Make(observation[1])
        )
        self.skill_status_port = self.DeclareAbstractInputPort(
            "skill_status", AbstractValue.Make(SkillStatus())
        )
        self._state = self.DeclareAbstractState(AbstractValue.Make(initial))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        self.command_port = self.DeclareAbstractOutputPort(
            "skill_command",
            lambda: AbstractValue.Make(SkillCommand()),
            self._calc_command,
            prerequisites_of_calc={self.abstract_state_ticket(self._state)},
        )

    def state(self, context) -> Any:
        """The controller state in this system's ``context``."""
        return context.get_abstract_state(self._state).get_value()

    def _calc_command(self, context, output) -> None:
        output.set_value(self.state(context).command)

    def _tick(self, context, s: Any, world: PortWorld) -> Status:
        """One tick of the controller held in ``s`` against ``world`` (subclasses)."""
        raise NotImplementedError

    def _observe(self, context) -> WorldState:
        """The `WorldState` the controller observes this tick (subclasses may convert)."""
        return self.observation_port.Eval(context)

    def _update(self, context, state) -> EventStatus:
        # ``state`` holds Drake's own (deep) copy of the context's state: change it in place
        s = state.get_mutable_abstract_state(self._state).get_value()
        if s.result is not None:
            return EventStatus.DidNothing()
        t = context.get_time()
        world = PortWorld(s, self._observe(context), self.skill_status_port.Eval(context), t)
        status = self._tick(context, s, world)
        s.ticks += 1
        if status is not Status.RUNNING:
            s.result = status
            s.finished_at = t
        state.get_mutable_abstract_state(self._state).set_value(s)
        return EventStatus.Succeeded()


class BtExecutor(ControllerSystem):
    """Ticks the behavior tree at a fixed period; outputs the `SkillCommand`."""

    def __init__(self, policy: Policy, *, period: float):
        blob = pickle.dumps(policy, protocol=pickle.HIGHEST_PROTOCOL)
        self._live: tuple[bytes, Any] = (blob, policy)
        super().__init__(
            "bt_executor",
            ("world_state", WorldState(robot=Pose(Point(0.0, 0.0)))),
            ExecutorState(blob),
            period=period,
        )
        self.world_state_port = self.observation_port

    def policy(self, context) -> Any:
        """The tree as it is in ``context`` (a live object; do not tick it)."""
        blob = self.state(context).policy_blob
        return self._live[1] if self._live[0] is blob else pickle.loads(blob)

    def _tick(self, context, s: ExecutorState, world: PortWorld) -> Status:
        blob = s.policy_blob
        policy = self._live[1] if self._live[0] is blob else pickle.loads(blob)
        status = policy.tick(world)
        s.policy_blob = pickle.dumps(policy, protocol=pickle.HIGHEST_PROTOCOL)
        self._live = (s.policy_blob, policy)
        return status
