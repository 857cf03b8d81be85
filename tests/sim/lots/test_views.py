"""Grasp post-processing and the place skill's free spot on synthetic arrays (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydrake.math import RigidTransform

from tamp.grasp.rect import GraspRect
from tamp.sim.core.messages import Seen
from tamp.sim.lots.grasping import dilate, on_mask, snap_to_mask
from tamp.sim.lots.kinematics import down
from tamp.sim.lots.room import empty_room, footprint, next_look, observed, place, to_length
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


def _room(w, occupied, X_WC, floor=None, avoid=()):
    """What one view of workspace ``w`` showed of its floor."""
    room = empty_room(w.center, w.floor_size, w.floor)
    return observed(room, X_WC, K, occupied=occupied, floor=floor, avoid=avoid)


def _bar(length: float, width: float) -> np.ndarray:
    """The footprint of a bar along the hand's x (points every 5 mm)."""
    xs = np.arange(-length / 2, length / 2 + 1e-9, 0.005)
    ys = np.arange(-width / 2, width / 2 + 1e-9, 0.005)
    return np.array([(x, y) for x in xs for y in ys])


DISC = np.array([(0.03 * math.cos(a), 0.03 * math.sin(a)) for a in np.linspace(0, 6.2, 16)])


def test_a_place_keeps_the_footprint_clear_of_objects_seen():
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34))
    occupied = np.zeros((180, 320), bool)
    empty = place(_room(w, occupied, X_LOOK), DISC, [0.0])
    assert (empty.x, empty.y) == pytest.approx((0.5, -0.25), abs=0.011)  # the middle
    occupied[60:120, 130:190] = True  # an object in the middle of the view
    p = place(_room(w, occupied, X_LOOK), DISC, [0.0])
    assert w.contains(p.x, p.y, margin=0.03)
    assert math.hypot(p.x - 0.5, p.y + 0.25) > 0.12 and p.clearance > 0.02


def test_a_place_keeps_away_from_hidden_objects():
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34))
    occupied = np.zeros((180, 320), bool)
    hidden = Seen(3, "screw", (0.61, -0.36, 0.01))
    p = place(_room(w, occupied, X_LOOK, avoid=(hidden,)), DISC, [0.0])
    assert math.hypot(p.x - 0.61, p.y + 0.36) > 0.1 and p.clearance > 0.05
    hidden_cell = _room(w, occupied, X_LOOK, avoid=(hidden,))
    i, j, _ = hidden_cell.index(np.array([[0.61, -0.36]]))
    assert hidden_cell.blocked[i, j].all()


def test_a_hidden_long_object_blocks_where_it_was_seen_lying():
    """Example 1 with a person: the screwdriver in the tray, hidden behind the held hammer,
    blocked a 3 cm disc round its centre, and the hammer's head went down on its handle 6 cm
    away. Its footprint, as last seen, is kept clear along its whole length (in that run
    the tray then has no clear spot for the hammer at all: docs/results/lots_workcell.md)."""
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34))
    occupied = np.zeros((180, 320), bool)
    xs = np.arange(0.40, 0.60, 0.01)  # a 20 cm bar along x through the middle
    bar = Seen(6, "screwdriver", (0.5, -0.25, 0.02), tuple((float(x), -0.25) for x in xs))
    room = _room(w, occupied, X_LOOK, avoid=(bar,))
    i, j, _ = room.index(np.array([[0.41, -0.25], [0.59, -0.25], [0.5, -0.2]]))
    assert room.blocked[i[:2], j[:2]].all()  # 9 cm from the centre, on the bar: blocked
    assert not room.blocked[i[2], j[2]]  # 5 cm beside it: free
    centre_only = _room(w, occupied, X_LOOK, avoid=(Seen(6, "screwdriver", (0.5, -0.25, 0.02)),))
    assert not centre_only.blocked[i[:2], j[:2]].any()


def test_a_place_in_a_tray_keeps_the_object_off_its_walls():
    """Example 1 in the cell: a screw placed 6 cm inside W^B's edges reached over the tray's
    wall (W^B is 0.34 m, the tray's floor 0.24 m), landed on it and rolled out of W^B. The
    footprint is kept inside the tray's floor."""
    tray = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34), tray=True)
    assert tray.floor_size == (0.24, 0.24)
    assert Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34)).floor_size == (0.34, 0.34)
    assert tray.on_floor(0.61, -0.25) and not tray.on_floor(0.63, -0.25)
    occupied = np.zeros((180, 320), bool)
    occupied[80:100, 150:170] = True  # a 4 cm object in the middle
    screw = _bar(0.08, 0.012)
    p = place(_room(tray, occupied, X_LOOK), screw, [0.0, math.pi / 2])
    assert p.clearance > 0.01
    c, s_ = math.cos(p.yaw), math.sin(p.yaw)
    for x, y in screw:
        assert tray.on_floor(p.x + c * x - s_ * y, p.y + s_ * x + c * y)


