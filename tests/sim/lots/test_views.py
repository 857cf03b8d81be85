"""Grasp post-processing and the place skill's free spot on synthetic arrays (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform

from tamp.grasp.rect import GraspRect
from tamp.sim.lots.grasping import dilate, on_mask, snap_to_mask
from tamp.sim.lots.kinematics import down
from tamp.sim.lots.room import at_best, empty_room, free_spot, next_look, observed
from tamp.sim.lots.scenario import Workspace

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


def _spot(w, occupied, X_WC, margin=0.06, avoid=(), floor=None):
    """The place's spot from one view of workspace ``w``."""
    room = empty_room(w.center, w.floor_size, w.floor, margin)
    room = observed(room, X_WC, K, occupied=occupied, floor=floor, avoid=avoid)
    return free_spot(room, w.center)


def test_free_spot_avoids_objects():
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34))
    occupied = np.zeros((180, 320), bool)
    assert _spot(w, occupied, X_LOOK) == ((0.5, -0.25), math.inf)
    occupied[60:120, 130:190] = True  # an object in the middle of the view
    (x, y), clear = _spot(w, occupied, X_LOOK)
    assert w.contains(x, y, margin=0.05)
    assert math.hypot(x - 0.5, y + 0.25) > 0.12 and clear > 0.06


def test_free_spot_keeps_away_from_hidden_objects():
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34))
    occupied = np.zeros((180, 320), bool)
    (x, y), _ = _spot(w, occupied, X_LOOK, avoid=((0.61, -0.36),))
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
    (x, y), _ = _spot(tray, occupied, X_LOOK, margin=0.06)
    assert max(abs(x - 0.5), abs(y + 0.25)) <= 0.12 - 0.06 + 1e-9  # 6 cm inside the walls
    assert math.hypot(x - 0.5, y + 0.25) > 0.08


def _held_view():
    """A look at W^B with a held object hiding the image's left 60 %: the floor is seen bare
    only right of it (the view's ``floor`` pixels), nothing detected."""
    hidden = np.zeros((180, 320), bool)
    hidden[:, :190] = True
    return hidden, ~hidden, np.zeros((180, 320), bool)


def test_a_spot_is_only_where_the_view_saw_bare_floor():
    """Example 1 with the learned detector: the person put the screwdriver in the tray while
    the robot carried the hammer, which hid the tray's middle in every view; with nothing
    detected the place took the tray's centre and laid the hammer on the screwdriver. A
    spot now lies where the view saw the floor bare, away from what it could not see."""
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34), tray=True)
    hidden, floor, occupied = _held_view()
    room = observed(empty_room(w.center, w.floor_size, w.floor, 0.06), X_LOOK, K,
                    occupied=occupied, floor=floor)  # fmt: skip
    assert room.seen.any() and not room.seen.all()
    (x, y), clear = free_spot(room, w.center)
    assert (x, y) != w.center and math.isfinite(clear)
    # the spot is a seen one, and its clearance is its distance to the nearest unseen one
    i = int(np.flatnonzero((room.grid == (x, y)).all(axis=1))[0])
    assert room.seen[i]
    assert clear == pytest.approx(np.min(np.linalg.norm(room.unseen - (x, y), axis=1)))


def test_another_view_shifts_the_camera_to_show_what_the_held_object_hid():
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34), tray=True)
    hidden, floor, occupied = _held_view()
    room = observed(empty_room(w.center, w.floor_size, w.floor, 0.06), X_LOOK, K,
                    occupied=occupied, floor=floor)  # fmt: skip
    # nothing seen on the floor: the unseen part may hold a clear spot
    assert at_best(room) == math.inf
    at = next_look(room, hidden, X_LOOK, K)
    assert at is not None and at != (0.5, -0.25)
    X_next = RigidTransform(X_LOOK.rotation(), [*at, X_LOOK.translation()[2]])
    # the next view, as predicted: its floor pixels outside the hidden part
    again = observed(room, X_next, K, occupied=occupied, floor=floor)
    assert again.seen.sum() > room.seen.sum()
    # once the whole floor was seen bare there is nothing left to look for
    full = observed(room, X_LOOK, K, occupied=occupied, floor=np.ones((180, 320), bool))
    assert full.seen.all() and next_look(full, hidden, X_LOOK, K) is None
    assert free_spot(full, w.center) == ((0.5, -0.25), math.inf)


def test_no_view_is_added_when_the_unseen_floor_cannot_hold_a_clearer_spot():
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34))
    hidden, floor, occupied = _held_view()
    occupied[:, 300:] = True  # an object along the image's right edge, seen
    room = observed(empty_room(w.center, w.floor_size, w.floor, 0.06), X_LOOK, K,
                    occupied=occupied, floor=floor & ~occupied)  # fmt: skip
    _, clear = free_spot(room, w.center)
    best = at_best(room)
    assert clear <= best < math.inf  # the unseen left part is farther from the object
    assert best > clear + 0.02
