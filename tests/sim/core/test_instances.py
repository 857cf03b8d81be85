"""Instances from a class map and depth: components per class, split at depth jumps, small
fragments merged back, world-frame points and centroids, low scores reported as unknown."""

from __future__ import annotations

import numpy as np
import pytest

from tamp.sim.core.instances import (
    FINE_JUMP,
    ObjectDetection,
    backproject_mask,
    depth_jumps,
    extract,
    proposals,
    split_at_jumps,
    split_at_levels,
    split_several,
    support_plane,
    world_heights,
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


# --- proposals from geometry -----------------------------------------------------------

#: a camera 0.5 m above the table looking straight down (its z along world -z)
X_DOWN = np.eye(4)
X_DOWN[:3, :3] = np.diag([1.0, -1.0, -1.0])
X_DOWN[:3, 3] = [0.0, 0.0, 0.5]


def _table(height: float = 0.0) -> np.ndarray:
    """The depth image of a flat surface at world z = ``height`` under `X_DOWN`."""
    return np.full((60, 80), 0.5 - height, np.float32)


def test_world_heights_back_project_through_the_camera_pose():
    depth = _table()
    depth[10, 20] = 0.45
    depth[0, 0] = 0.0
    z = world_heights(depth, INTR, X_DOWN)
    assert np.isnan(z[0, 0]) and z[10, 20] == pytest.approx(0.05)
    assert np.nanmax(np.abs(np.delete(z.ravel(), [0, 10 * 80 + 20]))) < 1e-9
    # a tilted camera: every pixel of the flat table is still at z = 0
    c, s = np.cos(0.3), np.sin(0.3)
    X = X_DOWN.copy()
    X[:3, :3] = X_DOWN[:3, :3] @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    vs, us = np.mgrid[0:60, 0:80]
    rays = np.stack([(us - 40.0) / 100, (vs - 30.0) / 100, 0 * us + 1.0])
    ray_z = np.tensordot(X[2, :3], rays, 1)
    tilted = (-0.5 / ray_z).astype(np.float32)  # depth along the axis to the plane z = 0
    assert np.allclose(world_heights(tilted, INTR, X), 0.0, atol=1e-6)


def test_the_support_plane_is_the_lowest_surface_that_fills_part_of_the_view():
    z = np.zeros((60, 80))
    z[:, 40:] = 0.001  # a mat 1 mm proud of the table: one band with it
    z[20:40, 10:30] = 0.03  # an object
    assert support_plane(z) == pytest.approx(0.0005, abs=0.001)
    z[:] = 0.01  # a tray floor 1 cm up fills the view
    z[5:10, 5:10] = -0.02  # a few stray low pixels are no plane
    z[20:40, 10:30] = 0.05
    assert support_plane(z) == pytest.approx(0.01, abs=1e-6)
    assert support_plane(np.full((4, 4), np.nan)) is None


def test_proposals_are_what_stands_on_the_plane_split_at_depth_jumps():
    depth = _table(0.01)  # the surface is 1 cm up: estimated, not assumed
    depth[20:40, 10:30] = 0.5 - 0.04  # two touching blocks, 3 and 6 cm above the surface
    depth[20:40, 30:50] = 0.5 - 0.07
    depth[50:52, 70:72] = 0.5 - 0.03  # 4 px: below the size rule
    depth[:, 75:] = 0.5 - 0.012  # a mat 2 mm proud of the surface: not an object
    prop = proposals(depth, INTR, X_DOWN)
    assert prop.plane == pytest.approx(0.01, abs=1e-6)
    assert sorted(int(m.sum()) for m in prop.masks) == [400, 400]
    assert np.nanmax(prop.heights) == pytest.approx(0.06, abs=1e-6)
    # at one height the two blocks are one proposal; the finer split cannot part them either
    depth[20:40, 30:50] = 0.5 - 0.04
    (one,) = proposals(depth, INTR, X_DOWN).masks
    assert one.sum() == 800 and len(split_at_jumps(one, depth, jump=FINE_JUMP)) == 1


def _tower(levels: list[tuple[int, float]], side: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Heights (m) of a stack seen from above: nested squares, each (half-size in px, top
    height), the largest first; each part's visible top a ring around the next, with a
    one-pixel side face whose pixels show heights from its top down to the next lower
    part's (a side face seen obliquely)."""
    rng = np.random.default_rng(0)
    h = np.full((side, side), np.nan)
    c = side // 2
    lower = 0.0
    for half, top in levels:
        h[c - half : c + half, c - half : c + half] = top
        ring = np.zeros((side, side), bool)
        ring[c - half : c + half, c - half : c + half] = True
        ring[c - half + 1 : c + half - 1, c - half + 1 : c + half - 1] = False
        h[ring] = rng.uniform(lower, top, int(ring.sum()))
        lower = top
    mask = np.isfinite(h)
    return mask, np.where(mask, h, np.nan)


def test_a_stack_is_cut_at_the_top_of_each_lower_part():
    """Fig. 10's tower from above: the bottom's top (4 cm) shows round the body (9 cm),
    the body's round the peak (13.5 cm): three levels, three parts, each holding its own
    top; the side faces between go to the part below their top edge's cut."""
    mask, z = _tower([(15, 0.04), (11, 0.09), (7, 0.135)])
    parts = split_at_levels(mask, z)
    assert len(parts) == 3
    assert np.logical_or.reduce(parts).sum() == mask.sum()
    assert sum(int(p.sum()) for p in parts) == mask.sum()  # disjoint
    tops = [float(np.nanmax(z[p])) for p in parts]
    assert tops == pytest.approx([0.04, 0.09, 0.135], abs=0.005)


def test_one_object_with_sloping_sides_is_not_cut():
    """A block seen at an angle: its top is one level, its side faces spread over many
    height bands and make none: one part."""
    mask, z = _tower([(15, 0.05)])
    yy, xx = np.mgrid[0:40, 0:40]
    side = mask & (xx < 12)
    z[side] = 0.05 * xx[side] / 12  # a wide side face, heights 0..5 cm
    (one,) = split_at_levels(mask, z)
    assert one is mask


def test_a_several_proposal_tries_depth_steps_first_then_levels():
    """Two blocks side by side at 3 and 6 cm are parted by the depth step; a stack, whose
    sides run on without one, by its levels."""
    depth = np.full((60, 80), 0.5)
    depth[20:40, 10:30], depth[20:40, 30:50] = 0.5 - 0.03, 0.5 - 0.06
    mask = depth < 0.5
    z = np.where(mask, 0.5 - depth, np.nan)
    parts, stacked = split_several(mask, depth, z)
    assert len(parts) == 2 and not stacked
    mask, z = _tower([(15, 0.04), (11, 0.09)])
    flat = np.where(mask, 0.5, 0.5)  # no depth steps at all: only the levels tell
    parts, stacked = split_several(mask, flat, z)
    assert len(parts) == 2 and stacked
