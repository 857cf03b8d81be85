"""The SMP-MRO models (youBot-like robot, bottle, obstacle): youBot numbers, physical inertias."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from tamp.sim.core.parsing import make_parser
from tamp.sim.smp.robot import HOME_ARM, OBJECT_KINDS, ROBOT


def new_plant():
    """A plant registered with a SceneGraph (so collision geometry is kept)."""
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    return plant


@pytest.fixture(scope="module")
def robot_plant():
    plant = new_plant()
    make_parser(plant).AddModelsFromUrl(ROBOT.url)
    plant.Finalize()
    return plant


def test_joint_limits_are_the_youbots(robot_plant):
    deg = math.radians
    expected = {
        "arm_joint_1": (-deg(169), deg(169)),
        "arm_joint_2": (-deg(65), deg(90)),
        "arm_joint_3": (-deg(151), deg(146)),
        "arm_joint_4": (-deg(102.5), deg(102.5)),
        "arm_joint_5": (-deg(167.5), deg(167.5)),
    }
    for name, (lo, hi) in expected.items():
        j = robot_plant.GetJointByName(name)
        assert j.position_lower_limits()[0] == pytest.approx(lo, abs=1e-3)
        assert j.position_upper_limits()[0] == pytest.approx(hi, abs=1e-3)
    assert robot_plant.num_actuators() == len(ROBOT.joints)


def test_link_lengths_and_base_size(robot_plant):
    ctx = robot_plant.CreateDefaultContext()

    def origin(body: str) -> np.ndarray:
        return robot_plant.EvalBodyPoseInWorld(ctx, robot_plant.GetBodyByName(body)).translation()

    # arm straight up: joint 2 is 0.147 m above the arm plate, then 0.155, 0.135, 0.081
    assert origin("arm_link_2")[2] - origin("arm_link_0")[2] == pytest.approx(0.147)
    assert np.linalg.norm(origin("arm_link_3") - origin("arm_link_2")) == pytest.approx(0.155)
    assert np.linalg.norm(origin("arm_link_4") - origin("arm_link_3")) == pytest.approx(0.135)
    assert np.linalg.norm(origin("gripper_palm") - origin("arm_link_4")) == pytest.approx(0.081)
    box = robot_plant.GetCollisionGeometriesForBody(robot_plant.GetBodyByName("base_link"))
    assert len(box) == 1
    assert ROBOT.footprint_radius == pytest.approx(math.hypot(0.29, 0.19), abs=0.005)


def test_inertias_are_physical(robot_plant):
    ctx = robot_plant.CreateDefaultContext()
    total = 0.0
    for i in robot_plant.GetBodyIndices(robot_plant.GetModelInstanceByName("youbot")):
        body = robot_plant.get_body(i)
        M = body.CalcSpatialInertiaInBodyFrame(ctx)
        assert M.IsPhysicallyValid(), body.name()
        total += body.default_mass()
    assert 25.0 < total < 35.0  # youBot: ~20 kg base + ~5 kg arm


@pytest.mark.parametrize("name", sorted(OBJECT_KINDS))
def test_objects_match_their_kind(name):
    kind = OBJECT_KINDS[name]
    plant = new_plant()
    (m,) = make_parser(plant).AddModelsFromUrl(kind.url)
    plant.Finalize()
    body = plant.GetBodyByName(kind.body, m)
    assert body.default_mass() == pytest.approx(kind.mass)
    assert len(plant.GetCollisionGeometriesForBody(body)) >= 1


def test_ready_pose_is_within_limits(robot_plant):
    for name, q in zip(ROBOT.arm_joints, HOME_ARM, strict=True):
        j = robot_plant.GetJointByName(name)
        assert j.position_lower_limits()[0] <= q <= j.position_upper_limits()[0]
