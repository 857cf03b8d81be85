"""Depth validity: which pixels are measured, how holes are filled, where a grasp may stand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tamp.errors import InputError
from tamp.grasp.depth import (
    DEFAULT_DEPTH_RANGE,
    MIN_VALID_SHARE,
    NEGATIVE_TOLERANCE,
    DepthRange,
    check_depth,
    fill_invalid,
    fill_invalid_depth,
    on_valid_depth,
    valid_depth,
    valid_share,
)
from tamp.grasp.rect import GraspRect


def test_the_command_line_default_is_the_library_default():
    from tamp.commands.grasp import DEPTH_RANGE

    assert DepthRange.parse(DEPTH_RANGE) == DEFAULT_DEPTH_RANGE


@pytest.mark.parametrize(
    "text, message",
    [("abc", "expected MIN,MAX"), ("1", "expected MIN,MAX"), ("1,2,3", "expected MIN,MAX"),
     ("1,0.5", "0 < MIN < MAX"), ("0,1", "0 < MIN < MAX"), ("0.1,inf", "finite"),
     ("nan,1", "finite")],
)  # fmt: skip
def test_bad_ranges_name_the_flag(text, message):
    with pytest.raises(InputError, match=message) as err:
        DepthRange.parse(text)
    assert err.value.field == "--depth-range"


def test_valid_pixels_are_finite_and_inside_the_range():
    d = np.array([[0.0, np.nan, np.inf, -np.inf], [-0.3, 0.01, 0.05, 0.6], [5.0, 5.1, 600, 2]])
    r = DepthRange(0.05, 5.0)
    expected = [[0, 0, 0, 0], [0, 0, 1, 1], [1, 0, 0, 1]]
    assert valid_depth(d, r).tolist() == np.array(expected, bool).tolist()
    c = check_depth(d, r)
    assert (c.holes, c.negative, c.near, c.far, c.valid_count) == (4, 1, 1, 2, 4)
    assert c.negative > NEGATIVE_TOLERANCE * c.pixels
    assert "1 of 12 pixels have negative depth" in c.problem()


@pytest.mark.parametrize(
    "fill, message",
    [(np.nan, "no valid depth: 0 of 64 pixels in 0.05-5 m, 64 holes (0 or NaN)"),
     (0.0, "64 holes"), (np.inf, "64 holes"), (7.0, "64 farther than 5 m"),
     (0.01, "64 nearer than 0.05 m"), (-0.6, "64 of 64 pixels have negative depth")],
)  # fmt: skip
def test_an_image_without_valid_depth_is_bad_input(fill, message):
    problem = check_depth(np.full((8, 8), fill, np.float32)).problem()
    assert problem is not None and message in problem


def test_millimetres_are_named():
    problem = check_depth(np.full((8, 8), 600.0)).problem()
    assert "values near 600 look like millimetres" in problem
    assert "millimetres" not in check_depth(np.full((8, 8), 7.0)).problem()


def test_a_few_negative_pixels_are_holes_many_are_bad_input():
    d = np.full((20, 20), 0.6, np.float32)
    d[0, :4] = -0.001  # 4 of 400 pixels: 1 %, filter noise at a hole's border
    c = check_depth(d)
    assert c.problem() is None and c.valid_count == 396
    d[0, 4] = -0.001  # 5 of 400: more than 1 %
    assert "5 of 400 pixels have negative depth" in check_depth(d).problem()


def test_holes_take_the_depth_of_the_nearest_valid_pixel():
    d = np.full((5, 7), 0.6, np.float32)
    d[:, 4:] = 0.5
    d[1:4, 2:5] = np.nan  # a hole across the step
    out = fill_invalid_depth(d)
    assert np.isfinite(out).all() and out.dtype == np.float32
    assert out[2, 2] == pytest.approx(0.6) and out[2, 4] == pytest.approx(0.5)
    untouched = np.isfinite(d)
    assert np.array_equal(out[untouched], d[untouched])
    assert not fill_invalid(d, np.zeros(d.shape, bool)).any()  # nothing valid: zeros


def test_a_grasp_stands_on_valid_depth_by_its_centre_and_most_of_its_rectangle():
    valid = np.ones((40, 40), bool)
    rect = GraspRect(20, 20, 0.0, 10, 4)  # closing along u, 10 px wide, 4 px jaws
    assert valid_share(rect, valid) == 1.0 and on_valid_depth(rect, valid)
    valid[20, 20] = False
    assert not on_valid_depth(rect, valid)  # centre on a hole
    valid[:] = True
    valid[:, 21:] = False  # the right half of the rectangle on invalid depth
    share = valid_share(rect, valid)
    assert 0.4 < share < MIN_VALID_SHARE + 0.1
    valid[:, 19:] = False
    valid[20, 20] = True
    assert valid_share(rect, valid) < MIN_VALID_SHARE and not on_valid_depth(rect, valid)
    assert valid_share(GraspRect(-50, -50, 0.0, 4, 2), valid) == 0.0  # outside the image


def test_range_describes_itself():
    assert DepthRange(0.05, 5.0).describe() == "0.05-5 m"
    assert math.isclose(DEFAULT_DEPTH_RANGE.near, 0.05)
