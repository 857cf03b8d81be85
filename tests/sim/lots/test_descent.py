"""The closed-loop descent's decisions (`tamp.sim.lots.descent`): fusion over views,
confidence, where the exploring camera looks, the speed profile; the within-view ranking and
the mask-geometry control (`tamp.sim.lots.grasping`); which views ask for a target. No
simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.grasp.rect import angle_difference
from tamp.sim.lots.descent import (
    CLUTTER_RADIUS,
    Thresholds,
    ViewGrasp,
    approach_velocity,
    confident,
    explore_offset,
    fuse,
)
from tamp.sim.lots.grasping import GraspCandidate, chord, mask_axis_grasps, rank

TH = Thresholds(min_views=3, max_spread=0.008, max_angle_spread=math.radians(15), min_quality=0.3)


def _g(x: float, y: float, yaw: float = 0.0, q: float = 0.8, **kw) -> GraspCandidate:
    return GraspCandidate(x, y, 0.03, yaw, 0.04, q, 0.3, **kw)


def _view(x, y, yaw=0.0, q=0.8, centre=(0.5, 0.2)) -> ViewGrasp:
    return ViewGrasp(_g(x, y, yaw, q), centre)


def test_agreeing_views_are_confident_once_there_are_enough():
    views = [_view(0.51, 0.2), _view(0.511, 0.2), _view(0.51, 0.201)]
    assert not confident(fuse(views[:2], (0.5, 0.2)), TH)  # two views: too few
    f = fuse(views, (0.5, 0.2))
    assert confident(f, TH) and f.views == 3 and f.spread < 0.001
    assert (f.grasp.x, f.grasp.y) == pytest.approx((0.51, 0.2), abs=0.002)


def test_two_grasp_modes_are_fused_apart():
    """The network alternating between the two ends of a tool: two modes, fused apart (not
    one wide estimate between them); the hand commits once one mode has enough views."""
    a, b = _view(0.47, 0.2), _view(0.53, 0.2)
    f = fuse([a, b, a, b], (0.5, 0.2))
    assert f.spread == pytest.approx(0.0, abs=1e-9) and f.views == 2 and f.misses == 2
    assert not confident(f, TH)
    f = fuse([a, b, a, b, a], (0.5, 0.2))
    assert confident(f, TH) and f.grasp.x == pytest.approx(0.47)


def test_closing_angles_fuse_modulo_a_half_turn():
    """89 deg and -89 deg close along (almost) the same line: a parallel gripper is
    symmetric, so the spread is small and the mean is near +-90 deg."""
    d = math.radians(89)
    f = fuse([_view(0.51, 0.2, d), _view(0.51, 0.2, -d), _view(0.51, 0.2, d)], (0.5, 0.2))
    assert f.angle_spread < math.radians(3)
    assert angle_difference(f.angle, math.pi / 2) < math.radians(2)
    crossed = [_view(0.51, 0.2, 0.0), _view(0.51, 0.2, math.pi / 2), _view(0.51, 0.2, 0.0)]
    assert not confident(fuse(crossed, (0.5, 0.2)), TH)


def test_views_without_a_grasp_count_but_add_nothing():
    views = [ViewGrasp(None, (0.5, 0.2)), _view(0.51, 0.2), ViewGrasp(None, (0.5, 0.2))]
    f = fuse(views, (0.5, 0.2))
    assert (f.views, f.misses) == (1, 2) and not confident(f, TH)
    assert fuse([ViewGrasp(None, (0.5, 0.2))], (0.5, 0.2)) is None


def test_low_quality_is_not_confident():
    views = [_view(0.51, 0.2, q=0.1)] * 4
    assert not confident(fuse(views, (0.5, 0.2)), TH)


def test_a_moving_target_carries_its_grasps():
    """The target slides 1 cm per view; the network's grasp stays 2 cm beside its centre:
    fused relative to the centre, the views agree, and the grasp executed is beside where
    the target is now."""
    views = [_view(0.52 + k * 0.01, 0.2, centre=(0.5 + k * 0.01, 0.2)) for k in range(4)]
    f = fuse(views, (0.56, 0.2))
    assert f.spread < 1e-9 and confident(f, TH)
    assert (f.grasp.x, f.grasp.y) == pytest.approx((0.58, 0.2))


offsets = st.tuples(st.floats(-0.05, 0.05), st.floats(-0.05, 0.05))


@given(
    st.lists(
        st.tuples(offsets, st.floats(-math.pi, math.pi), st.floats(0.0, 1.2)),
        min_size=1,
        max_size=8,
    )
)
@settings(max_examples=60, deadline=None)
def test_fusion_bounds(members):
    """The mean offset lies within the members' box; spreads are within their ranges; the
    executed grasp is one of the members (moved to the centre); order does not matter."""
    views = [_view(0.5 + dx, 0.2 + dy, yaw, q) for (dx, dy), yaw, q in members]
    f = fuse(views, (0.5, 0.2))
    xs = [dx for (dx, _), _, _ in members]
    ys = [dy for (_, dy), _, _ in members]
    assert min(xs) - 1e-9 <= f.offset[0] <= max(xs) + 1e-9
    assert min(ys) - 1e-9 <= f.offset[1] <= max(ys) + 1e-9
    assert 0.0 <= f.spread <= math.hypot(max(xs) - min(xs), max(ys) - min(ys)) + 1e-9
    assert 0.0 <= f.angle_spread
    assert any(
        math.isclose(f.grasp.x, v.grasp.x, abs_tol=1e-12)
        and math.isclose(f.grasp.y, v.grasp.y, abs_tol=1e-12)
        for v in views
    )
    g = fuse(views[::-1], (0.5, 0.2))
    assert g.spread == pytest.approx(f.spread, abs=1e-9)
    assert g.quality == pytest.approx(f.quality, abs=1e-9)


def test_exploring_moves_away_from_the_nearest_clutter():
    target, other = (0.5, 0.2), (0.55, 0.2)
    ox, oy = explore_offset(target, [other, (0.9, 0.9)], 0, 0.03)
    assert math.hypot(ox, oy) == pytest.approx(0.03) and ox < -0.029  # away: -x
    far = (0.5 + CLUTTER_RADIUS + 0.01, 0.2)
    turns = {tuple(np.round(explore_offset(target, [far], k, 0.03), 6)) for k in range(4)}
    assert len(turns) == 4  # no clutter near: four directions round the target
    assert explore_offset(target, [other], 0, 0.0) == (0.0, 0.0)


vec = st.tuples(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-0.3, 0.3))


@given(vec, vec, st.floats(0.05, 0.5), st.floats(0.05, 0.5), st.floats(0.1, 3.0))
@settings(max_examples=60, deadline=None)
def test_the_servo_keeps_its_bounds_and_stops_at_the_goal(p0, goal, speed, lateral, accel):
    """Never faster than ``speed`` down or ``lateral`` sideways, never accelerating more than
    ``accel`` (per direction), and it comes to rest at the goal without overshooting it by
    more than a step."""
    dt = 0.01
    p, v = np.array(p0), np.zeros(3)
    goal = np.array(goal)
    dist0 = np.abs(goal - p)
    budget = np.linalg.norm(dist0[:2]) / lateral + dist0[2] / speed + 2 * (speed + lateral) / accel
    for _ in range(int(budget / dt) + 100):
        nv = approach_velocity(p, goal, v, speed, accel, dt, lateral)
        assert np.linalg.norm(nv[:2]) <= lateral + 1e-9 and abs(nv[2]) <= speed + 1e-9
        assert np.linalg.norm(nv[:2] - v[:2]) <= accel * dt + 1e-9
        assert abs(nv[2] - v[2]) <= accel * dt + 1e-9
        p, v = p + nv * dt, nv
        assert abs(goal[2] - p[2]) <= dist0[2] + speed * dt + 1e-9
        if np.linalg.norm(goal - p) < 1e-4 and np.linalg.norm(v) < 1e-3:
            break
    assert np.linalg.norm(goal - p) < 1e-3 and np.linalg.norm(v) < 0.02


def test_within_a_view_a_clear_grasp_comes_first():
    """A clear grasp is never hidden behind a better-quality one the jaws' sweep rules out;
    among clear ones, seated first, then quality."""
    blocked = _g(0.5, 0.2, q=0.99, clear=False)
    loose = _g(0.5, 0.2, q=0.9, seated=False)
    good = _g(0.5, 0.2, q=0.4)
    assert rank([blocked, loose, good]) == [good, loose, blocked]


def _bar(deg: float) -> np.ndarray:
    a = math.radians(deg)
    e1 = np.array([math.cos(a), -math.sin(a)])
    e2 = np.array([math.sin(a), math.cos(a)])
    yy, xx = np.mgrid[0:180, 0:180]
    u = (xx - 90) * e1[0] + (yy - 90) * e1[1]
    v = (xx - 90) * e2[0] + (yy - 90) * e2[1]
    return (np.abs(u) < 50) & (np.abs(v) < 8)


@pytest.mark.parametrize("deg", [0, 30, 75, 120])
def test_the_mask_control_closes_across_the_principal_axis(deg):
    from tamp.grasp.rect import GraspRect

    m = _bar(deg)
    grasps = mask_axis_grasps(m, 5)
    assert len(grasps) == 5 and grasps[0].quality >= grasps[-1].quality
    for g in grasps:
        assert m[int(round(g.v)), int(round(g.u))]
        # across the bar: 90 deg from its long axis, the chord its 16 px width
        assert angle_difference(g.angle, math.radians(deg + 90)) < math.radians(3)
        lo, hi = chord(GraspRect(g.u, g.v, g.angle, 10, 5), m)
        assert abs(lo + hi) <= 2.0 and 14 <= hi - lo + 1 <= 19
    assert math.hypot(grasps[0].u - 90, grasps[0].v - 90) < 3  # best at the centroid
    assert mask_axis_grasps(np.zeros((20, 20), bool), 5) == []


def test_only_a_picks_own_views_ask_for_a_target():
    """A class left from an earlier pick must not make a later look render colour or follow
    an instance: only a ``target`` view's request names it. The lift's view names the track
    the grasp picked, without a target (is it in the gripper?: no colour, no following)."""
    from tamp.sim.lots.catalogue import READY
    from tamp.sim.lots.kinematics import ArmKinematics
    from tamp.sim.lots.scenario import load_cell_scenario
    from tamp.sim.lots.skills import PandaSkillController, SkillState, Step

    scenario = load_cell_scenario("tower")
    kin = ArmKinematics(scenario.control.period)
    q0 = np.array([*READY[:7], 0.04, 0.04])
    skills = PandaSkillController(scenario, kin, None, q0, list(range(9)))
    s = SkillState(q=q0[:7].copy(), target_cls="body", track=7)
    for handler in ("counted", "lifted", "seen", "target"):
        skills._enter(s, Step("view", handler=handler), 0.0, q0)
        named = {"target": ("body", 7), "lifted": (None, 7)}.get(handler, (None, None))
        assert (s.request.target, s.request.track) == named
