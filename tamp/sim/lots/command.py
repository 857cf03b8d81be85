"""The arm command stream: the skills' joint setpoints (every ``control.period``, 10 ms) as a
1 kHz command, as Franka's controller expects it (Zhou et al. §IV-C: the arm stops when
commands arrive below 1000 Hz).

Differential IK runs at the skill rate: each setpoint is where the arm should be one skill
period later (``q_{k+1} = q_k + v_k dt``). Solving it at 1 kHz would cost ten QPs in Python
per 10 ms; instead `ArmCommandStream` is a first-order hold sampled at ``command_period``
(1 ms): the command of tick k (at ``k · command_period``) is the point of the straight
joint-space segment from the last command to the new setpoint, reached one skill period after
the setpoint appeared, with the segment's velocity as the desired velocity (the PD actuators'
feed-forward). That is the trajectory the setpoints describe, sampled at 1 kHz. The fingers
are not interpolated: their setpoint is a width goal passed through as it is.

A tick's command is a function of the segment and the tick's time, so the stream keeps only
the segment in its state and computes the command of the last tick when its output is read:
at time t the output is the command of the last tick before t (ticks at t itself are not yet
published, as for any discrete update at t), and ``count`` is the number of ticks so far. The
segment changes in an update one tick after each skill period, when a new setpoint is first
seen on the tick grid; setpoints change only at the skills' own periodic updates, so every
reader (the plant's 4 ms step, the watchdog every 10 ms) gets the values of a stream that
updated at every tick, without a simulator step and a Python call per millisecond. When the
skill period is not a whole number of ticks, the stream updates at every tick instead.

The plant (SAP, 4 ms step) samples its desired-state input once per step, so physics sees
every fourth command; the 1 kHz stream matters to the watchdog that measures its rate
(`tamp.sim.lots.safety.SafetyMonitor`) and to anything else that reads the command.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

N = 9  # 7 arm joints + 2 fingers, in actuator order
#: ticks within this fraction of a command period of t count as at t
_TICK_TOL = 1e-6


class ArmCommandStream(LeafSystem):
    """First-order hold of the skills' setpoints sampled at ``period`` (see the module
    docstring).

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
        # state: segment start, segment end (setpoint), segment t0
        self._state = self.DeclareDiscreteState(np.r_[q0, q0, 0.0])
        self.target_port = self.DeclareVectorInputPort("target", 2 * N)
        ticks = self.setpoint_period / self.period
        if abs(ticks - round(ticks)) < 1e-9:  # one tick after each skill period
            self.DeclarePeriodicDiscreteUpdateEvent(self.setpoint_period, self.period, self._update)
        else:  # setpoints can be first seen at any tick
            self.DeclarePeriodicDiscreteUpdateEvent(self.period, 0.0, self._update)
        deps = {self.xd_ticket(), self.time_ticket()}
        self.desired_state_port = self.DeclareVectorOutputPort(
            "desired_state", 2 * N, self._calc_desired, deps
        )
        self.count_port = self.DeclareVectorOutputPort("count", 1, self._calc_count, deps)

    def _tick(self, t: float) -> int:
        """The last tick before time ``t`` (-1: none yet)."""
        return math.ceil(t / self.period - _TICK_TOL) - 1

    def _command(self, x: np.ndarray, t: float) -> np.ndarray:
        """The command (18) of the last tick before ``t``, on the segment in state ``x``."""
        start, end, t0 = x[:N], x[N : 2 * N], x[-1]
        out = np.zeros(2 * N)
        out[:N] = end
        arm = self._arm_idx
        k = self._tick(t)
        if k < 0:  # nothing published yet: the initial command
            out[arm] = start[arm]
            return out
        tau, T = k * self.period, self.setpoint_period
        a = min((tau - t0 + self.period) / T, 1.0)
        out[arm] = start[arm] + a * (end[arm] - start[arm])
        if tau - t0 < T - 1e-9:
            out[N + arm] = (end[arm] - start[arm]) / T
        return out

    def _update(self, context, xd) -> EventStatus:
        x = xd.get_mutable_vector(self._state).get_mutable_value()
        target = self.target_port.Eval(context)[:N]
        if (target != x[N : 2 * N]).any():  # a new setpoint: a new segment from here
            t = context.get_time()
            x[:N] = self._command(context.get_discrete_state(self._state).get_value(), t)[:N]
            x[N : 2 * N] = target
            x[-1] = t
        return EventStatus.Succeeded()

    def _calc_desired(self, context, output: BasicVector) -> None:
        x = context.get_discrete_state(self._state).get_value()
        output.SetFromVector(self._command(x, context.get_time()))

    def _calc_count(self, context, output: BasicVector) -> None:
        output.SetFromVector([self._tick(context.get_time()) + 1])
