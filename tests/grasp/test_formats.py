"""Cornell and Jacquard file formats: round trips, conventions and precise errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tamp.errors import InputError
from tamp.grasp import formats
from tamp.grasp.rect import GraspRect, angle_difference


def test_jacquard_round_trip_and_angle_convention(tmp_path: Path):
    # Jacquard's theta is measured with y pointing down: theta = 90 means a closing
    # direction along +y in the image (down on screen), i.e. our angle -90 degrees.
    p = tmp_path / "0_a_grasps.txt"
    p.write_text("10;20;90;30;8\n15.5;25;-45;12;6\n")
    a, b = formats.read_jacquard_grasps(p)
    assert np.allclose(a.direction, [0, -1]) or np.allclose(a.direction, [0, 1])
    assert angle_difference(a.angle, -math.pi / 2) < 1e-9
    assert (a.width, a.height) == (30, 8)
    # direction (cos 45, -sin 45) * (-1) in pixels: down-right for theta = -45 -> up-right
    assert angle_difference(b.angle, math.radians(45)) < 1e-9
    text = formats.format_jacquard_grasps([a, b])
    p.write_text(text)
    again = formats.read_jacquard_grasps(p)
    assert all(r1.iou(r2) > 0.999 for r1, r2 in zip([a, b], again, strict=True))


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("1;2;3;4\n", "line 1: expected 5 fields"),
        ("1;2;3;4;5\n1;2;x;4;5\n", "line 2: not a number"),
        ("1;2;3;0;5\n", "line 1: values must be finite"),
        ("\n\n", "no grasp rectangle"),
    ],
)
def test_jacquard_errors_name_file_and_line(tmp_path: Path, content, message):
    p = tmp_path / "bad_grasps.txt"
    p.write_text(content)
    with pytest.raises(InputError) as err:
        formats.read_jacquard_grasps(p)
    assert str(p) in str(err.value) and message in str(err.value)


def test_missing_file_is_named(tmp_path: Path):
    with pytest.raises(InputError, match="nothere_grasps.txt: file not found"):
        formats.read_jacquard_grasps(tmp_path / "nothere_grasps.txt")
    with pytest.raises(InputError, match="x.tiff: file not found"):
        formats.read_depth_tiff(tmp_path / "x.tiff")
    bad = tmp_path / "bad.png"
    bad.write_text("not a png")
    with pytest.raises(InputError, match="bad.png: not a readable image"):
        formats.read_rgb(bad)


def test_cornell_rectangles_skip_nan_and_keep_opening_first(tmp_path: Path):
    p = tmp_path / "pcd0100cpos.txt"
    # first edge (0,0)->(30,0) is the opening: 30 wide, 10 jaw, horizontal
    p.write_text("0 0\n30 0\n30 10\n0 10\nNaN NaN\n1 1\n2 2\n3 3\n")
    (r,) = formats.read_cornell_grasps(p)
    assert (r.x, r.y, r.width, r.height) == (15, 5, 30, 10)
    assert angle_difference(r.angle, 0.0) < 1e-9
    same = GraspRect(r.x, r.y, r.angle, r.width, r.height)
    assert GraspRect.from_corners(same.corners()).iou(r) > 0.999


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("0 0\n30 0\n30 10\n", "line 3: 3 corner lines is not a multiple of 4"),
        ("0 0\n30 0 1\n30 10\n0 10\n", "line 2: expected 'x y'"),
        ("0 0\n30 a\n30 10\n0 10\n", "line 2: not a number"),
    ],
)
def test_cornell_errors(tmp_path: Path, content, message):
    p = tmp_path / "pcd0101cpos.txt"
    p.write_text(content)
    with pytest.raises(InputError) as err:
        formats.read_cornell_grasps(p)
    assert str(p) in str(err.value) and message in str(err.value)


def test_cornell_point_cloud_depth(tmp_path: Path):
    depth = np.zeros((4, 5), np.float32)
    depth[1, 2] = 0.6
    depth[3, 4] = 0.55
    p = tmp_path / "pcd0100.txt"
    formats.write_cornell_pcd(p, depth)
    back = formats.read_cornell_pcd(p, (4, 5))
    assert np.allclose(back, depth, atol=1e-6)
    # the depth is the point's distance from the camera, in metres (file in millimetres)
    p.write_text("VERSION .7\nFIELDS x y z rgb index\nDATA ascii\n300 400 0 0 7\n")
    assert math.isclose(formats.read_cornell_pcd(p, (4, 5))[1, 2], 0.5, rel_tol=1e-6)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("DATA ascii\n1 2 3 4\n", "line 2: expected 5 fields"),
        ("DATA ascii\n1 2 3 4 99\n", "line 2: pixel index 99 outside"),
        ("DATA ascii\n1 2 z 4 1\n", "line 2: not a number"),
        ("HELLO 1\n", "line 1: unknown PCD header entry"),
        ("# only a comment\n", "no 'DATA ascii' header"),
    ],
)
def test_point_cloud_errors(tmp_path: Path, content, message):
    p = tmp_path / "pcd0100.txt"
    p.write_text(content)
    with pytest.raises(InputError) as err:
        formats.read_cornell_pcd(p, (4, 5))
    assert str(p) in str(err.value) and message in str(err.value)
