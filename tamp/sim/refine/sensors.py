"""SensorReadings: what one robot's sensors read right now, from the plant (no delay here;
the `Channel` samples it at the sensor rate and queues the samples).

- force (N): the magnitude of the reaction force in the welded ``gripper_mount`` joint (what
  a force sensor between the lever and the gripper measures: a push, a load), or the
  paddles' contact force along their joints when that is larger (a squeeze has no net
  force at the mount);
- IMU (rad): the lever's pitch, up positive (the base is planar, so the IMU frame's pitch
  in the world is the ``arm_pitch`` joint's angle);
- odometry: the base's pose ``(x, y, yaw)`` on the floor.
"""

from __future__ import annotations

import math

from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from tamp.sim.refine.messages import Readings


class SensorReadings(LeafSystem):
    """Force, IMU and odometry of one robot (inputs: its state, the plant's reaction forces
    and its generalized contact forces)."""

    def __init__(
        self,
        name: str,
        *,
        nq: int,
        nv: int,
        pose_index: tuple[int, int, int],
        arm_index: int,
        finger_index: tuple[int, int],
        mount_joint: int,
        reaction_model: AbstractValue,
    ):
        super().__init__()
        self.set_name(f"sensors_{name}")
        self._pose = pose_index
        self._arm = arm_index
        self._fingers = finger_index
        self._mount = mount_joint
        self.state_port = self.DeclareVectorInputPort("robot_state", nq + nv)
        self.reaction_port = self.DeclareAbstractInputPort("reaction_forces", reaction_model)
        self.contact_port = self.DeclareVectorInputPort("contact_forces", nv)
        self.readings_port = self.DeclareAbstractOutputPort(
            "readings", lambda: AbstractValue.Make(Readings()), self._calc
        )

    def _calc(self, context, output) -> None:
        x = self.state_port.Eval(context)
        fx, fy, fz = self.reaction_port.Eval(context)[self._mount].translational()
        mount = math.sqrt(fx * fx + fy * fy + fz * fz)
        tau = self.contact_port.Eval(context)
        a, b = self._fingers
        squeeze = max(abs(float(tau[a])), abs(float(tau[b])))
        i, j, k = self._pose
        output.set_value(
            Readings(
                force=max(mount, squeeze),
                imu=float(x[self._arm]),
                odometry=(float(x[i]), float(x[j]), float(x[k])),
            )
        )
