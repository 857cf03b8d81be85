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