def test_a_place_keeps_off_a_trays_walls_before_keeping_away_from_objects():
    """Example 1 with the learned detector: with the hammer in the tray's lower part, the
    screw went as far from it as it could, 2 cm from the upper wall, and went over the wall.
    In a tray it now keeps `WALL_MARGIN` off the walls (beyond `EDGE`), and only then as far
    from the hammer as it can; on a floor without walls the edges stay a constraint only."""
    from tamp.sim.lots.room import EDGE, WALL_MARGIN

    tray = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34), tray=True)
    room = observed(empty_room(tray.center, tray.floor_size, tray.floor), X_LOOK, K,
                    occupied=None, floor=None)  # fmt: skip
    cells = room.cells
    hammer = (np.abs(cells[..., 1] - (-0.25 - 0.07)) < 0.015) & (np.abs(cells[..., 0] - 0.5) < 0.1)
    room = type(room)(room.center, room.size, room.floor, room.seen, hammer)
    screw = _bar(0.08, 0.012)
    half = np.asarray(tray.floor_size) / 2

    def edge(p):
        pts = np.array([p.x, p.y]) + screw
        return float((half - np.abs(pts - np.asarray(tray.center))).min())

    p = place(room, screw, [0.0], walls=True)
    assert edge(p) >= EDGE + WALL_MARGIN - 0.005 and p.y > -0.25  # far side from the hammer
    flat = place(room, screw, [0.0])  # no walls: as far from the hammer as the edges allow
    assert EDGE <= edge(flat) < EDGE + 0.02 and flat.clearance > p.clearance


def test_a_long_object_is_turned_to_fit_beside_another():
    """A 20 cm hammer in the 24 cm tray with a screwdriver lying across its upper part: at
    the hand's present yaw (across the screwdriver) it fits nowhere; turned parallel it
    does."""
    tray = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34), tray=True)
    room = empty_room(tray.center, tray.floor_size, tray.floor)
    room = observed(room, X_LOOK, K, occupied=None, floor=None)  # all seen bare
    cells = room.cells
    lying = (np.abs(cells[..., 1] - (-0.25 + 0.07)) < 0.015) & (np.abs(cells[..., 0] - 0.5) < 0.1)
    room = type(room)(room.center, room.size, room.floor, room.seen, lying)
    hammer = _bar(0.20, 0.03)
    across = place(room, hammer, [math.pi / 2])  # the hammer along y: it meets the screwdriver
    assert across.clearance < 0.0
    best = place(room, hammer, [math.pi / 2, 0.0])
    assert best.yaw == 0.0 and best.clearance > 0.005
    assert best.y < -0.25  # beside it, on the far side of the middle


def _held_view():
    """A look at W^B with a held object hiding the image's left 60 %: the floor is seen bare
    only right of it (the view's ``floor`` pixels), nothing detected."""
    hidden = np.zeros((180, 320), bool)
    hidden[:, :190] = True
    return hidden, ~hidden, np.zeros((180, 320), bool)


def test_a_place_is_only_where_the_views_saw_bare_floor():
    """Example 1 with the learned detector: the person put the screwdriver in the tray while
    the robot carried the hammer, which hid the tray's middle in every view; with nothing
    detected the place took the tray's centre and laid the hammer on the screwdriver. The
    footprint now lies where the views saw the floor bare."""
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34), tray=True)
    hidden, floor, occupied = _held_view()
    room = _room(w, occupied, X_LOOK, floor=floor)
    assert room.seen.any() and not room.seen.all()
    small = DISC / 2  # 1.5 cm round: the floor seen bare is a strip 6 cm wide
    p = place(room, small, [0.0])
    i, j, inside = room.index(np.array([[p.x, p.y]]) + small)
    assert inside.all() and room.seen[i, j].all() and p.clearance > 0
    # taking the unseen floor as bare would put it in the middle
    q = place(room, small, [0.0], unseen_bare=True)
    assert q.clearance > p.clearance + 0.02


def test_another_view_shifts_the_camera_to_show_what_the_held_object_hid():
    w = Workspace(name="B", center=(0.5, -0.25), size=(0.34, 0.34), tray=True)
    hidden, floor, occupied = _held_view()
    room = _room(w, occupied, X_LOOK, floor=floor)
    at = next_look(room, hidden, X_LOOK, K)
    assert at is not None and at != (0.5, -0.25)
    X_next = RigidTransform(X_LOOK.rotation(), [*at, X_LOOK.translation()[2]])
    again = observed(room, X_next, K, occupied=occupied, floor=floor)
    assert again.seen.sum() > room.seen.sum()
    # once the whole floor was seen bare there is nothing left to look for
    full = observed(room, X_LOOK, K, occupied=occupied, floor=np.ones((180, 320), bool))
    assert full.seen.all() and next_look(full, hidden, X_LOOK, K) is None


