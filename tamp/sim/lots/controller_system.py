"""The LOTS controller (Zhou et al. Alg. 1-3) as a LeafSystem of the workcell diagram.

`LotsControllerSystem` holds a tick-based `tamp.lots.controller.LotsController` in its
abstract state and ticks it once per periodic unrestricted update against a `PortWorld` (the
`tamp.world.World` contract over ports and state that the BT executor uses too):

- ``observe()``  -> `observed_state` of the ``observation`` input: the counts per class of the
  workspace the wrist camera saw last, as `tamp.lots.cell.view_state` (the controller reads
  only `tamp.lots.cell.visible_counts` of it, and only when a ``LookAt`` ends);
- ``start(a)``   -> a `SkillCommand` with the next id on the ``skill_command`` output;
- ``poll(h)``    -> the ``skill_status`` input when it reports command ``h``;
- ``cancel(h)``  -> the same command with ``cancel=True``.

The controller's skills are the ``lots_arm`` domain's (``LookAt(l)``, ``Pick(k, l)``,
``Place(l)``, ``Wait(l)``) and the cell's `SkillController` speaks that vocabulary itself
(``Place(waste)`` is its ``Discard()``, ``Wait(l)`` a look and a hold), so nothing is
translated here and the skill timing stays in the one skill layer.

The inputs are the camera's observation and the skills' status only: the controller never
sees a plant pose (a test walks the diagram's connections). The state is kept by deep copy:
`ControllerState.__deepcopy__` takes the controller's `snapshot` (~50 us), which shares the
automaton, planner and tables, so Drake's two copies per update stay cheap.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, LeafSystem

from tamp.lots.cell import SIDES, initial_state, view_state
from tamp.lots.controller import LotsController
from tamp.sim.core.executor import ActionLog, PortWorld
from tamp.sim.core.messages import SkillCommand, SkillStatus
from tamp.sim.lots.perception import Observation
from tamp.world.actions import Action
from tamp.world.interface import Status
from tamp.world.state import WorldState

#: controller tick (s): fast enough to start the next skill without a visible pause
PERIOD = 0.05


@dataclass
class ControllerState:
    """The system's abstract state: the controller, the current command and the skill log.

    ``command``, ``next_id``, ``log``, ``action`` and ``extra_areas`` are what `PortWorld`
    reads and writes (the same fields as the BT executor's state).
    """

    controller: LotsController
    command: SkillCommand = field(default_factory=SkillCommand)
    next_id: int = 1
    log: list[ActionLog] = field(default_factory=list)
    action: Action | None = None
    extra_areas: dict = field(default_factory=dict)
    result: Status | None = None
    reason: str = ""
    finished_at: float | None = None
    ticks: int = 0

    def __deepcopy__(self, memo: dict) -> ControllerState:
        return ControllerState(
            self.controller.snapshot(),
            self.command,
            self.next_id,
            [copy.copy(r) for r in self.log],
            self.action,
            dict(self.extra_areas),
            self.result,
            self.reason,
            self.finished_at,
            self.ticks,
        )


def observed_state(obs: Observation) -> WorldState:
    """What the camera's last view stands for: its counts in the workspace it looked at, or
    (before any view) the camera over neither workspace."""
    if obs.id == 0 or obs.side not in SIDES:
        return initial_state({})
    return view_state(obs.side, dict(obs.counts))


class LotsControllerSystem(LeafSystem):
    """Ticks a `LotsController` every ``period`` seconds; outputs its `SkillCommand`."""

    def __init__(self, controller: LotsController, *, period: float = PERIOD):
        super().__init__()
        self.set_name("lots_controller")
        self.observation_port = self.DeclareAbstractInputPort(
            "observation", AbstractValue.Make(Observation())
        )
        self.skill_status_port = self.DeclareAbstractInputPort(
            "skill_status", AbstractValue.Make(SkillStatus())
        )
        init = ControllerState(controller.snapshot())
        self._state = self.DeclareAbstractState(AbstractValue.Make(init))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        self.command_port = self.DeclareAbstractOutputPort(
            "skill_command",
            lambda: AbstractValue.Make(SkillCommand()),
            self._calc_command,
            prerequisites_of_calc={self.abstract_state_ticket(self._state)},
        )

    def state(self, context) -> ControllerState:
        """The controller state in this system's ``context`` (controller, log, result)."""
        return context.get_abstract_state(self._state).get_value()

    def _calc_command(self, context, output) -> None:
        output.set_value(self.state(context).command)

    def _update(self, context, state) -> EventStatus:
        # ``state`` is Drake's own copy of the context's state: change it in place
        s: ControllerState = state.get_mutable_abstract_state(self._state).get_value()
        if s.result is not None:
            return EventStatus.DidNothing()
        t = context.get_time()
        obs = self.observation_port.Eval(context)
        world = PortWorld(s, observed_state(obs), self.skill_status_port.Eval(context), t)
        status = s.controller.tick(world)
        s.ticks += 1
        if status is not Status.RUNNING:
            s.result, s.reason, s.finished_at = status, s.controller.reason, t
        state.get_mutable_abstract_state(self._state).set_value(s)
        return EventStatus.Succeeded()
