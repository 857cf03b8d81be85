"""The shared detector (`tamp.sim.core.perception`) on synthetic arrays (no simulation): counts,
targets, crops, tracks, and what it remembers of a workspace it cannot see all of."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix

from tamp.sim.core.messages import Detection, Seen
from tamp.sim.core.perception import (
    choose_target,
    covering,
    crop_square,
    detect,
    gripper_region,
    hidden,
    merged_into_others,
    recall,
)
from tamp.sim.core.tracks import Tracks, update

EMPTY = 32766  # RenderLabel.kEmpty
NO_TRACKS = Tracks()


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


def test_detections_on_the_table_with_threshold_and_hand_cut():
    label, depth = scene()
    dets = detect(label, depth, CLASSES, min_pixels=25)
    assert sorted(d.cls for d in dets) == ["scissors", "scissors"]
    assert sorted(d.pixels for d in dets) == [100, 200]
    big = max(dets, key=lambda d: d.pixels)
    assert (big.u, big.v, big.depth) == pytest.approx((19.5, 14.5, 0.45))
    assert np.isnan(big.centroid[0]) and big.points.shape == (3, 0)  # no camera pose: unplaced
    # the gripper's region is decided from depth alone: the saw's 64 pixels
    assert gripper_region(depth).sum() == 64


def _dets():
    return (
        Detection(3, "scissors", 200, 19.5, 14.5, 0.45),
        Detection(4, "scissors", 100, 54.5, 34.5, 0.45),
    )


def test_choose_target_follows_its_track_or_reports_it_lost():
    dets = _dets()
    assert choose_target(dets, "scissors", 4, (0, 0)).track == 4  # tracked
    assert choose_target(dets, "scissors", None, (0, 0)).track == 3  # none yet: nearest
    assert choose_target(dets, "scissors", None, (80, 60)).track == 4
    # the tracked instance is not in view: lost, never the other scissors in its place
    assert choose_target(dets, "scissors", 99, (80, 60)) is None
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


def look(memory, label, depth, tracks=NO_TRACKS, held=frozenset(), time=0.0):
    """One placed view as `Perception` makes it: detections, their tracks, then memory."""
    classes = CLASSES | {9: "hammer"}
    dets = detect(label, depth, classes, intrinsics=K, X_WC=X_LOOK)
    keep = {m.track for m in memory}
    masks = [d.mask for d in dets]
    under = {t.id: covering(t.position, masks, X_LOOK, K) for t in tracks.tracks}
    observed = [(d.cls, d.centroid) for d in dets]
    tracks, ids = update(tracks, observed, time, keep=keep, under=under)
    now = tuple(Seen(i, d.cls, d.centroid) for i, d in zip(ids, dets, strict=True))
    merged = merged_into_others(memory, ids, masks, depth, X_LOOK, K)
    memory, occluded = recall(memory, now, held, depth, X_LOOK, K, merged=merged)
    return memory, occluded, tracks


SAW = (slice(80, 100), slice(100, 130))
SCISSORS = (slice(130, 155), slice(190, 225))  # W^B's corner, where the person put it


def test_a_remembered_instance_hidden_by_the_held_object_is_kept_as_occluded():
    memory, occluded, tracks = look((), *view({8: SAW, 5: SCISSORS}))
    assert occluded == () and sorted(m.cls for m in memory) == ["saw", "scissors"]
    scissors = next(m for m in memory if m.cls == "scissors")
    # back-projected through depth, intrinsics and the camera pose: on the table, in W^B
    x, y, z = scissors.position
    assert z == pytest.approx(0.02, abs=1e-6)
    u, v = 207.0, 142.0  # the block's median pixel; image right is world +x, image down -y
    assert (x, y) == pytest.approx(
        (0.5 + (u - K[2]) / K[0] * 0.45, -0.25 - (v - K[3]) / K[1] * 0.45)
    )
    # the robot comes back holding the hammer, whose band covers the corner: the scissors'
    # pixels show the hammer 8 cm away; the scissors stays in memory, reported occluded
    assert abs(x - 0.5) <= 0.17 and abs(y + 0.25) <= 0.17  # in W^B (0.34 m square)
    hammer_band = (slice(110, 180), slice(180, 320))
    label, depth = view({8: SAW}, held=hammer_band)
    label[SCISSORS][depth[SCISSORS] > 0.1] = 5  # nothing of it is left uncovered
    memory2, occluded2, tracks2 = look(memory, label, depth, tracks, time=60.0)
    assert [m.cls for m in occluded2] == ["scissors"] and occluded2[0] == scissors
    assert sorted(m.cls for m in memory2) == ["saw", "scissors"]
    # the saw, seen again where it was, keeps its track; the hidden scissors' track is kept
    # by the memory although it was not seen for longer than a track's lifetime
    saw = next(m for m in memory if m.cls == "saw")
    assert next(m for m in memory2 if m.cls == "saw").track == saw.track
    assert tracks2.get(scissors.track) is not None


def test_an_instance_whose_place_is_in_plain_view_and_empty_is_gone_after_two_views():
    memory, _, tracks = look((), *view({8: SAW, 5: SCISSORS}))
    # the held hammer covers another part of the image; the corner shows the bare table
    label, depth = view({8: SAW}, held=(slice(0, 40), slice(0, 80)))
    memory2, occluded, tracks2 = look(memory, label, depth, tracks)
    # one view's miss may be the detector's: still counted, its miss counted up
    (scissors,) = occluded
    assert scissors.cls == "scissors" and scissors.misses == 1
    assert sorted(m.cls for m in memory2) == ["saw", "scissors"]
    memory3, occluded3, _ = look(memory2, label, depth, tracks2)
    assert occluded3 == () and [m.cls for m in memory3] == ["saw"]


def test_one_miss_then_a_sighting_starts_the_count_of_misses_afresh():
    memory, _, tracks = look((), *view({8: SAW, 5: SCISSORS}))
    bare, depth_bare = view({8: SAW})
    memory, occluded, tracks = look(memory, bare, depth_bare, tracks, time=1.0)
    assert [m.misses for m in occluded] == [1]
    memory, occluded, tracks = look(memory, *view({8: SAW, 5: SCISSORS}), tracks, time=2.0)
    assert occluded == () and all(m.misses == 0 for m in memory)
    memory, occluded, _ = look(memory, bare, depth_bare, tracks, time=3.0)
    assert [(m.cls, m.misses) for m in occluded] == [("scissors", 1)]


def test_an_instance_taken_into_the_gripper_is_forgotten_and_one_seen_again_is_updated():
    memory, _, tracks = look((), *view({8: SAW, 5: SCISSORS}))
    scissors = next(m for m in memory if m.cls == "scissors")
    # the scissors is now in the gripper, over its old place (perception has found its
    # track in hand: nothing on the table there); the saw moved 2 cm to the right
    label, depth = view({8: (slice(80, 100), slice(110, 140))})
    label[SCISSORS], depth[SCISSORS] = 5, 0.09
    memory2, occluded, _ = look(memory, label, depth, tracks, held=frozenset({scissors.track}))
    assert occluded == () and [m.cls for m in memory2] == ["saw"]
    saw0 = next(m for m in memory if m.cls == "saw")
    assert memory2[0].track == saw0.track  # 2 cm: within the gate, the same track
    assert memory2[0].position[0] > saw0.position[0]  # seen further right (+x): remembered there


BESIDE_SAW = (slice(84, 96), slice(132, 150))  # 2 px right of the saw's block


def test_an_instance_merged_into_a_neighbours_detection_is_kept_not_gone():
    """The learned detector can see a screw lying against a hammer as part of the hammer's
    detection (LOTS Example 1). Its place is in plain view, but inside another detection's
    mask: it is kept (reported occluded) and its track is not handed on."""
    memory, _, tracks = look((), *view({8: SAW, 5: BESIDE_SAW}))
    scissors = next(m for m in memory if m.cls == "scissors")
    label, depth = view({8: SAW, 5: BESIDE_SAW})
    label[BESIDE_SAW] = 8  # one saw detection over both
    memory2, occluded, _ = look(memory, label, depth, tracks, time=1.0)
    assert occluded == (scissors,)
    assert sorted(m.cls for m in memory2) == ["saw", "scissors"]
    # the same place, bare: gone (after the second such view: one may be a miss)
    memory3, occluded3, tracks3 = look(memory, *view({8: SAW}), tracks, time=1.0)
    assert [(m.cls, m.misses) for m in occluded3] == [("scissors", 1)]
    memory3, occluded3, _ = look(memory3, *view({8: SAW}), tracks3, time=1.1)
    assert occluded3 == () and [m.cls for m in memory3] == ["saw"]


def test_a_part_taken_off_a_stack_is_gone_though_the_part_below_covers_its_place():
    """Inside a neighbour's detection an object is kept only while its surface is still
    there: a part stacked 8 cm up, taken away, leaves the part below (2 cm up) under its
    pixel, 6 cm farther; it is gone, though that part's detection covers its place."""
    label, depth = view({8: SAW})
    label[BESIDE_SAW], depth[BESIDE_SAW] = 5, TABLE - 0.08
    memory, _, tracks = look((), label, depth)
    label, depth = view({8: SAW})
    label[BESIDE_SAW] = 8  # the saw's detection now covers the place; its surface is 2 cm up
    memory2, occluded, tracks2 = look(memory, label, depth, tracks, time=1.0)
    assert [m.misses for m in occluded] == [1]  # not merged: missed once in plain view
    memory2, occluded, _ = look(memory2, label, depth, tracks2, time=1.1)
    assert occluded == () and [m.cls for m in memory2] == ["saw"]


def test_covering_names_the_masks_over_a_points_pixel():
    label, depth = view({8: SAW})
    dets = detect(label, depth, CLASSES, intrinsics=K, X_WC=X_LOOK)
    saw = dets[0].centroid
    assert covering(saw, [d.mask for d in dets], X_LOOK, K) == (0,)
    assert covering((0.5, -0.25, 0.0), [d.mask for d in dets], X_LOOK, K) == ()
    assert covering((0.5, 0.25, 0.0), [d.mask for d in dets], X_LOOK, K) == ()  # off image
    assert covering(saw, [], X_LOOK, K) == ()


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
