"""Grasp post-processing and the place skill's free spot on synthetic arrays (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform

from tamp.grasp.rect import GraspRect
from tamp.sim.lots.grasping import dilate, on_mask, snap_to_mask
from tamp.sim.lots.kinematics import down
from tamp.sim.lots.scenario import Workspace
from tamp.sim.lots.skills import free_spot

K = (231.4, 231.4, 159.5, 89.5)
X_LOOK = RigidTransform(down(0.0), [0.5, -0.25, 0.47])  # a look at W^B from 0.47 m


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
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34))
    K = (231.4, 231.4, 159.5, 89.5)
    X_WC = RigidTransform(down(0.0), [0.5, -0.25, 0.47])
    occupied = np.zeros((180, 320), bool)
    assert free_spot(w, occupied, X_WC, K) == (0.5, -0.25)
    occupied[60:120, 130:190] = True  # an object in the middle of the view
    x, y = free_spot(w, occupied, X_WC, K)
    assert w.contains(x, y, margin=0.05)
    assert math.hypot(x - 0.5, y + 0.25) > 0.12


def test_free_spot_keeps_away_from_hidden_objects():
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34))
    occupied = np.zeros((180, 320), bool)
    x, y = free_spot(w, occupied, X_LOOK, K, avoid=((0.61, -0.36),))
    assert math.hypot(x - 0.61, y + 0.36) > 0.25


def test_free_spot_in_a_tray_keeps_the_object_off_its_walls():
    """Example 1 in the cell: a screw placed 6 cm inside W^B's edges reached over the tray's
    wall (W^B is 0.34 m, the tray's floor 0.24 m), landed on it and rolled out of W^B. The
    spot is now measured from the tray's walls."""
    tray = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34), tray=True)
    assert tray.floor_size == (0.24, 0.24)
    assert Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34)).floor_size == (0.34, 0.34)
    assert tray.on_floor(0.61, -0.25) and not tray.on_floor(0.63, -0.25)
    occupied = np.zeros((180, 320), bool)
    occupied[80:100, 150:170] = True  # a 4 cm object in the middle: the spot goes to a corner
    x, y = free_spot(tray, occupied, X_LOOK, K, margin=0.06)
    assert max(abs(x - 0.5), abs(y + 0.25)) <= 0.12 - 0.06 + 1e-9  # 6 cm inside the walls
    assert math.hypot(x - 0.5, y + 0.25) > 0.08
