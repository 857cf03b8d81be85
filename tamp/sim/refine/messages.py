"""Values on the refinement workcell's abstract ports (no Drake import).

SensorReadings --Readings--> Channel --ChannelState (delivered samples)--> PioneerStateMachine
PioneerStateMachine --Command--> Channel --actuation (setpoints)--> plant
PioneerStateMachine --Progress--> the other robot's machine, RateTuningSupervisor
RateTuningSupervisor --RateOverride--> both machines

`Command` and `Progress` are what a state machine puts out (`tamp.refine.machine`).
"""

from __future__ import annotations

from dataclasses import dataclass, field


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
class RateOverride:
    """The supervisor's command rate per robot (absent: the program's own rates)."""

    rates: dict[str, float] = field(default_factory=dict)

    def __deepcopy__(self, memo: dict) -> RateOverride:
        return self
