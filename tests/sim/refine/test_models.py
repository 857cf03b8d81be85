"""The refinement models load offline (package://tamp_models) with the Pioneer's numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from tamp.sim.core.models import model_url, sdf_path
from tamp.sim.core.parsing import make_parser

ROBOTS = ("pioneer_lift", "pioneer_parallel")
OBJECTS = {"briefcase": 3.0, "scale": 2.0, "table": 8.0, "folding_chair": 4.0}


def load(name: str):
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.001)
    (model,) = make_parser(plant).AddModelsFromUrl(model_url(name))
    plant.Finalize()
    return plant, model


@pytest.mark.parametrize("name", ROBOTS)
def test_pioneer_dimensions_and_joints(name):
    plant, model = load(name)
    joints = {plant.get_joint(j).name() for j in plant.GetJointIndices(model)}
    assert {"base_x", "base_y", "base_yaw", "arm_pitch", "gripper_mount"} <= joints
    assert {"finger_left_joint", "finger_right_joint"} <= joints
    assert plant.num_actuators() == 6  # base x, y, yaw, arm, two fingers
    base = plant.GetBodyByName("base_link", model)
    assert base.default_mass() == pytest.approx(9.0)
    ctx = plant.CreateDefaultContext()
    arm = plant.GetJointByName("arm_pitch", model)
    assert arm.position_lower_limits()[0] == pytest.approx(-0.9)

    def tip_height(angle):
        arm.set_angle(ctx, angle)
        X = plant.CalcRelativeTransform(ctx, plant.world_frame(), plant.GetFrameByName("imu"))
        g = plant.CalcRelativeTransform(
            ctx, plant.world_frame(), plant.GetFrameByName("gripper_base")
        )
        return X, g.translation()[2]

    X0, h0 = tip_height(0.0)
    assert h0 == pytest.approx(0.20)  # lever horizontal at 0.20 m
    X1, h1 = tip_height(-0.7)
    assert h1 == pytest.approx(0.20 - 0.30 * math.sin(0.7), abs=1e-9)  # at the floor
    # positive pitch raises the lever (up is positive, the IMU reads it)
    _, h2 = tip_height(0.3)
    assert h2 > h0
    pitch = math.asin(X1.rotation().matrix()[2, 0])  # the lever's x axis, up positive
    assert pitch == pytest.approx(-0.7)


def test_wheels_are_pioneer_sized():
    text = sdf_path("pioneer_lift").read_text()
    assert "<radius>0.0975</radius>" in text  # 0.195 m wheels
    assert "0.455 0.381 0.197" in text  # body, 0.04 .. 0.237 m above the floor


@pytest.mark.parametrize("name,mass", sorted(OBJECTS.items()))
def test_objects_load(name, mass):
    plant, model = load(name)
    ctx = plant.CreateDefaultContext()
    assert plant.CalcTotalMass(ctx, [model]) == pytest.approx(mass)


def test_chair_hinge_opens_frame_b():
    plant, model = load("folding_chair")
    hinge = plant.GetJointByName("hinge", model)
    assert (hinge.position_lower_limits()[0], hinge.position_upper_limits()[0]) == (0.0, 1.2)
    ctx = plant.CreateDefaultContext()
    plant.SetFreeBodyPose(ctx, plant.GetBodyByName("frame_a"), RigidTransform())
    b = plant.GetBodyByName("frame_b")
    hinge.set_angle(ctx, 0.0)
    p0 = plant.EvalBodyPoseInWorld(ctx, b).multiply(np.array([-0.385, 0, 0]))
    hinge.set_angle(ctx, 1.0)
    p1 = plant.EvalBodyPoseInWorld(ctx, b).multiply(np.array([-0.385, 0, 0]))
    assert np.linalg.norm(p1 - p0) == pytest.approx(2 * 0.385 * math.sin(0.5))
    assert p1[2] == pytest.approx(p0[2])  # the hinge axis is vertical: it opens on the floor


@pytest.mark.parametrize("name,half", [("briefcase", 0.06), ("scale", 0.025)])
def test_objects_rest_on_the_floor(name, half):
    from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
    from pydrake.systems.analysis import Simulator

    builder = DiagramBuilder()
    config = MultibodyPlantConfig(
        time_step=0.002,
        discrete_contact_approximation="sap",
        contact_model="hydroelastic_with_fallback",
    )
    plant, _ = AddMultibodyPlant(config, builder)
    parser = make_parser(plant)
    (floor,) = parser.AddModelsFromUrl(model_url("floor"))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("floor", floor))
    (model,) = parser.AddModelsFromUrl(model_url(name))
    plant.Finalize()
    diagram = builder.Build()
    sim = Simulator(diagram)
    ctx = plant.GetMyMutableContextFromRoot(sim.get_mutable_context())
    body = plant.GetBodyByName(name, model)
    plant.SetFreeBodyPose(ctx, body, RigidTransform([0, 0, half + 0.01]))
    sim.AdvanceTo(0.5)
    z = plant.EvalBodyPoseInWorld(ctx, body).translation()[2]
    assert z == pytest.approx(half, abs=2e-3)
