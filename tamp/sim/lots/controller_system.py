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
``Place(l)``, ``Wait(l)``) and the cell's `PandaSkillController` speaks that vocabulary itself
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

from tamp.lots.cell import SIDES, view_state
from tamp.lots.controller import LotsController
from tamp.sim.core.executor import ActionLog, ControllerSystem, PortWorld
from tamp.sim.core.messages import Observation, SkillCommand
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
    """What the camera's last view stands for: its counts in the workspace it looked at (or,
    before any view, the camera over neither workspace) and what it sees in the gripper."""
    in_hand = obs.in_hand[0] if obs.in_hand else None
    if obs.id == 0 or obs.side not in SIDES:
        return view_state(None, {}, in_hand)
    return view_state(obs.side, dict(obs.counts), in_hand)


class LotsControllerSystem(ControllerSystem):
    """Ticks a `LotsController` every ``period`` seconds; outputs its `SkillCommand`."""

    def __init__(self, controller: LotsController, *, period: float = PERIOD):
        super().__init__(
            "lots_controller",
            ("observation", Observation()),
            ControllerState(controller.snapshot()),
            period=period,
        )

    def _observe(self, context) -> WorldState:
        return observed_state(self.observation_port.Eval(context))

    def _tick(self, context, s: ControllerState, world: PortWorld) -> Status:
        status = s.controller.tick(world)
        if status is not Status.RUNNING:
            s.reason = s.controller.reason
        return status
