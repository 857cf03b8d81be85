"""Grasps in pixels and in the world frame: the call the robot makes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tamp.grasp.maps import WIDTH_SCALE
from tamp.grasp.predict import GraspPredictor, to_world
from tamp.grasp.rect import GraspRect, angle_difference
from tamp.grasp.synthetic import look_at, project

F, C = 120.0, 63.5


def _camera(x, y, h, yaw):
    X = np.eye(4)
    X[:3, :3] = look_at(np.array([x, y, h]), np.array([x, y, 0.0]), yaw)
    X[:3, 3] = [x, y, h]
    return X


@given(
    st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(0.25, 0.5), st.floats(-3, 3),
    st.floats(-0.08, 0.08), st.floats(-0.08, 0.08), st.floats(-1.5, 1.5), st.floats(0.01, 0.08),
)  # fmt: skip
def test_pixel_grasp_to_world(x, y, h, cam_yaw, dx, dy, grasp_yaw, opening):
    """Oracle: project a world grasp on the table into a top-down camera, then back."""
    K = np.array([[F, 0, C], [0, F, C], [0, 0, 1]])
    X = _camera(x, y, h, cam_yaw)
    centre = np.array([x + dx, y + dy, 0.0])
    ends = centre + np.array([[-1, 1]]).T * opening / 2 * [
        math.cos(grasp_yaw),
        math.sin(grasp_yaw),
        0,
    ]
    (u, v), (ua, va), (ub, vb) = project(K, X, np.vstack([centre, ends]))
    rect = GraspRect(u, v, math.atan2(-(vb - va), ub - ua), math.hypot(ub - ua, vb - va), 5)
    depth = np.full((128, 128), h, np.float32)  # the table plane seen from straight above
    pos, yaw, width = to_world(rect, depth, (F, F, C, C), X)
    assert np.allclose(pos, centre, atol=1e-6)
    assert angle_difference(yaw, grasp_yaw) < 1e-6
    assert math.isclose(width, opening, rel_tol=1e-6)


class _PeakModel:
    """A stand-in network: quality peak at a fixed input pixel, fixed angle and width."""

    def __init__(self, size, row, col, angle, width):
        import torch

        self.out = torch.zeros(1, 4, size, size)
        self.out[0, 0, row - 2 : row + 3, col - 2 : col + 3] = 1.0
        self.out[0, 1] = math.cos(2 * angle)
        self.out[0, 2] = math.sin(2 * angle)
        self.out[0, 3] = width / WIDTH_SCALE

    def __call__(self, x):
        return self.out.expand(x.shape[0], -1, -1, -1)


def test_predictor_maps_back_to_the_original_pixels():
    # a 200x160 image: the central 160x160 square is resized to the 80 px network input
    model = _PeakModel(80, row=20, col=60, angle=0.4, width=10)
    pred = GraspPredictor(model, {"input": "d", "size": 80})
    (g,) = pred.predict(depth=np.full((160, 200), 0.5, np.float32))
    assert math.isclose(g.u, 20 + 60 * 2 + 0.5, abs_tol=0.6)
    assert math.isclose(g.v, 20 * 2 + 0.5, abs_tol=0.6)
    assert math.isclose(g.width_px, 20, rel_tol=0.1)
    assert angle_difference(g.angle, 0.4) < 0.02
    assert g.position is None


def test_predictor_needs_the_right_images():
    from tamp.errors import InputError

    pred = GraspPredictor(_PeakModel(32, 10, 10, 0, 5), {"input": "rgbd", "size": 32})
    with pytest.raises(InputError, match="depth image is needed"):
        pred.predict(rgb=np.zeros((32, 32, 3), np.uint8))
    with pytest.raises(InputError, match="RGB image is needed"):
        pred.predict(depth=np.zeros((32, 32), np.float32))
