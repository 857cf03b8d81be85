"""The LOTS workcell models parse offline and carry Franka's published numbers."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from tamp.sim.core.parsing import make_parser
from tamp.sim.lots.catalogue import ARM, CLASSES, READY, TABLE_URL, TRAY_URL, WASTE_BASKET_URL
from tamp.sim.lots.kinematics import ArmKinematics, hand_yaw_for_closing


def _plant():
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    return plant


@pytest.fixture(scope="module")
def arm_plant():
    plant = _plant()
    (m,) = make_parser(plant).AddModelsFromUrl(ARM.url)
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(ARM.base_frame, m))
    plant.Finalize()
    return plant, m


def test_arm_has_franka_limits(arm_plant):
    plant, m = arm_plant
    assert plant.num_positions(m) == 9
    for k, name in enumerate(ARM.arm_joints):
        j = plant.GetJointByName(name, m)
        assert j.position_lower_limits()[0] == pytest.approx(ARM.lower[k])
        assert j.position_upper_limits()[0] == pytest.approx(ARM.upper[k])
        assert j.velocity_upper_limits()[0] == pytest.approx(ARM.max_velocity[k])
    for name in ARM.finger_joints:
        j = plant.GetJointByName(name, m)
        assert (j.position_lower_limits()[0], j.position_upper_limits()[0]) == (0.0, 0.04)
    assert 17.0 < plant.CalcTotalMass(plant.CreateDefaultContext(), [m]) < 22.0


def test_ready_pose_matches_franka():
    """Franka's ready pose puts the TCP 0.307 m ahead and 0.487 m up, pointing down."""
    kin = ArmKinematics(0.01)
    X = kin.tcp_pose(np.array(READY))
    np.testing.assert_allclose(X.translation(), [0.3069, 0.0, 0.4869], atol=2e-4)
    np.testing.assert_allclose(X.rotation().matrix(), np.diag([1.0, -1.0, -1.0]), atol=1e-9)
    # the camera looks along the approach axis, 6.5 cm off it
    np.testing.assert_allclose(kin.X_TC.translation(), [0.065, 0.0, -0.0554], atol=1e-9)


def test_closing_yaw_to_hand_yaw():
    assert hand_yaw_for_closing(-np.pi / 2) == pytest.approx(0.0)
    assert hand_yaw_for_closing(0.0) == pytest.approx(-np.pi / 2)
    for a in np.linspace(-3, 3, 13):
        psi = hand_yaw_for_closing(a)
        assert -np.pi / 2 <= psi <= np.pi / 2
        # fingers close along psi - pi/2, modulo pi
        d = (psi - np.pi / 2 - a) % np.pi
        assert min(d, np.pi - d) < 1e-9


@pytest.mark.parametrize("toward", [-3.0, -1.4, 0.0, 1.5, 3.1])
def test_hand_yaw_is_the_symmetric_twin_nearest_the_reference(toward):
    for a in np.linspace(-3, 3, 13):
        psi = hand_yaw_for_closing(a, toward)
        off = (psi - toward + np.pi) % (2 * np.pi) - np.pi
        assert abs(off) <= np.pi / 2 + 1e-9 and -np.pi <= psi <= np.pi
        d = (psi - np.pi / 2 - a) % np.pi
        assert min(d, np.pi - d) < 1e-9


#: the arm at a look pose over W^A with its wrist at 1.55 rad (seen in a LOTS campaign run)
LOOK = np.array([0.25, 0.04, 0.49, -2.44, -0.03, 2.48, 1.55])


def test_the_wrist_centred_yaw_keeps_the_last_joint_in_range():
    """Whatever the wrist's angle, the reference is the yaw at which it would be mid-range;
    a grasp closing along world x then takes the TCP yaw that turns the wrist back towards
    0 (+91 deg), not the one that turns it past its limit (-89 deg: 1.55 + 1.55 rad)."""
    kin = ArmKinematics(0.01)
    q = LOOK.copy()
    q[6] = 0.0
    R = kin.tcp_pose(q).rotation().matrix()
    mid_yaw = np.arctan2(R[1, 0], R[0, 0])
    for wrist in (-2.5, -1.0, 1.55, 2.5):
        q[6] = wrist
        assert kin.wrist_centred_yaw(q) == pytest.approx(mid_yaw, abs=1e-3)
    psi = hand_yaw_for_closing(np.radians(1.0), kin.wrist_centred_yaw(LOOK))
    assert np.degrees(psi) == pytest.approx(91.0, abs=1e-6)


