"""Pinhole camera geometry without Drake or torch: the grasp network's pixels, the workcells'
detections and the safety monitor's hand pixels all become 3-D points through this one
function (`tamp.sim.core.camera.backproject` adds the camera pose)."""

from __future__ import annotations

import numpy as np


def pixel_to_camera(u, v, z, intrinsics) -> np.ndarray:
    """The pinhole back-projection: pixel (u, v) at depth ``z`` (along the optical axis) as a
    point in the camera frame (+z forward, +x right, +y down). Scalars give a 3-vector, arrays
    of N pixels a 3 x N matrix. The one place of this formula (cameras, grasps, safety)."""
    fx, fy, cx, cy = intrinsics
    return np.array([(u - cx) * z / fx, (v - cy) * z / fy, z])
