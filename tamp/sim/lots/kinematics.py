"""The arm's own kinematic model: forward kinematics of the TCP and camera, and one step of
Drake's differential IK (the skills' only way of moving the end effector).

A separate arm-only `MultibodyPlant` (same SDF, base welded) serves as the controller's
model, as on a real robot: it never sees the objects. `step` solves Drake's
``DoDifferentialInverseKinematics`` QP over the 7 arm joints for a desired TCP spatial
velocity, with Franka's joint position, velocity and acceleration limits and a small
joint-centring term towards the ready posture (it resolves the arm's redundancy). The QP
plans within `LIMIT_MARGIN` of the velocity and acceleration limits, and where it finds no
solution the arm brakes within them (`brake`) instead of stopping dead: the safety monitor
checks the commands against the full limits, and a velocity zeroed in one 10 ms step is an
acceleration of 100 rad/s^2 or more, an emergency stop of the arm's own making.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.inverse_kinematics import (
    DifferentialInverseKinematicsParameters,
    DifferentialInverseKinematicsStatus,
    DoDifferentialInverseKinematics,
)
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable

from tamp.grasp.rect import wrap_angle
from tamp.sim.core.parsing import make_parser
from tamp.sim.lots.catalogue import ARM, READY

#: share of Franka's joint velocity and acceleration limits the differential IK plans within
#: (the safety monitor allows 1 % over the full limits; the 1 kHz command stream between
#: the two reads the setpoints' differences, which round a little above the QP's bound)
LIMIT_MARGIN = 0.9

#: TCP pointing down, hand x along world x: the orientation of the look poses (yaw 0).
R_DOWN = RotationMatrix(np.diag([1.0, -1.0, -1.0]))


def down(yaw: float) -> RotationMatrix:
    """TCP orientation pointing down, turned by ``yaw`` about the world z axis."""
    return RotationMatrix.MakeZRotation(yaw) @ R_DOWN


def hand_yaw_for_closing(closing_yaw: float, toward: float = 0.0) -> float:
    """The TCP yaw whose fingers close along world direction ``closing_yaw``, within pi/2 of
    ``toward`` (default: the ready yaw 0, a yaw in (-pi/2, pi/2]).

    The fingers close along the hand's y axis, which at TCP yaw psi points along psi - pi/2;
    a parallel gripper is symmetric, so psi is taken modulo pi, the one nearest ``toward``
    (the skills pass `ArmKinematics.wrist_centred_yaw`: the wrist then stays in its range).
    """
    psi = closing_yaw + math.pi / 2
    return math.remainder(toward + wrap_angle(psi - toward), 2 * math.pi)


class ArmKinematics:
    """Forward kinematics and differential IK of ``lots_arm.sdf`` (7 joints, fingers ignored)."""

    def __init__(self, period: float):
        self.plant = MultibodyPlant(0.0)
        (self.model,) = make_parser(self.plant).AddModelsFromUrl(ARM.url)
        self.plant.WeldFrames(
            self.plant.world_frame(), self.plant.GetFrameByName(ARM.base_frame, self.model)
        )
        self.plant.Finalize()
        self.context = self.plant.CreateDefaultContext()
        self.tcp = self.plant.GetFrameByName(ARM.tcp_frame, self.model)
        self.camera = self.plant.GetFrameByName(ARM.camera_frame, self.model)
        self.X_TC = self.camera.CalcPose(self.context, self.tcp)  # camera in the TCP frame
        self.params = DifferentialInverseKinematicsParameters(7, 7)
        self.params.set_time_step(period)
        self.params.set_joint_position_limits((np.array(ARM.lower), np.array(ARM.upper)))
        self.period = float(period)
        vmax = LIMIT_MARGIN * np.array(ARM.max_velocity)
        self.params.set_joint_velocity_limits((-vmax, vmax))
        self.amax = LIMIT_MARGIN * np.array(ARM.max_acceleration)
        self.params.set_joint_acceleration_limits((-self.amax, self.amax))
        self.params.set_nominal_joint_position(np.array(READY))
        self.params.set_joint_centering_gain(0.5 * np.eye(7))
        self.lower, self.upper = np.array(ARM.lower), np.array(ARM.upper)
        self.wrist = self.plant.GetJointByName(ARM.arm_joints[-1], self.model)

    def _set(self, q7: np.ndarray) -> None:
        q = self.plant.GetPositions(self.context)
        q[:7] = q7
        self.plant.SetPositions(self.context, q)

    def tcp_pose(self, q7: np.ndarray) -> RigidTransform:
        self._set(q7)
        return self.tcp.CalcPoseInWorld(self.context)

    def camera_pose(self, q7: np.ndarray) -> RigidTransform:
        self._set(q7)
        return self.camera.CalcPoseInWorld(self.context)

    def tcp_for_camera(self, X_WC: RigidTransform) -> RigidTransform:
        """The TCP pose that puts the camera at ``X_WC``."""
        return X_WC @ self.X_TC.inverse()

    def step(self, q7: np.ndarray, v7: np.ndarray, V_WT: np.ndarray) -> tuple[np.ndarray, bool]:
        """Joint velocities that move the TCP at spatial velocity ``V_WT`` ([w; v] in the
        world frame), within the limits; (v, solved). A step Drake calls stuck (a tiny
        velocity scale) is used but not solved; with no solution (the direction cannot be
        followed within the limits from ``v7``) the joints brake (`brake`)."""
        self._set(q7)
        # the position limits hold the posture the arm stands in: a joint the PD carried a
        # hair past its limit would otherwise make every step infeasible (it must move back
        # at once, faster than the acceleration limit allows), and the arm would never move
        q7 = np.asarray(q7, float)
        self.params.set_joint_position_limits(
            (np.minimum(self.lower, q7), np.maximum(self.upper, q7))
        )
        J = self.plant.CalcJacobianSpatialVelocity(
            self.context,
            JacobianWrtVariable.kV,
            self.tcp,
            np.zeros(3),
            self.plant.world_frame(),
            self.plant.world_frame(),
        )[:, :7]
        result = DoDifferentialInverseKinematics(q7, v7, V_WT, J, self.params)
        if (
            result.status == DifferentialInverseKinematicsStatus.kNoSolutionFound
            or result.joint_velocities is None
        ):
            return self.brake(v7), False
        # kStuck (the velocity scale alpha is tiny, e.g. from rest towards a far target, the
        # acceleration limit allowing one small step): still the right direction, so use it
        v = np.asarray(result.joint_velocities).reshape(-1)
        return v, result.status == DifferentialInverseKinematicsStatus.kSolutionFound

    def tcp_yaw(self, q7: np.ndarray) -> float:
        """The TCP's yaw about the world's vertical (the angle of its x axis; `down`'s yaw)."""
        R = self.tcp_pose(q7).rotation().matrix()
        return math.atan2(R[1, 0], R[0, 0])

    def wrist_centred_yaw(self, q7: np.ndarray) -> float:
        """The TCP yaw (hand pointing down) at which the last joint would sit mid-range, the
        other joints as in ``q7``: the wrist turns the hand about the vertical, so a grasp
        yaw chosen near this (`hand_yaw_for_closing`) keeps it within its +-2.9 rad."""
        yaw = self.tcp_yaw(q7)
        R_WJ = self.wrist.frame_on_parent().CalcPoseInWorld(self.context).rotation()
        up = float((R_WJ @ self.wrist.revolute_axis())[2])  # about -1: the axis points down
        k = self.wrist.position_start()
        centred = yaw + up * ((self.lower[k] + self.upper[k]) / 2 - float(q7[k]))
        return math.remainder(centred, 2 * math.pi)

    def brake(self, v7: np.ndarray) -> np.ndarray:
        """The joint velocities one period after ``v7`` when every joint decelerates towards
        rest at its (margined) acceleration limit: a controlled stop, not a jump to zero."""
        v7 = np.asarray(v7, float)
        return v7 - np.clip(v7, -self.amax * self.period, self.amax * self.period)


def pose_error(X_now: RigidTransform, X_goal: RigidTransform) -> np.ndarray:
    """[rotation vector; translation] that takes ``X_now`` to ``X_goal``, in the world frame."""
    R = X_goal.rotation() @ X_now.rotation().inverse()
    aa = RotationMatrix(R.ToQuaternion()).ToAngleAxis()  # re-orthonormalised
    return np.r_[aa.axis() * aa.angle(), X_goal.translation() - X_now.translation()]