def test_a_footprint_is_the_objects_points_in_the_hands_frame():
    pts = np.array([[-0.05, 0.0], [0.05, 0.0]])  # along world x round the centre
    shape = footprint(pts, math.pi / 2)  # a hand turned to world y
    assert shape == pytest.approx(np.array([[0.0, 0.05], [0.0, -0.05]]), abs=1e-12)
    assert len(footprint(np.random.default_rng(0).random((1000, 2)), 0.0)) <= 64


def test_a_place_starts_from_the_looks_taken_while_carrying():
    """The look at W^B while carrying saw the floor bare but for an object in its middle;
    the place's own view, the held object hiding all but a strip, sees too little floor.
    The place's floor starts from the carry's look (its bare floor and what stood on it),
    so the object goes where that look saw room, clear of the object; started empty (as
    before), the unseen floor was taken as bare and the object put in the middle, on it."""
    from types import SimpleNamespace

    from tamp.sim.core.messages import Observation, SkillCommand
    from tamp.sim.lots.catalogue import READY
    from tamp.sim.lots.kinematics import ArmKinematics
    from tamp.sim.lots.scenario import load_cell_scenario
    from tamp.sim.lots.skills import PLACE_VIEWS, PandaSkillController, SkillState

    class LookingAtB(ArmKinematics):  # the camera over W^B's middle, whatever the joints
        def camera_pose(self, q7):
            return X_LOOK

    scenario = load_cell_scenario("tower")
    q0 = np.array([*READY[:7], 0.04, 0.04])
    kin = LookingAtB(scenario.control.period)
    skills = PandaSkillController(scenario, kin, SimpleNamespace(intrinsics=K), q0, list(range(9)))
    s = SkillState(q=q0[:7].copy(), held="screwdriver", side="B", hold_shape=DISC)
    thing = np.zeros((180, 320), bool)
    thing[75:105, 145:175] = True  # an object in the middle of the look's image
    look = Observation(side="B", occupied=thing, floor=~thing, hidden=np.zeros_like(thing))
    skills._on_recounted(s, 1.0, look, q0)
    skills._start(s, SkillCommand(id=2, name="Place", args=("B",)), 2.0)
    assert s.looked is None and s.room is not None and s.room.blocked.any()
    hidden = np.ones_like(thing)
    hidden[:, 300:] = False  # the held object hides all but a strip at the image's edge
    s.place_views = PLACE_VIEWS  # no more views: the unseen floor is taken as bare
    view = Observation(side="B", occupied=np.zeros_like(thing), floor=~hidden, hidden=hidden)
    skills._on_place(s, 3.0, view, q0)
    line = next(text for _, text in reversed(s.log) if text.startswith("place the"))
    x, y = (float(v) for v in line.split("at (")[1].split(")")[0].split(", "))
    assert math.hypot(x - 0.5, y + 0.25) > 0.06  # clear of the object the look saw
    # a pick in between: the looks of an earlier carry do not count
    s.looked = ("B", s.room)
    skills._start(s, SkillCommand(id=3, name="LookAt", args=("A",)), 4.0)
    assert s.looked is not None
    s.held = None
    skills._start(s, SkillCommand(id=4, name="LookAt", args=("A",)), 5.0)
    assert s.looked is None


@given(
    length=st.floats(0.05, 0.2),
    share=st.floats(0.0, 0.5),
    angle=st.floats(-np.pi, np.pi),
)
def test_a_footprint_measured_short_reaches_its_catalogue_length_at_both_ends(length, share, angle):
    """A view that lost ``share`` of one end of a 2 cm wide object: the footprint spans at
    least the catalogue ``length`` along the object's axis, beyond the measured outline at
    both ends (which end was lost is not known); one measured whole is left as it is."""
    u = np.array([np.cos(angle), np.sin(angle)])
    v = np.array([-u[1], u[0]])
    lost = share * length
    across = np.linspace(-0.01, 0.01, 5)
    a, b = np.meshgrid(np.linspace(-length / 2, length / 2 - lost, 30), across)
    pts = a.reshape(-1, 1) * u + b.reshape(-1, 1) * v
    out = to_length(pts, length)
    along = out @ u
    assert along.max() - along.min() >= length - 0.001
    assert along.min() <= (pts @ u).min() + 1e-9 and along.max() >= (pts @ u).max() - 1e-9
    whole = to_length(pts, float(np.ptp(pts @ u)))
    assert whole.shape == pts.shape
