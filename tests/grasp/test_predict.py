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


class _BlobModel:
    """A stand-in network whose quality falls off smoothly from one input pixel over the
    whole image (so the order of its peaks is defined), angle 0, width 8 px; counts calls."""

    def __init__(self, size, row, col, spread=12.0):
        import torch

        ys, xs = torch.meshgrid(torch.arange(size), torch.arange(size), indexing="ij")
        r2 = ((ys - row) ** 2 + (xs - col) ** 2).float()
        self.out = torch.zeros(1, 4, size, size)
        self.out[0, 0] = torch.exp(-r2 / (2 * spread**2))
        self.out[0, 1] = 1.0
        self.out[0, 3] = 8 / WIDTH_SCALE
        self.calls = 0

    def __call__(self, x):
        self.calls += 1
        return self.out.expand(x.shape[0], -1, -1, -1)


def _hole(depth, row, col, radius, value=np.nan):
    ys, xs = np.mgrid[0 : depth.shape[0], 0 : depth.shape[1]]
    out = depth.copy()
    out[(ys - row) ** 2 + (xs - col) ** 2 <= radius**2] = value
    return out


TABLE = np.full((64, 64), 0.6, np.float32)
DOWN = np.array([[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 0.6], [0, 0, 0, 1]], float)
K64 = (80.0, 80.0, 31.5, 31.5)


@pytest.mark.parametrize(
    "fill, message",
    [(np.nan, "4096 holes"), (0.0, "holes (0 or NaN)"), (-0.6, "have negative depth"),
     (7.0, "farther than 5 m")],
)  # fmt: skip
def test_no_valid_depth_gives_no_grasp_and_the_reason(fill, message):
    """All NaN, all zero, all negative, all beyond the range: the network is not even run."""
    model = _BlobModel(64, 32, 32)
    pred = GraspPredictor(model, {"input": "d", "size": 64})
    found = pred.detect(depth=np.full((64, 64), fill, np.float32), intrinsics=K64, X_WC=DOWN)
    assert found.grasps == [] and message in found.reason and model.calls == 0
    assert pred.predict(depth=np.full((64, 64), fill, np.float32)) == []


def test_partly_invalid_depth_still_grasps_the_object_on_valid_depth():
    """Half the image NaN, a strip of zeros: the peak stands on measured depth and is kept."""
    depth = TABLE.copy()
    depth[:, :24] = np.nan
    depth[:6] = 0.0
    pred = GraspPredictor(_BlobModel(64, 32, 44), {"input": "d", "size": 64})
    found = pred.detect(depth=depth, intrinsics=K64, X_WC=DOWN, n=2)
    assert found.reason is None and len(found.grasps) == 2
    g = found.grasps[0]
    assert abs(g.u - 44) < 1 and abs(g.v - 32) < 1 and g.quality > 0.9
    assert g.position[2] == pytest.approx(0.0, abs=1e-6)  # the table, seen from 0.6 m
    assert found.depth.valid_count == 64 * 40 - 6 * 40


@pytest.mark.parametrize("value", [np.nan, 0.0, 9.0, 0.01])
def test_a_peak_on_invalid_depth_is_passed_over(value):
    """A small hole (or depth beyond the range) under the best peak: the best grasp on
    valid depth comes back instead, off the hole."""
    depth = _hole(TABLE, 32, 32, 4, value)
    pred = GraspPredictor(_BlobModel(64, 32, 32), {"input": "d", "size": 64})
    (g,) = pred.predict(depth=depth, intrinsics=K64, X_WC=DOWN)
    assert math.hypot(g.u - 32, g.v - 32) > 4 and g.quality < 1.0
    assert all(math.isfinite(v) for v in g.position)


def test_no_grasp_where_the_best_peaks_all_lie_on_invalid_depth():
    """A hole over everything the network rates best: no grasp, and why."""
    depth = _hole(TABLE, 32, 32, 20)
    pred = GraspPredictor(_BlobModel(64, 32, 32), {"input": "d", "size": 64})
    found = pred.detect(depth=depth, n=3)
    assert found.grasps == []
    assert "best grasps lie on invalid depth" in found.reason and "holes" in found.reason


def test_the_range_is_the_predictor_s():
    from tamp.grasp.depth import DepthRange

    near = GraspPredictor(
        _BlobModel(64, 32, 32), {"input": "d", "size": 64}, depth_range=DepthRange(0.05, 0.5)
    )
    assert "farther than 0.5 m" in near.detect(depth=TABLE).reason


def test_no_made_up_depth_for_the_world_point():
    """Without valid depth around the grasp pixel the world point is NaN, not the image's
    median (the robot would reach for a point nobody measured)."""
    depth = _hole(TABLE, 10, 10, 5)
    pos, _, _ = to_world(GraspRect(10, 10, 0.0, 8, 4), depth, K64, DOWN)
    assert all(math.isnan(v) for v in pos)
