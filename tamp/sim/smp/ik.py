"""Arm configurations from Drake's `InverseKinematics` for top grasps and placements.

The solver works on a robot-only plant (the same SDF), with the base and finger joints
fixed at their measured values, so only the five arm joints move. A top grasp puts the
palm's z axis straight down (the youBot's usual way to pick from the floor); the wrist roll
(joint 5) matches the object's yaw so that the weld switched on at the grasp pose does not
turn the object (see `grasp_rotation`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.inverse_kinematics import InverseKinematics
from pydrake.multibody.plant import MultibodyPlant
from pydrake.solvers import Solve

from tamp.sim.core.parsing import make_parser
from tamp.sim.smp.robot import ROBOT, ObjectKind


def grasp_rotation(variant: int) -> RotationMatrix:
    """R_GO: the object's frame in the palm frame G for weld ``variant`` (0 or 1).

    The object's z axis points against the palm's z axis (palm points down, object up);
    variant 1 is variant 0 turned by pi about the object's axis.
    """
    return RotationMatrix(RollPitchYaw(math.pi, 0.0, 0.0)).multiply(
        RotationMatrix.MakeZRotation(math.pi * variant)
    )


def grasp_transform(kind: ObjectKind, variant: int) -> RigidTransform:
    """X_GO: the object's pose in the palm frame when grasped (the weld's fixed offset)."""
    return RigidTransform(
        grasp_rotation(variant), [0.0, 0.0, ROBOT.grasp_offset + kind.grasp_height]
    )


@dataclass
class IkResult:
    q_arm: np.ndarray
    variant: int


class ArmIK:
    """Solves for the 5 arm joints given the measured robot configuration."""

    def __init__(self) -> None:
        self.plant = MultibodyPlant(0.0)
        parser = make_parser(self.plant)
        parser.AddModelsFromUrl(ROBOT.url)
        self.plant.Finalize()
        self.context = self.plant.CreateDefaultContext()
        self.index = {
            name: self.plant.GetJointByName(name).position_start() for name in ROBOT.joints
        }
        self.arm = [self.index[n] for n in ROBOT.arm_joints]
        self.fixed = [self.index[n] for n in ROBOT.base_joints + ROBOT.finger_joints]
        self.palm = self.plant.GetBodyByName(ROBOT.palm_body).body_frame()
        self.world = self.plant.world_frame()

    def _q_full(self, q_robot: np.ndarray) -> np.ndarray:
        q = np.zeros(self.plant.num_positions())
        for k, name in enumerate(ROBOT.joints):
            q[self.index[name]] = q_robot[k]
        return q

    def solve(
        self,
        q_robot: np.ndarray,
        point: np.ndarray,
        *,
        R_WG: RotationMatrix | None = None,
        nominal_arm: np.ndarray | None = None,
        pos_tol: float = 0.002,
    ) -> np.ndarray | None:
        """Arm joints putting the grasp point at ``point`` with the palm pointing down.

        ``R_WG`` also fixes the palm's yaw; without it the wrist stays near ``nominal_arm``.
        Returns None when no solution within the joint limits exists.
        """
        q_now = self._q_full(q_robot)
        ik = InverseKinematics(self.plant, self.context, with_joint_limits=True)
        q = ik.q()
        prog = ik.get_mutable_prog()
        for i in self.fixed:
            prog.AddBoundingBoxConstraint(q_now[i], q_now[i], q[i])
        p = np.asarray(point, float)
        ik.AddPositionConstraint(
            self.palm, [0.0, 0.0, ROBOT.grasp_offset], self.world, p - pos_tol, p + pos_tol
        )
        if R_WG is not None:
            ik.AddOrientationConstraint(self.world, R_WG, self.palm, RotationMatrix(), 0.01)
        else:
            ik.AddAngleBetweenVectorsConstraint(
                self.world, [0.0, 0.0, -1.0], self.palm, [0.0, 0.0, 1.0], 0.0, 0.01
            )
        # aim the arm plane at the point, elbow up: a good seed and the nominal posture
        X_WB = RigidTransform(RotationMatrix.MakeZRotation(q_robot[2]), [*q_robot[:2], 0.0])
        p_B = X_WB.inverse().multiply(p)
        aim = math.atan2(p_B[1], p_B[0] - 0.143)
        base_nominal = np.array([aim, 0.6, 1.0, 1.5, q_robot[7]])
        nom = base_nominal if nominal_arm is None else np.asarray(nominal_arm, float)
        q_nom = q_now.copy()
        q_nom[self.arm] = nom
        weights = np.zeros(len(q_now))
        weights[self.arm] = [1.0, 0.1, 0.1, 0.1, 1.0]
        prog.AddQuadraticErrorCost(np.diag(weights), q_nom, q)
        best = None
        seeds = (nom, base_nominal, np.array([aim, 0.9, 0.6, 1.6, 0.0]), q_robot[3:8])
        for seed in seeds:
            guess = q_now.copy()
            guess[self.arm] = seed
            prog.SetInitialGuess(q, guess)
            result = Solve(prog)
            if result.is_success():
                best = result.GetSolution(q)[self.arm]
                break
        return best

    def grasp(self, q_robot: np.ndarray, X_WO: RigidTransform, kind: ObjectKind) -> IkResult | None:
        """Arm joints for a top grasp of an upright object at ``X_WO`` (weld variant chosen
        so that the wrist turns least)."""
        yaw = RollPitchYaw(X_WO.rotation()).yaw_angle()
        point = X_WO.translation() + [0.0, 0.0, kind.grasp_height]
        out = []
        for v in (0, 1):
            R_WG = RotationMatrix.MakeZRotation(yaw).multiply(grasp_rotation(v).transpose())
            q = self.solve(q_robot, point, R_WG=R_WG)
            if q is not None:
                out.append(IkResult(q, v))
        if not out:
            return None
        return min(out, key=lambda r: abs(r.q_arm[4] - q_robot[7]))
