"""Pinhole camera geometry without Drake or torch: the grasp network's pixels, the workcells'
detections and the safety monitor's hand points become 3-D points through `pixel_to_camera`
(`tamp.sim.core.camera.backproject` adds the camera pose), and 3-D points become pixels
through `camera_to_pixel` (synthetic grasp labels, perception's occlusion test)."""

from __future__ import annotations

import numpy as np


def pixel_to_camera(u, v, z, intrinsics) -> np.ndarray:
    """The pinhole back-projection: pixel (u, v) at depth ``z`` (along the optical axis) as a
    point in the camera frame (+z forward, +x right, +y down). Scalars give a 3-vector, arrays
    of N pixels a 3 x N matrix; ``z = 1`` gives the pixels' viewing rays. The one place of this
    formula (cameras, grasps, safety, free table spots)."""
    fx, fy, cx, cy = intrinsics
    return np.array([(u - cx) * z / fx, (v - cy) * z / fy, z])


def camera_to_pixel(p_C, intrinsics) -> tuple:
    """The pinhole projection, inverse of `pixel_to_camera`: a camera-frame point (3-vector,
    or a 3 x N matrix of points) as pixel coordinates (u, v), scalars or arrays. Points must
    be in front of the camera (z > 0)."""
    fx, fy, cx, cy = intrinsics
    x, y, z = np.asarray(p_C, float)
    return fx * x / z + cx, fy * y / z + cy
