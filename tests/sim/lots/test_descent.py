"""The closed-loop descent's decisions (`tamp.sim.lots.descent`): fusion over views,
confidence, where the exploring camera looks, the speed profile, the final approach's goal,
gate, turn, the target's velocity and whether a view shows all of it; the within-view ranking and
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
    STILL_SPEED,
    Thresholds,
    ViewGrasp,
    approach_aim,
    approach_velocity,
    carried,
    confident,
    explore_offset,
    fuse,
    predicted_centre,
    same_grasp,
    seen_velocity,
    target_velocity,
    turn_rate,
    wholly_in_view,
    wrist_turn,
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


def test_a_grasp_is_carried_with_its_target():
    g = _g(0.52, 0.21, yaw=0.3)
    moved = carried(g, (0.5, 0.2), (0.53, 0.18))
    assert (moved.x, moved.y) == pytest.approx((0.55, 0.19))
    assert (moved.z, moved.yaw, moved.quality) == (g.z, g.yaw, g.quality)
    assert carried(g, (0.5, 0.2), (0.5, 0.2)) == g


@given(
    st.floats(-math.pi, math.pi),
    st.floats(-2.8, 2.8),
    st.floats(-math.pi / 2, math.pi / 2),
    st.floats(0.3, 2.0),
)
@settings(max_examples=60, deadline=None)
def test_the_turn_keeps_the_wrist_in_range_within_its_bounds_and_stops(centre, off0, off1, accel):
    """From a yaw the wrist can hold (within 2.8 rad of its centred yaw) to a goal within a
    quarter turn of it (`hand_yaw_for_closing`'s choice): never faster than the speed, never
    changing the rate by more than accel * dt, never farther from the centre than the two
    ends (the wrist never goes round into its limit), at rest on the goal's yaw in the end."""
    dt, speed = 0.01, 1.2
    yaw, goal, w = centre + off0, centre + off1, 0.0
    for _ in range(int((abs(off1 - off0) / speed + 2 * speed / accel) / dt) + 100):
        nw = turn_rate(wrist_turn(yaw, goal, centre), w, speed, accel, dt)
        assert abs(nw) <= speed + 1e-9 and abs(nw - w) <= accel * dt + 1e-9
        yaw, w = yaw + nw * dt, nw
        assert abs(yaw - centre) <= max(abs(off0), abs(off1)) + 1e-6
    assert abs(math.remainder(goal - yaw, 2 * math.pi)) < 1e-3 and abs(w) < 0.02


def test_the_wrist_turns_through_its_centre_not_the_short_way():
    """The hand at yaw 0 with the wrist centred at 98 deg, the grasp at 184 deg: +184 deg
    through the centre (the short way, -176 deg, runs the last joint into its limit)."""
    centre, goal = math.radians(98), math.radians(184)
    assert math.degrees(wrist_turn(0.0, goal, centre)) == pytest.approx(184)
    assert math.degrees(wrist_turn(0.0, math.radians(30), centre)) == pytest.approx(30)


def test_a_square_blocks_two_grasps_are_not_the_same_grasp():
    def fused(x: float, yaw: float):
        f = fuse([_view(x, 0.2, yaw)] * 3, (0.5, 0.2))
        assert f is not None
        return f

    a, b = fused(0.5, 0.0), fused(0.5, math.pi / 2)
    c = fused(0.505, math.pi - 0.1)  # 6 deg off, modulo a half turn
    assert not same_grasp(a, b) and same_grasp(a, c) and same_grasp(c, a)
    assert not same_grasp(a, fused(0.53, 0.0))  # 3 cm along: the other end


def test_the_approach_goes_down_past_the_gate_only_over_the_goal():
    goal, gate = np.array([0.5, 0.2, 0.02]), 0.1
    above = np.array([0.45, 0.2, 0.15])  # 5 cm beside the goal, above the gate
    assert approach_aim(above, goal, 0.0, gate, 0.004, 0.05) == pytest.approx([0.5, 0.2, gate])
    over = np.array([0.502, 0.2, 0.1])  # over it, but still turning
    assert approach_aim(over, goal, 0.2, gate, 0.004, 0.05)[2] == gate
    assert approach_aim(over, goal, 0.01, gate, 0.004, 0.05) == pytest.approx(goal)
    # ... and not on a view that missed the target
    assert approach_aim(over, goal, 0.01, gate, 0.004, 0.05, seen=False)[2] == gate
    below = np.array([0.45, 0.2, 0.08])  # already under the gate: on down, whatever happens
    assert approach_aim(below, goal, 0.5, gate, 0.004, 0.05) == pytest.approx(goal)
    high = np.array([0.5, 0.3, 0.2])  # a goal above the gate is gone to at once
    assert approach_aim(high, goal + [0, 0, 0.1], 0.5, gate, 0.004, 0.05) == pytest.approx(
        goal + [0, 0, 0.1]
    )


def test_the_targets_velocity_from_its_recent_views():
    rng = np.random.default_rng(0)
    ts = np.arange(0.0, 1.2, 0.2)
    sliding = [(t, 0.5 + 0.02 * t + rng.normal(0, 0.0005), 0.2 - 0.01 * t) for t in ts]
    vx, vy = target_velocity(sliding)
    assert (vx, vy) == pytest.approx((0.02, -0.01), abs=0.003)
    # a still target's centres scatter by a millimetre: still, not creeping
    still = [(t, 0.5 + rng.normal(0, 0.0005), 0.2 + rng.normal(0, 0.0005)) for t in ts]
    assert target_velocity(still) == (0.0, 0.0)
    # only the views of the last span count: it slid, then stopped
    stopped = [(t, 0.5 + 0.02 * min(t, 0.4), 0.2) for t in np.arange(0.0, 1.6, 0.2)]
    assert target_velocity(stopped) == (0.0, 0.0)
    assert target_velocity(sliding[:2]) == (0.0, 0.0)  # too few views to tell
    assert target_velocity([]) == (0.0, 0.0)
    assert math.hypot(*target_velocity(sliding, still=0.03)) == 0.0
    assert STILL_SPEED < 0.02


def test_the_centre_goes_on_from_whole_views_only_and_for_a_while():
    """Carried on at the whole views' velocity, for at most the horizon; a latest view that
    shows only part of the target (its centre the visible part's, wandering as the camera
    moves) carries nothing on, whatever the centres did."""
    ts = np.arange(0.0, 1.0, 0.2)
    sliding = [(t, 0.5 + 0.02 * t, 0.2, True) for t in ts]
    assert seen_velocity(sliding) == pytest.approx((0.02, 0.0))
    t0 = ts[-1]
    assert predicted_centre(sliding, t0 + 0.5) == pytest.approx((0.5 + 0.02 * (t0 + 0.5), 0.2))
    far = predicted_centre(sliding, t0 + 10.0, horizon=1.5)
    assert far == pytest.approx((0.5 + 0.02 * (t0 + 1.5), 0.2))
    # the clutter hammer: still, its cut centre wandering 2 cm between views
    cut = [*sliding[:2], *((t, 0.5 + 0.05 * t, 0.2 - 0.1 * t, False) for t in ts[2:])]
    assert seen_velocity(cut) == (0.0, 0.0)
    assert predicted_centre(cut, t0 + 1.0) == pytest.approx(cut[-1][1:3])
    # a whole view after cut ones: the whole views' line, not through the cut ones
    back = [*cut, (t0 + 0.2, 0.5 + 0.02 * (t0 + 0.2), 0.2, True)]
    assert seen_velocity(back) == (0.0, 0.0)  # too few whole views in the span
    assert predicted_centre(back, t0 + 0.7) == pytest.approx(back[-1][1:3])


def test_a_view_shows_all_of_the_target_only_inside_its_edges():
    K = (231.0, 231.0, 159.5, 89.5)  # 320 x 180
    body = np.array([[-0.035, 0.035, 0.035, -0.035], [-0.02, -0.02, 0.02, 0.02], [0.2] * 4])
    assert wholly_in_view(body, K, 320, 180)
    # the tower's body 6.5 cm beside the optical axis (under the TCP) 0.14 m away: its far
    # end is out of the image; 0.16 m away it is in
    near = body.copy()
    near[0] -= 0.065
    near[2] = 0.14
    assert not wholly_in_view(near, K, 320, 180)
    near[2] = 0.16
    assert wholly_in_view(near, K, 320, 180)
    behind = body.copy()
    behind[2] = -0.1
    assert not wholly_in_view(behind, K, 320, 180)
    assert wholly_in_view(np.zeros((3, 0)), K, 320, 180)


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


def _approach_commands(hold=(), lose_at=None, jump_at=None, ticks=60):
    """The joint targets of a closed approach run by the skill controller alone, period by
    period (the arm tracking them, no simulation): the grasp 5 cm beside the TCP and 70 deg
    round, the target's last view one short of lost. ``hold``: the periods the safety
    monitor holds the arm (it slows down under the hold); ``lose_at``: the period a view
    without the target comes; ``jump_at``: the period the target is seen 6 cm aside. Returns
    the rate of the targets in each period (what the command stream carries), whether each
    period was held, and the final skill state."""
    from tamp.sim.core.messages import Observation, SkillCommand, SkillStatus
    from tamp.sim.lots.catalogue import READY
    from tamp.sim.lots.descent import FusedGrasp
    from tamp.sim.lots.kinematics import ArmKinematics
    from tamp.sim.lots.scenario import load_cell_scenario
    from tamp.sim.lots.skills import PandaSkillController, SkillState, Step
    from tamp.world.interface import Status

    scenario = load_cell_scenario("tower")
    kin = ArmKinematics(scenario.control.period)
    dt = kin.period
    q0 = np.array([*READY[:7], 0.04, 0.04])
    skills = PandaSkillController(scenario, kin, None, q0, list(range(9)))
    context = skills.CreateDefaultContext()
    cmd = SkillCommand(id=1, name="Pick", args=("body", "A"))
    x, y, _ = kin.tcp_pose(q0[:7]).translation()
    g = _g(x + 0.04, y - 0.03)
    f = FusedGrasp(g, (0.0, 0.0), 0.0, 0.0, 0.0, g.quality, 3, 0)
    yaw = kin.tcp_yaw(q0[:7]) + math.radians(70)
    s = SkillState(
        q=q0[:7].copy(),
        command=cmd,
        status=SkillStatus(1, Status.RUNNING),
        steps=(Step("approach", pose=(g.x, g.y, 0.005, yaw)),),
        target_cls="body",
        target_xy=(g.x, g.y),
        target_top=0.03,
        sure=(f, (g.x, g.y)),
        lost=2,
        attempt=1,
    )
    context.get_mutable_abstract_state(0).set_value(s)
    skills.command_port.FixValue(context, cmd)
    q, v = q0[:7].copy(), np.zeros(7)
    targets, held = [q.copy()], []
    for k in range(ticks):
        s = skills.state(context)
        if k in hold:
            v = 0.85 * v  # stopped: the arm slows down
            q = q + v * dt
        else:
            q, v = s.q.copy(), s.v.copy()
        if k == jump_at:
            s.target_xy = (g.x, g.y + 0.06)
        obs = Observation(id=s.request.id if k == lose_at else 0, time=k * dt)
        skills.arm_state_port.FixValue(context, np.r_[q, 0.04, 0.04, v, 0.0, 0.0])
        skills.observation_port.FixValue(context, obs)
        skills.hold_port.FixValue(context, [float(k in hold)])
        context.SetTime(k * dt)
        skills._update_timed(context, context.get_mutable_state())
        targets.append(skills.state(context).q.copy())
        held.append(k in hold)
    return np.diff(targets, axis=0) / dt, held, skills.state(context)


@pytest.mark.parametrize("case", ["jump", "hold", "lost"])
def test_the_closed_approach_commands_within_the_arms_limits(case):
    """The safety monitor's own check (`safety.check_limits`) finds nothing in the approach's
    command stream: with the target seen 6 cm aside; resumed after a stop while the arm still
    moved (the targets follow the held arm: the step that resumes goes on from their rate,
    not from rest: about twice the limit); losing its target while the wrist turns (the arm
    brakes from that period on; the targets stood still for one period: about 6x)."""
    from tamp.sim.lots.safety import check_limits

    hold = range(15, 17) if case == "hold" else ()
    rates, held, s = _approach_commands(
        hold, lose_at=40 if case == "lost" else None, jump_at=20 if case == "jump" else None
    )
    assert np.abs(rates).max() > 0.5  # the wrist turns fast
    # the monitor checks no acceleration within a stop, nor into one
    for k in range(1, len(rates)):
        if not held[k]:
            assert check_limits(np.zeros(7), rates[k], rates[k - 1], 0.01) == [], k
    lost = any("during the final approach" in m for _, m in s.log)
    assert lost == (case == "lost")
    assert (s.steps[0].kind == "approach") == (case != "lost")
