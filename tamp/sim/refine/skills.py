"""PioneerStateMachine: what drives a Pioneer-like robot, its event-driven state machine as a
LeafSystem (Figueroa Heredia et al. 2018 §2.2).

Once per sensor period the system runs `tamp.refine.machine.Machine.step` on what its
`Channel` has *delivered* (not on the plant's state), the other robot's fired events and
the supervisor's rate, and keeps the result in its abstract state. Outputs: the latest
``command`` (to the Channel, which delivers it to the actuators) and its ``progress``
(fired events, running behaviors; to the other robot's machine and the supervisor).
"""

from __future__ import annotations

from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, LeafSystem

from tamp.refine.machine import Command, Machine, MachineState, Progress
from tamp.refine.program import Program
from tamp.sim.refine.channel import ChannelState
from tamp.sim.refine.messages import RateOverride


class PioneerStateMachine(LeafSystem):
    """Fires robot ``robot``'s events on delivered data and publishes its commands at P."""

    def __init__(self, program: Program, robot: str, period: float, empty: ChannelState):
        super().__init__()
        self.set_name(f"state_machine_{robot}")
        self.robot = robot
        self.machine = Machine(program, robot)
        self.delivered_port = self.DeclareAbstractInputPort("delivered", AbstractValue.Make(empty))
        self.others_port = self.DeclareAbstractInputPort("others", AbstractValue.Make(Progress()))
        self.rates_port = self.DeclareAbstractInputPort("rates", AbstractValue.Make(RateOverride()))
        self._state = self.DeclareAbstractState(AbstractValue.Make(self.machine.initial()))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        ticket = {self.abstract_state_ticket(self._state)}
        self.command_port = self.DeclareAbstractOutputPort(
            "command",
            lambda: AbstractValue.Make(Command()),
            lambda ctx, out: out.set_value(self.state(ctx).command),
            prerequisites_of_calc=ticket,
        )
        self._progress: tuple[MachineState | None, Progress] = (None, Progress())
        self.progress_port = self.DeclareAbstractOutputPort(
            "progress",
            lambda: AbstractValue.Make(Progress()),
            self._calc_progress,
            prerequisites_of_calc=ticket,
        )

    def state(self, context) -> MachineState:
        return context.get_abstract_state(self._state).get_value()

    def _calc_progress(self, context, output) -> None:
        """The progress of the machine's state (the same state object as on the last tick,
        when its step changed nothing, gives the same progress: not recomputed)."""
        s = self.state(context)
        if s is not self._progress[0]:
            self._progress = (s, self.machine.progress_of(s))
        output.set_value(self._progress[1])

    def _update(self, context, state) -> EventStatus:
        delivered: ChannelState = self.delivered_port.Eval(context)
        others: Progress = self.others_port.Eval(context)
        override = self.rates_port.Eval(context).rates.get(self.robot)
        s = self.state(context)
        new = self.machine.step(s, context.get_time(), delivered.latest, others.fired, override)
        if new is s:
            return EventStatus.DidNothing()
        state.get_mutable_abstract_state(self._state).set_value(new)
        return EventStatus.Succeeded()
