"""Coordinate transforms from the person's mixed-reality frame to the robot frame (§IV-A).

The MR layer (HoloLens 2 / Unity) is left-handed with y up; the robot frame is right-handed
with z up. A point ``p_u`` in the user frame reaches the robot frame in two steps:

1. eq. (1)–(3): ``p_rn = R (p_u − uP_r)``, the point relative to the robot's position
   ``uP_r`` in the user frame, rotated by ``R`` (the paper assumes aligned frames, R = I,
   where this is exactly ``T^u_rn [p_u; 1]`` with ``T = [R, −uP_r; 0, 1]``; for R ≠ I we
   subtract before rotating, which is the correct inverse of a rigid transform);
2. eq. (4)–(5): ``p_r = A p_rn`` with the handedness matrix ``A``.

The default ``A`` is the Unity→ROS conversion used by ROS#: robot x = user z,
robot y = −user x, robot z = user y.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tamp.world.geometry import Point

UNITY_TO_ROS = ((0.0, 0.0, 1.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@dataclass(frozen=True)
class MRFrame:
    """The robot's pose in the user's MR frame plus the handedness matrix ``A``."""

    robot_position: tuple[float, float, float]
    rotation: tuple[tuple[float, ...], ...] = IDENTITY
    handedness: tuple[tuple[float, ...], ...] = UNITY_TO_ROS

    def homogeneous(self) -> np.ndarray:
        """``T^u_rn`` of eq. (1), generalised to R ≠ I as ``[R, −R uP_r; 0, 1]``."""
        R = np.asarray(self.rotation, dtype=float)
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = -R @ np.asarray(self.robot_position, dtype=float)
        return T

    def to_robot(self, p_user: tuple[float, float, float]) -> Point:
        """eq. (2)/(3) then eq. (4)/(5): a user-frame point in the robot frame."""
        p = self.homogeneous() @ np.array([*p_user, 1.0])
        x, y, z = np.asarray(self.handedness, dtype=float) @ p[:3]
        return Point(float(x), float(y), float(z))


def check_rotation(m: np.ndarray, *, proper: bool) -> str | None:
    """Why ``m`` is not an orthonormal 3×3 matrix (det +1, or ±1 when not ``proper``)."""
    if m.shape != (3, 3):
        return "must be a 3x3 matrix"
    if not np.allclose(m @ m.T, np.eye(3), atol=1e-6):
        return "must be orthonormal (M Mᵀ = I)"
    det = float(np.linalg.det(m))
    if proper and det < 0:
        return "must be a rotation (det = +1)"
    if not np.isclose(abs(det), 1.0, atol=1e-6):
        return "must have determinant ±1"
    return None
