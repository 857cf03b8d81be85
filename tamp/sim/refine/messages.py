"""Values on the refinement workcell's abstract ports (no Drake import).

SensorReadings --Readings--> Channel --ChannelState (delivered samples)--> executor
StateMachineExecutor --Command--> Channel --actuation (setpoints)--> plant
StateMachineExecutor --Progress--> other executor, RateTuningSupervisor
RateTuningSupervisor --RateOverride--> executors
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Readings:
    """One robot's sensors right now: force at the gripper (N), the lever's pitch from the
    IMU (rad, up positive), the base's odometry pose ``(x, y, yaw)``."""

    force: float = 0.0
    imu: float = 0.0
    odometry: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def value(self, sensor: str):
        return getattr(self, sensor)

    def __deepcopy__(self, memo: dict) -> Readings:
        return self


@dataclass(frozen=True)
class Command:
    """The ``number``-th command of a robot (0: none yet), created at ``created``: absolute
    setpoints of its joints (`tamp.sim.refine.scene.JOINTS` order, fingers from the
    opening)."""

    number: int = 0
    created: float = 0.0
    setpoints: tuple[float, ...] = ()

    @property
    def actuation(self) -> np.ndarray:
        """The desired state of the robot's PD actuators: the setpoints, zero velocities."""
        return np.concatenate([self.setpoints, np.zeros(len(self.setpoints))])

    def __deepcopy__(self, memo: dict) -> Command:
        return self


@dataclass(frozen=True)
class Progress:
    """What a robot's executor has done: fired events (id -> time), the behaviors running
    now, whether every behavior's event fired, and the command rate it uses."""

    fired: dict[str, float] = field(default_factory=dict)
    running: tuple[str, ...] = ()
    done: bool = False
    rate: float = 0.0

    def __deepcopy__(self, memo: dict) -> Progress:
        return self


@dataclass(frozen=True)
class RateOverride:
    """The supervisor's command rate per robot (absent: the program's own rates)."""

    rates: dict[str, float] = field(default_factory=dict)

    def __deepcopy__(self, memo: dict) -> RateOverride:
        return self
