"""Rectangle geometry and the rectangle metric (IoU > 0.25, angle <= 30 degrees)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from tamp.grasp.rect import GraspRect, angle_difference, is_correct, wrap_angle

coords = st.floats(0, 200, allow_nan=False)
sizes = st.floats(2, 80, allow_nan=False)
angles = st.floats(-4, 4, allow_nan=False)
rects = st.builds(GraspRect, coords, coords, angles, sizes, sizes)


def test_iou_of_known_overlaps():
    a = GraspRect(10, 10, 0.0, 20, 10)
    assert math.isclose(a.iou(a), 1.0)
    # shifted by half the width: intersection 10x10 = 100, union 300
    assert math.isclose(a.iou(GraspRect(20, 10, 0.0, 20, 10)), 1 / 3)
    assert a.iou(GraspRect(100, 100, 0.0, 20, 10)) == 0.0
    # a square turned by 90 degrees is the same square
    s = GraspRect(0, 0, 0.3, 10, 10)
    assert math.isclose(s.iou(GraspRect(0, 0, 0.3 + math.pi / 2, 10, 10)), 1.0)


def test_cross_shaped_overlap():
    # two 30x10 bars crossing at right angles: intersection 10x10, union 500
    a = GraspRect(0, 0, 0.0, 30, 10)
    b = GraspRect(0, 0, math.pi / 2, 30, 10)
    assert math.isclose(a.iou(b), 100 / 500)


@given(rects, rects)
def test_iou_symmetric_and_bounded(a, b):
    x, y = a.iou(b), b.iou(a)
    assert 0.0 <= x <= 1.0 + 1e-9
    assert math.isclose(x, y, abs_tol=1e-9)


@given(rects)
def test_corners_round_trip(r):
    back = GraspRect.from_corners(r.corners())
    assert np.allclose([back.x, back.y, back.width, back.height], [r.x, r.y, r.width, r.height])
    assert angle_difference(back.angle, r.angle) < 1e-9


@given(angles)
def test_wrap_and_half_turn_symmetry(a):
    w = wrap_angle(a)
    assert -math.pi / 2 <= w < math.pi / 2
    assert angle_difference(a, a + math.pi) < 1e-9


def test_metric_thresholds():
    truth = GraspRect(50, 50, 0.0, 40, 20)
    assert GraspRect(50, 50, math.radians(29), 40, 20).matches(truth)
    assert not GraspRect(50, 50, math.radians(31), 40, 20).matches(truth)
    assert GraspRect(50, 50, math.radians(-29 + 180), 40, 20).matches(truth)
    # IoU just above and below 0.25 at equal angle: shifted along the width
    # overlap (40 - s) * 20 / (2 * 800 - (40 - s) * 20) > 0.25  <=>  s < 24
    assert GraspRect(50 + 23, 50, 0.0, 40, 20).matches(truth)
    assert not GraspRect(50 + 25, 50, 0.0, 40, 20).matches(truth)
    assert is_correct([GraspRect(50, 50, 0.1, 40, 20)], [GraspRect(0, 0, 0, 5, 5), truth])
    assert not is_correct([], [truth])
