"""Instances from a class map and depth: components per class, split at depth jumps, small
fragments merged back, world-frame points and centroids, low scores reported as unknown."""

from __future__ import annotations

import numpy as np
import pytest

from tamp.sim.core.instances import (
    ObjectDetection,
    backproject_mask,
    depth_jumps,
    extract,
    split_at_jumps,
)

NAMES = ("background", "table", "block", "unknown", "hand")
INTR = (100.0, 100.0, 40.0, 30.0)  # fx, fy, cx, cy of an 80 x 60 image


def _probs(cls_map: np.ndarray, p: float = 0.9) -> np.ndarray:
    """One-hot-ish probabilities: ``p`` on each pixel's class, the rest spread evenly."""
    n = len(NAMES)
    probs = np.full((n, *cls_map.shape), (1 - p) / (n - 1), np.float32)
    for c in range(n):
        probs[c][cls_map == c] = p
    return probs


def _scene(second_height: float):
    """A table at 0.5 m and two touching 'block' patches, the second ``second_height``
    nearer than the first (0.03 m above the table)."""
    depth = np.full((60, 80), 0.5, np.float32)
    cls_map = np.ones((60, 80), int)
    cls_map[20:40, 10:30] = 2
    depth[20:40, 10:30] = 0.47
    cls_map[20:40, 30:50] = 2
    depth[20:40, 30:50] = 0.47 - second_height
    return cls_map, depth


def test_touching_objects_of_one_class_split_where_depth_jumps():
    cls_map, depth = _scene(0.03)
    found = extract(_probs(cls_map), depth, NAMES, [2, 3, 4], INTR, np.eye(4))
    assert sorted(d.pixels for d in found) == [400, 400]
    assert {d.cls for d in found} == {"block"}


def test_touching_objects_of_one_class_at_one_height_stay_one_instance():
    cls_map, depth = _scene(0.0)
    found = extract(_probs(cls_map), depth, NAMES, [2, 3, 4], INTR, np.eye(4))
    assert [d.pixels for d in found] == [800]


def test_a_thin_strip_beyond_a_jump_goes_back_to_its_object():
    """A box's steep side seen edge-on is a strip of a few pixels beyond a depth jump: it is
    part of the box, not an instance of its own."""
    depth = np.full((60, 80), 0.5, np.float32)
    cls_map = np.ones((60, 80), int)
    cls_map[20:32, 10:31] = 2
    depth[20:32, 10:30] = 0.45
    depth[20:32, 30] = 0.48  # the side: 1 px wide, 3 cm deeper (12 px: below the size rule)
    found = extract(_probs(cls_map), depth, NAMES, [2, 3, 4], INTR, np.eye(4))
    assert [d.pixels for d in found] == [252]


def test_low_scores_are_reported_unknown_and_small_blobs_dropped():
    cls_map, depth = _scene(0.03)
    probs = _probs(cls_map, p=0.3)
    cls_map[50:52, 60:62] = 2  # 4 px: below the size rule
    found = extract(probs, depth, NAMES, [2, 3, 4], INTR, np.eye(4), unknown_below=0.5)
    assert {d.cls for d in found} == {"unknown"} and len(found) == 2


def test_touching_objects_of_two_classes_at_one_height_split_by_class():
    cls_map, depth = _scene(0.0)
    cls_map[20:40, 30:50] = 3  # the second patch is 'unknown'
    found = extract(_probs(cls_map), depth, NAMES, [2, 3, 4], INTR, np.eye(4))
    assert sorted((d.cls, d.pixels) for d in found) == [("block", 400), ("unknown", 400)]
    cls_map[28:31, 38:41] = 2  # a flicker of 'block' inside the second object
    found = extract(_probs(cls_map), depth, NAMES, [2, 3, 4], INTR, np.eye(4))
    assert sorted(d.cls for d in found) == ["block", "unknown"]


def test_a_class_flickering_inside_one_object_does_not_split_it():
    depth = np.full((60, 80), 0.5, np.float32)
    cls_map = np.ones((60, 80), int)
    cls_map[20:40, 10:30] = 2
    depth[20:40, 10:30] = 0.47
    cls_map[25:28, 15:18] = 3  # 9 px of 'unknown' inside the block
    probs = _probs(cls_map)
    (d,) = extract(probs, depth, NAMES, [2, 3, 4], INTR, np.eye(4))
    assert d.cls == "block" and d.pixels == 400


def test_points_and_centroid_are_in_the_world_frame():
    """A camera 0.5 m above the table looking down (its z along world -z): the centroid of a
    patch seen at the image centre lies under the camera at the patch's height."""
    depth = np.full((60, 80), 0.5, np.float32)
    cls_map = np.ones((60, 80), int)
    cls_map[25:36, 35:46] = 2  # centred on (cx, cy) = (40, 30)
    depth[25:36, 35:46] = 0.45
    X_WC = np.eye(4)
    X_WC[:3, :3] = np.diag([1.0, -1.0, -1.0])
    X_WC[:3, 3] = [0.3, -0.1, 0.5]
    (d,) = extract(_probs(cls_map), depth, NAMES, [2], INTR, X_WC)
    assert isinstance(d, ObjectDetection)
    assert d.centroid == pytest.approx((0.3, -0.1, 0.05), abs=1e-6)
    assert d.points.shape == (3, 121)
    assert np.allclose(d.points[2], 0.05)
    assert d.points[0].min() == pytest.approx(0.3 - 5 * 0.45 / 100)


def test_pixels_without_depth_give_no_points():
    mask = np.zeros((4, 4), bool)
    mask[1:3, 1:3] = True
    depth = np.zeros((4, 4), np.float32)
    depth[1, 1] = 1.0
    pts = backproject_mask(mask, depth, (1.0, 1.0, 0.0, 0.0), np.eye(4))
    assert pts.shape == (3, 1) and np.allclose(pts[:, 0], [1.0, 1.0, 1.0])


def test_depth_jumps_mark_both_sides():
    d = np.zeros((3, 4), np.float32) + 1.0
    d[:, 2:] = 0.9
    e = depth_jumps(d, 0.01)
    assert e[:, 1].all() and e[:, 2].all() and not e[:, 0].any() and not e[:, 3].any()
    assert len(split_at_jumps(np.ones((3, 4), bool), d, jump=0.01, min_pixels=3)) == 2