def test_diff_ik_moves_a_joint_standing_past_its_limit():
    """The PD carried the wrist to 2.9 rad, past Franka's 2.8973: the QP (position limits that
    hold the posture) still finds steps, instead of no solution at every step for good."""
    kin = ArmKinematics(0.01)
    past = np.array([0.48, 0.24, 0.19, -2.3, -0.08, 2.53, 2.9])
    v, solved = kin.step(past, np.zeros(7), np.array([0, 0, 0.3, 0, 0, 0.05]))
    assert solved and np.abs(v).max() > 0.05
    assert past[6] + v[6] * kin.period <= 2.9  # not further past the limit


@pytest.mark.parametrize(
    "url", [TABLE_URL, TRAY_URL, WASTE_BASKET_URL] + [c.url for c in CLASSES.values()]
)
def test_models_parse_offline(url):
    plant = _plant()
    (m,) = make_parser(plant).AddModelsFromUrl(url)
    plant.Finalize()
    assert plant.num_bodies() >= 2


def test_object_models_are_free_bodies_with_collision_boxes():
    for c in CLASSES.values():
        plant = _plant()
        (m,) = make_parser(plant).AddModelsFromUrl(c.url)
        plant.Finalize()
        body = plant.GetBodyByName(c.body, m)
        assert body.is_floating_base_body()
        assert 0.05 <= body.default_mass() <= 0.35
        assert plant.GetCollisionGeometriesForBody(body)


def test_diff_ik_stays_within_the_margined_limits_and_brakes_when_unsolved():
    """The safety monitor stops the arm at Franka's limits: the skills' differential IK must
    plan inside them, and where its QP has no solution decelerate instead of jumping to 0."""
    from tamp.sim.lots.kinematics import LIMIT_MARGIN

    kin = ArmKinematics(0.01)
    amax = np.array(ARM.max_acceleration)
    rng = np.random.default_rng(0)
    q, v = np.array(READY), np.zeros(7)
    for _ in range(40):  # a fast sweep: 0.5 m/s along y, turning
        v_new, ok = kin.step(q, v, np.r_[0.0, 0.0, 0.8, 0.0, 0.5, 0.1])
        assert ok
        assert np.all(np.abs(v_new) <= LIMIT_MARGIN * np.array(ARM.max_velocity) + 1e-6)
        assert np.all(np.abs(v_new - v) / 0.01 <= LIMIT_MARGIN * amax + 1e-6)
        q, v = q + v_new * 0.01, v_new
    # joint 1 past its upper limit: no velocity within the limits gets it back in one step
    q_out = np.array(READY)
    q_out[0] = ARM.upper[0] + 0.1
    v7 = rng.uniform(-1.5, 1.5, 7)
    braked, ok = kin.step(q_out, v7, np.zeros(6))
    assert not ok
    np.testing.assert_allclose(braked, kin.brake(v7))
    dv = np.abs(braked - v7) / 0.01
    assert np.all(dv <= LIMIT_MARGIN * amax + 1e-9)  # never beyond the limit
    assert np.all(np.abs(braked) <= np.abs(v7)) and np.all(np.sign(braked) * np.sign(v7) >= 0)
    # braking repeatedly comes to rest
    for _ in range(200):
        v7 = kin.brake(v7)
    assert np.all(v7 == 0.0)


def test_diff_ik_towards_a_far_target_from_rest_accelerates_within_the_limit():
    """A desired TCP velocity far beyond reach in one step (Drake's ``kStuck``: tiny alpha)
    still gives a small step in its direction, not a standstill."""
    from tamp.sim.lots.kinematics import LIMIT_MARGIN

    kin = ArmKinematics(0.01)
    q = np.array(READY)
    V = np.r_[0.0, 0.0, 0.0, 0.0, 30.0, 0.0]  # 30 m/s along y: alpha ~ 0
    v, ok = kin.step(q, np.zeros(7), V)
    assert np.any(v != 0.0)
    assert np.all(np.abs(v) / 0.01 <= LIMIT_MARGIN * np.array(ARM.max_acceleration) + 1e-6)
    X0, X1 = kin.tcp_pose(q), kin.tcp_pose(q + v * 0.01)
    d = X1.translation() - X0.translation()
    assert d[1] > 0 and abs(d[0]) < 0.1 * d[1] and abs(d[2]) < 0.1 * d[1]
