"""MR-frame messages ↔ the demonstration file's coordinates (SMP-MRO §IV-A, eq. 1–5).

A demonstration file holds positions in the person's raw Unity frame (left-handed, y up);
the loader (`tamp.demo.loader`) maps them to the robot frame with ``p_r = A R (p_u − uP_r)``.
MR apps built on ROS# send positions already passed through ``Unity2Ros`` (the ``A`` of
eq. 4–5, `tamp.demo.frames.UNITY_TO_ROS`): x, y, z = z_u, −x_u, y_u, in a frame we call
``mr``. This module maps such messages back to the file's coordinates (``Aᵀ``, exact: ``A``
permutes axes and flips a sign), so a live session and its exported YAML are one
demonstration, byte for byte, and maps robot-frame results forward to ``mr`` for display.

``header.frame_id``: ``""``, ``"mr"`` or ``"Unity"`` (ROS#'s default, whose data is already
converted) mean ROS convention in the MR frame; ``"unity_lh"`` means raw Unity coordinates.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tamp.demo.frames import UNITY_TO_ROS, MRFrame

ROS_FRAMES = ("", "mr", "Unity")
RAW_FRAME = "unity_lh"

_A = np.asarray(UNITY_TO_ROS, dtype=float)


class MessageError(ValueError):
    """A field of a message that cannot be used: ``field: reason``."""

    def __init__(self, field: str, reason: str):
        super().__init__(f"{field}: {reason}")
        self.field = field


def number(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MessageError(field, "expected a number")
    v = float(value)
    if not math.isfinite(v):
        raise MessageError(field, "expected a finite number")
    return v


def frame_of(msg: dict[str, Any], field: str = "header.frame_id") -> str:
    header = msg.get("header") or {}
    if not isinstance(header, dict):
        raise MessageError("header", "expected a mapping")
    frame = header.get("frame_id", "") or ""
    if frame not in (*ROS_FRAMES, RAW_FRAME):
        raise MessageError(field, f"unknown frame {str(frame)[:40]!r} (known: mr, Unity, unity_lh)")
    return frame


def point(value: Any, field: str) -> tuple[float, float, float]:
    """A ``geometry_msgs/Point`` (missing coordinates are 0, as in ROS messages)."""
    if not isinstance(value, dict):
        raise MessageError(field, "expected a point {x, y, z}")
    return tuple(number(value.get(k, 0.0), f"{field}.{k}") for k in "xyz")  # type: ignore[return-value]


def to_file(p: tuple[float, float, float], frame: str) -> list[float]:
    """A point of a message in the file's raw Unity coordinates (``Aᵀ p`` unless raw)."""
    if frame == RAW_FRAME:
        return [float(v) for v in p]
    return [float(v) + 0.0 for v in _A.T @ np.asarray(p, dtype=float)]


def to_mr(p_user: list[float]) -> list[float]:
    """File (raw Unity) coordinates → ``mr`` (``Unity2Ros``), for display."""
    return [float(v) + 0.0 for v in _A @ np.asarray(p_user, dtype=float)]


def robot_to_mr(frame: MRFrame, p_robot: tuple[float, float, float]) -> list[float]:
    """Inverse of eq. (1)–(5): ``p_u = Rᵀ Aᵀ p_r + uP_r``, then ``Unity2Ros``."""
    R = np.asarray(frame.rotation, dtype=float)
    A = np.asarray(frame.handedness, dtype=float)
    p_u = R.T @ np.linalg.inv(A) @ np.asarray(p_robot, dtype=float) + np.asarray(
        frame.robot_position, dtype=float
    )
    return [round(float(v), 6) + 0.0 for v in _A @ p_u]


def rotation_of(q: Any, frame: str, field: str) -> list[list[float]] | None:
    """The ``R`` of eq. (1) for the robot's orientation ``q`` in the MR frame (None: R = I).

    With ``Q`` the robot's axes in ``mr`` (ROS convention), ``p_r = Qᵀ (p_mr − P_mr)`` and
    ``p_mr = A p_u`` give ``A R = Qᵀ A``, so ``R = Aᵀ Qᵀ A``. A missing or all-zero
    quaternion is the identity (ROS's default message); a non-unit one is refused.
    """
    if q is None:
        return None
    if not isinstance(q, dict):
        raise MessageError(field, "expected a quaternion {x, y, z, w}")
    x, y, z = (number(q.get(k, 0.0), f"{field}.{k}") for k in "xyz")
    w = number(q.get("w", 0.0), f"{field}.w")
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n == 0.0 or (abs(x) + abs(y) + abs(z) == 0.0 and w > 0):
        return None
    if abs(n - 1.0) > 1e-3:
        raise MessageError(field, f"not a unit quaternion (norm {n:.4g})")
    if frame == RAW_FRAME:
        raise MessageError(field, "a rotated robot must be given in the mr frame")
    x, y, z, w = x / n, y / n, z / n, w / n
    Q = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    R = _A.T @ Q.T @ _A
    return [[round(float(v), 12) + 0.0 for v in row] for row in R]


def pose_stamped(p_mr: list[float], yaw: float = 0.0, frame_id: str = "mr") -> dict[str, Any]:
    """A ``geometry_msgs/PoseStamped`` at ``p_mr`` turned by ``yaw`` about the MR z axis."""
    now = stamp()
    return {
        "header": {"frame_id": frame_id, "stamp": now},
        "pose": {
            "position": dict(zip("xyz", p_mr, strict=True)),
            "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)},
        },
    }


def stamp() -> dict[str, int]:
    """Now, in both the ROS 1 (secs, nsecs) and ROS 2 (sec, nanosec) spellings."""
    import time

    t = time.time()
    s, ns = int(t), int((t % 1) * 1e9)
    return {"secs": s, "nsecs": ns, "sec": s, "nanosec": ns}
