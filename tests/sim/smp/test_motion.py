"""Reference trajectories and base planning (pure numpy): limits hold, paths avoid objects."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from tamp.sim.smp.motion import (
    CLEARANCE,
    BasePlanner,
    Disc,
    Trapezoid,
    base_segment,
    joint_segment,
    quintic,
    standoff_pose,
)
from tamp.sim.smp.scenario import BaseLimits

WS = (-1.0, 4.0, -2.0, 2.0)


@given(st.floats(0.05, 2.0), st.floats(0.05, 5.0))
def test_trapezoid_respects_speed_and_acceleration(v, a):
    prof = Trapezoid.of(v, a)
    ts = np.linspace(0.0, prof.duration, 400)
    s = np.array([prof(t)[0] for t in ts])
    ds = np.array([prof(t)[1] for t in ts])
    assert s[0] == 0.0 and abs(s[-1] - 1.0) < 1e-9
    assert ds.max() <= v + 1e-9
    acc = np.diff(ds) / np.diff(ts)
    assert np.abs(acc).max() <= a * (1 + 1e-6)
    assert np.all(np.diff(s) >= -1e-12)


@given(st.floats(0.1, 3.0), st.floats(-3.0, 3.0), st.floats(-math.pi, math.pi))
def test_base_segment_limits_and_end(dx, dy, yaw):
    lim = BaseLimits()
    q0 = np.zeros(10)
    seg = base_segment(0.0, q0, (dx, dy, yaw), [(0.0, 0.0), (dx, dy)], lim)
    ts = np.linspace(0.0, seg.duration, 300)
    vs = np.array([seg.sample(t)[1] for t in ts])
    assert np.hypot(vs[:, 0], vs[:, 1]).max() <= lim.max_speed + 1e-6
    assert np.abs(vs[:, 2]).max() <= lim.max_yaw_rate + 1e-6
    q_end, v_end = seg.sample(seg.duration)
    assert np.allclose(q_end[:2], (dx, dy)) and abs(q_end[2] - yaw) < 1e-9
    assert np.allclose(v_end, 0.0)


def test_quintic_ends_at_rest():
    assert quintic(0.0, 2.0) == (0.0, 0.0)
    s, ds = quintic(2.0, 2.0)
    assert s == 1.0 and ds == 0.0
    seg = joint_segment(0.0, np.zeros(3), np.array([1.0, -0.5, 0.2]), 1.0, 0.1)
    peak = max(np.abs(seg.sample(t)[1]).max() for t in np.linspace(0, seg.duration, 200))
    assert peak <= 1.0 + 1e-6


@given(st.lists(st.tuples(st.floats(0.0, 3.0), st.floats(-1.5, 1.5)), max_size=6))
def test_planned_paths_keep_the_footprint_clear(points):
    obstacles = [Disc(x, y, 0.035) for x, y in points]
    fp = 0.45
    start, goal = (-0.5, 0.0), (3.5, 0.0)
    if any(
        math.hypot(o.x - p[0], o.y - p[1]) < fp + o.r + CLEARANCE
        for o in obstacles
        for p in (start, goal)
    ):
        return
    path = BasePlanner(WS).plan(start, goal, obstacles, fp)
    if path is None:
        return
    assert path[0] == start and path[-1] == goal
    for a, b in zip(path, path[1:], strict=False):
        for u in np.linspace(0, 1, 50):
            x, y = a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])
            for o in obstacles:  # grid resolution: allow half a cell
                assert math.hypot(x - o.x, y - o.y) >= fp + o.r + CLEARANCE - 0.05


def test_planner_goes_around_a_wall_of_objects():
    wall = [Disc(1.5, y, 0.035) for y in np.arange(-2.0, 1.0, 0.1)]
    path = BasePlanner(WS).plan((0.0, 0.0), (3.0, 0.0), wall, 0.45)
    assert path is not None and len(path) > 2
    assert max(p[1] for p in path) > 1.0 + 0.45  # it passes above the wall's end


def test_standoff_faces_the_target_and_avoids_neighbours():
    target = (2.0, 0.0)
    neighbour = Disc(1.6, 0.0, 0.035)  # blocks the side the robot comes from
    pose = standoff_pose(target, (0.0, 0.0), [neighbour], WS, 0.45)
    assert pose is not None
    x, y, yaw = pose
    assert math.hypot(x - 2.0, y) == np.float64(0.4) or abs(math.hypot(x - 2.0, y) - 0.4) < 1e-9
    assert math.hypot(x - neighbour.x, y - neighbour.y) >= 0.45 + 0.035 + CLEARANCE
    assert abs(math.atan2(-y, 2.0 - x) - yaw) < 1e-9


def test_base_backs_away_from_what_it_just_put_down():
    placed = Disc(2.0, 0.0, 0.05)  # the obstacle box, 0.4 m ahead of the base
    start, goal = (1.6, 0.0), (2.0, 1.5)
    path = BasePlanner(WS).plan(start, goal, [placed], 0.45)
    assert path is not None and path[0] == start
    d0 = math.hypot(start[0] - placed.x, start[1] - placed.y)
    for a, b in zip(path, path[1:], strict=False):
        for u in np.linspace(0, 1, 100):
            x, y = a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])
            # never closer than where it stood (the rotating corners reach 0.345 m)
            assert math.hypot(x - placed.x, y - placed.y) >= d0 - 1e-6


def test_a_base_inside_a_margin_goes_straight_to_a_goal_it_backs_away_to():
    """Case 3 after O1 is set aside at free2: the base stands 0.4 m from it (inside its
    margin) and its goal is the stand-off before O_a, which is the target and so no
    obstacle. Straight there only backs away from O1, so the base goes straight; escaping
    along a fixed direction first overshot the goal by 5 cm towards O_a and pushed it."""
    set_aside = Disc(2.0, 1.6, 0.04)
    target = (2.2, 0.8)
    start = (2.0 - 0.4 * math.cos(1.047), 1.6 - 0.4 * math.sin(1.047))
    goal = (target[0] - 0.4 * math.cos(-0.786), target[1] - 0.4 * math.sin(-0.786))
    path = BasePlanner((-1.0, 4.0, -2.2, 2.8)).plan(start, goal, [set_aside], 0.45)
    assert path == [start, goal]
    closest = min(
        math.hypot(a[0] + u * (b[0] - a[0]) - target[0], a[1] + u * (b[1] - a[1]) - target[1])
        for a, b in zip(path, path[1:], strict=False)
        for u in np.linspace(0, 1, 101)
    )
    assert closest >= 0.4 - 1e-6  # never nearer the target than the stand-off
