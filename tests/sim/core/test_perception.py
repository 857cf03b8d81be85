"""The shared detector (`tamp.sim.core.perception`) on synthetic arrays (no simulation): counts,
targets, crops, and what it remembers of a workspace it cannot see all of."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix

from tamp.sim.core.perception import (
    analyse,
    choose_target,
    crop_square,
    gripper_labels,
    hidden,
    recall,
)

EMPTY = 32766  # RenderLabel.kEmpty


def scene():
    label = np.full((60, 80), EMPTY, np.int16)
    depth = np.full((60, 80), 0.45, np.float32)
    label[10:20, 10:30] = 5  # a scissors, 200 px
    label[30:40, 50:60] = 6  # another scissors, 100 px
    label[50:53, 70:73] = 7  # a hammer sliver: 9 px, below the detector's threshold
    label[0:8, 0:8] = 8  # a saw in the gripper (close to the camera)
    depth[0:8, 0:8] = 0.08
    label[40:45, 0:5] = 2  # the table's body: no object class
    return label, depth


CLASSES = {5: "scissors", 6: "scissors", 7: "hammer", 8: "saw"}


def test_counts_per_class_with_threshold_and_hand_cut():
    label, depth = scene()
    view = analyse(label, depth, CLASSES, min_pixels=25)
    assert view.counts == {"scissors": 2}
    assert view.in_hand == ("saw",)
    assert view.held == gripper_labels(label, depth, CLASSES) == {8}
    assert sorted(d.pixels for d in view.detections) == [100, 200]
    d5 = next(d for d in view.detections if d.label == 5)
    assert (d5.u, d5.v, d5.depth) == pytest.approx((19.5, 14.5, 0.45))
    assert view.occupied.sum() == 300


def test_choose_target_tracks_then_nearest_centre():
    label, depth = scene()
    dets = analyse(label, depth, CLASSES).detections
    assert choose_target(dets, "scissors", 6, (0, 0)).label == 6  # tracked
    assert choose_target(dets, "scissors", None, (0, 0)).label == 5  # nearest
    assert choose_target(dets, "scissors", 99, (80, 60)).label == 6
    assert choose_target(dets, "hammer", None, (0, 0)) is None


def test_crop_square_stays_in_the_image():
    assert crop_square(180, (180, 320), 160, 90) == (70, 0)
    assert crop_square(180, (180, 320), 10, 90) == (0, 0)
    assert crop_square(180, (180, 320), 310, 10) == (140, 0)


# ---- occlusion is not absence: what perception remembers of a workspace ---------------------

K = (231.4, 231.4, 159.5, 89.5)
TABLE = 0.47  # the camera's height over the table at the look pose
#: the camera looking straight down, image right along world +x, image down along world -y
LOOKING_DOWN = RotationMatrix(np.diag([1.0, -1.0, -1.0]))
X_LOOK = RigidTransform(LOOKING_DOWN, [0.5, -0.25, TABLE])


def view(objects: dict[int, tuple[slice, slice]], held: tuple[slice, slice] | None = None):
    """A 320 x 180 look at a table 0.47 m below: label and depth images with objects 2 cm
    tall at the given pixel blocks and, optionally, a held hammer (label 9) 8 cm from the
    camera."""
    label = np.full((180, 320), EMPTY, np.int16)
    depth = np.full((180, 320), TABLE, np.float32)
    for value, block in objects.items():
        label[block] = value
        depth[block] = TABLE - 0.02
    if held is not None:
        label[held] = 9
        depth[held] = 0.08
    return label, depth


def look(memory, label, depth):
    classes = CLASSES | {9: "hammer"}
    view = analyse(label, depth, classes)
    return recall(memory, view.detections, view.held, depth, X_LOOK, K)


SAW = (slice(80, 100), slice(100, 130))
SCISSORS = (slice(130, 155), slice(190, 225))  # W^B's corner, where the person put it


def test_a_remembered_instance_hidden_by_the_held_object_is_kept_as_occluded():
    memory, occluded = look((), *view({8: SAW, 5: SCISSORS}))
    assert occluded == () and sorted(m.cls for m in memory) == ["saw", "scissors"]
    scissors = next(m for m in memory if m.cls == "scissors")
    # back-projected through depth, intrinsics and the camera pose: on the table, in W^B
    x, y, z = scissors.position
    assert z == pytest.approx(0.02, abs=1e-6)
    u, v = 207.0, 142.0  # the block's centroid; image right is world +x, image down -y
    assert (x, y) == pytest.approx(
        (0.5 + (u - K[2]) / K[0] * 0.45, -0.25 - (v - K[3]) / K[1] * 0.45)
    )
    # the robot comes back holding the hammer, whose band covers the corner: the scissors'
    # pixels show the hammer 8 cm away; the scissors stays in memory, reported occluded
    assert abs(x - 0.5) <= 0.17 and abs(y + 0.25) <= 0.17  # in W^B (0.34 m square)
    hammer_band = (slice(110, 180), slice(180, 320))
    label, depth = view({8: SAW}, held=hammer_band)
    label[SCISSORS][depth[SCISSORS] > 0.1] = 5  # nothing of it is left uncovered
    memory2, occluded2 = look(memory, label, depth)
    assert [m.cls for m in occluded2] == ["scissors"] and occluded2[0] == scissors
    assert sorted(m.cls for m in memory2) == ["saw", "scissors"]


def test_an_instance_whose_place_is_in_plain_view_and_empty_is_gone():
    memory, _ = look((), *view({8: SAW, 5: SCISSORS}))
    # the held hammer covers another part of the image; the corner shows the bare table
    memory2, occluded = look(memory, *view({8: SAW}, held=(slice(0, 40), slice(0, 80))))
    assert occluded == () and [m.cls for m in memory2] == ["saw"]


def test_an_instance_seen_in_the_gripper_is_forgotten_and_one_seen_again_is_updated():
    memory, _ = look((), *view({8: SAW, 5: SCISSORS}))
    # the scissors is now in the gripper (label 5 near the camera), over its old place
    label, depth = view({8: (slice(80, 100), slice(140, 170))})
    label[SCISSORS], depth[SCISSORS] = 5, 0.09
    memory2, occluded = look(memory, label, depth)
    assert occluded == () and [m.cls for m in memory2] == ["saw"]
    saw0 = next(m for m in memory if m.cls == "saw")
    assert memory2[0].position[0] > saw0.position[0]  # seen further right (+x): remembered there


def test_hidden_out_of_the_image_behind_the_camera_and_under_a_patch():
    _, depth = view({})
    assert not hidden((0.5, -0.25, 0.0), depth, X_LOOK, K)  # the centre: bare table
    assert hidden((0.5, 0.25, 0.0), depth, X_LOOK, K)  # W^A: out of the image
    assert hidden((0.5, -0.25, 0.6), depth, X_LOOK, K)  # above the camera
    # 3 px from the image's left edge: its 7 px patch is not all in the image; 20 px: it is
    assert hidden((0.5 + (3 - K[2]) / K[0] * TABLE, -0.25, 0.0), depth, X_LOOK, K)
    assert not hidden((0.5 + (20 - K[2]) / K[0] * TABLE, -0.25, 0.0), depth, X_LOOK, K)
    depth[88:92, 158:162] = 0.0  # nearer than the clipping plane: covered
    assert hidden((0.5, -0.25, 0.0), depth, X_LOOK, K)
    _, depth = view({})
    depth[89, 165] = 0.3  # 5.5 px from the centre, inside the 1.5 cm patch (7 px)
    assert hidden((0.5, -0.25, 0.0), depth, X_LOOK, K)
    assert not hidden((0.5, -0.25, 0.0), depth, X_LOOK, K, window=0.005)
    # an object lying there 2 cm tall is no cover for a point on its top
    _, depth = view({5: (slice(80, 100), slice(150, 170))})
    assert not hidden((0.5, -0.25, 0.02), depth, X_LOOK, K)
