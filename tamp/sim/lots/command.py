"""The arm command stream: the skills' joint setpoints (every ``control.period``, 10 ms) as a
1 kHz command, as Franka's controller expects it (Zhou et al. §IV-C: the arm stops when
commands arrive below 1000 Hz).

Differential IK runs at the skill rate: each setpoint is where the arm should be one skill
period later (``q_{k+1} = q_k + v_k dt``). Solving it at 1 kHz would cost ten QPs in Python
per 10 ms; instead `ArmCommandStream` is a first-order hold at ``command_period`` (1 ms):
every millisecond it publishes the point of the straight joint-space segment from the last
command to the new setpoint, reached one skill period after the setpoint appeared, with the
segment's velocity as the desired velocity (the PD actuators' feed-forward). That is the
trajectory the setpoints describe, sampled at 1 kHz, for one small update per sample. The
fingers are not interpolated: their setpoint is a width goal passed through as it is.

The plant (SAP, 4 ms step) samples its desired-state input once per step, so physics sees
every fourth command; the 1 kHz stream matters to the watchdog that measures its rate
(`tamp.sim.lots.safety.SafetyMonitor`) and to anything else that reads the command.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

N = 9  # 7 arm joints + 2 fingers, in actuator order


class ArmCommandStream(LeafSystem):
    """First-order hold of the skills' setpoints at ``period`` (see the module docstring).

    Input ``target``: the skills' desired state (18, actuator order, velocities ignored).
    Outputs ``desired_state`` (18: positions, velocities) and ``count`` (commands published).
    ``interpolate[k]``: whether actuator k is an arm joint (True) or a finger (False).
    """

    def __init__(self, period: float, setpoint_period: float, interpolate, q0: np.ndarray):
        super().__init__()
        self.set_name("arm_command")
        self.period = float(period)
        self.setpoint_period = float(setpoint_period)
        self._arm_idx = np.flatnonzero(np.asarray(interpolate, bool))
        q0 = np.asarray(q0, float)
        # state: q_cmd, v_cmd, segment start, segment end (setpoint), segment t0, count
        init = np.r_[q0, np.zeros(N), q0, q0, 0.0, 0.0]
        self._state = self.DeclareDiscreteState(init)
        self.target_port = self.DeclareVectorInputPort("target", 2 * N)
        self.DeclarePeriodicDiscreteUpdateEvent(self.period, 0.0, self._update)
        self.desired_state_port = self.DeclareVectorOutputPort(
            "desired_state", 2 * N, self._calc_desired, {self.xd_ticket()}
        )
        self.count_port = self.DeclareVectorOutputPort(
            "count", 1, self._calc_count, {self.xd_ticket()}
        )

    def _update(self, context, xd) -> EventStatus:
        # kept lean: it runs 1000 times per simulated second
        x = xd.get_mutable_vector(self._state).get_mutable_value()
        target = self.target_port.Eval(context)[:N]
        t = context.get_time()
        if (target != x[3 * N : 4 * N]).any():  # a new setpoint: a new segment from here
            x[2 * N : 3 * N] = x[:N]
            x[3 * N : 4 * N] = target
            x[-2] = t
        start, end, t0 = x[2 * N : 3 * N], x[3 * N : 4 * N], x[-2]
        T = self.setpoint_period
        a = min((t - t0 + self.period) / T, 1.0)
        x[:N] = end
        x[self._arm_idx] = start[self._arm_idx] + a * (end[self._arm_idx] - start[self._arm_idx])
        x[N : 2 * N] = 0.0
        if t - t0 < T - 1e-9:
            x[N + self._arm_idx] = (end[self._arm_idx] - start[self._arm_idx]) / T
        x[-1] += 1
        return EventStatus.Succeeded()

    def _calc_desired(self, context, output: BasicVector) -> None:
        output.SetFromVector(context.get_discrete_state(self._state).get_value()[: 2 * N])

    def _calc_count(self, context, output: BasicVector) -> None:
        output.SetFromVector([context.get_discrete_state(self._state).get_value()[-1]])
