"""Perception and grasp post-processing on synthetic arrays (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform

from tamp.grasp.rect import GraspRect
from tamp.sim.lots.grasping import dilate, on_mask, snap_to_mask
from tamp.sim.lots.kinematics import down
from tamp.sim.lots.perception import analyse, choose_target, crop_square
from tamp.sim.lots.scenario import Workspace
from tamp.sim.lots.skills import free_spot

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
    counts, dets, in_hand, occupied = analyse(label, depth, CLASSES, min_pixels=25)
    assert counts == {"scissors": 2}
    assert in_hand == ("saw",)
    assert sorted(d.pixels for d in dets) == [100, 200]
    d5 = next(d for d in dets if d.label == 5)
    assert (d5.u, d5.v, d5.depth) == pytest.approx((19.5, 14.5, 0.45))
    assert occupied.sum() == 300


def test_choose_target_tracks_then_nearest_centre():
    label, depth = scene()
    _, dets, _, _ = analyse(label, depth, CLASSES)
    assert choose_target(dets, "scissors", 6, (0, 0)).label == 6  # tracked
    assert choose_target(dets, "scissors", None, (0, 0)).label == 5  # nearest
    assert choose_target(dets, "scissors", 99, (80, 60)).label == 6
    assert choose_target(dets, "hammer", None, (0, 0)) is None


def test_crop_square_stays_in_the_image():
    assert crop_square(180, (180, 320), 160, 90) == (70, 0)
    assert crop_square(180, (180, 320), 10, 90) == (0, 0)
    assert crop_square(180, (180, 320), 310, 10) == (140, 0)


def test_snap_moves_a_grasp_beside_a_bar_onto_it():
    mask = np.zeros((100, 100), bool)
    mask[45:55, 10:90] = True  # a horizontal bar
    # the centre 20 px above the bar, closing vertically (angle 90 deg), opening 50 px
    g = GraspRect(40.0, 30.0, math.pi / 2, 50.0, 10.0)
    assert on_mask(g, mask) is None
    s = snap_to_mask(g, mask)
    assert (s.x, s.y) == pytest.approx((40.0, 49.5), abs=0.5)
    assert abs(math.sin(s.angle)) == pytest.approx(1.0)  # the network's angle is kept
    # closing along the bar from beside it never reaches the bar: rejected
    assert snap_to_mask(GraspRect(40.0, 20.0, 0.0, 50.0, 10.0), mask) is None
    assert on_mask(GraspRect(40.0, 50.0, 0.0, 50.0, 10.0), mask) is not None


def test_dilate():
    m = np.zeros((5, 5), bool)
    m[2, 2] = True
    assert dilate(m, 1).sum() == 9 and dilate(m, 2).sum() == 25


def test_free_spot_avoids_objects():
    w = Workspace("B", (0.5, -0.25), (0.34, 0.34))
    K = (231.4, 231.4, 159.5, 89.5)
    X_WC = RigidTransform(down(0.0), [0.5, -0.25, 0.47])
    occupied = np.zeros((180, 320), bool)
    assert free_spot(w, occupied, X_WC, K) == (0.5, -0.25)
    occupied[60:120, 130:190] = True  # an object in the middle of the view
    x, y = free_spot(w, occupied, X_WC, K)
    assert w.contains(x, y, margin=0.05)
    assert math.hypot(x - 0.5, y + 0.25) > 0.12
