"""The refinement models load offline (package://tamp_models) with the Pioneer's numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
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


def test_chair_latch_swings_up_one_way_only():
    """The latch under frame_b's handle bar hangs to 3 cm above the floor and swings up
    towards +x (a fork passes under it); its limit stops it the other way (the hook)."""
    plant, model = load("folding_chair")
    latch = plant.GetJointByName("latch", model)
    assert latch.position_lower_limits()[0] == 0.0 and latch.position_upper_limits()[0] > 1.0
    ctx = plant.CreateDefaultContext()
    plate = plant.GetBodyByName("latch_plate")
    bottom = np.array([0.0, 0.0, -0.105])
    p0 = plant.EvalBodyPoseInWorld(ctx, plate).multiply(bottom)
    assert p0[2] == pytest.approx(0.031, abs=1e-6)
    latch.set_angle(ctx, 0.5)
    p1 = plant.EvalBodyPoseInWorld(ctx, plate).multiply(bottom)
    assert p1[0] > p0[0] + 0.04 and p1[2] > p0[2]  # up and away from Robot 1 (-x side)


def test_outcome_reads_the_hinge_and_the_tilt():
    """`outcome.measure` reads joint angles and object poses on the plant, and the scene's
    goals judge them (no program numbers involved)."""
    from tamp.sim.refine.outcome import measure, start_heights
    from tamp.sim.refine.scenario import load_scene

    goals = load_scene("open_chair").goals

    plant, model = load("folding_chair")
    ctx = plant.CreateDefaultContext()
    frame_a = plant.GetBodyByName("frame_a")
    plant.SetFreeBodyPose(ctx, frame_a, RigidTransform())
    objects = {"folding_chair": model}
    heights = start_heights(plant, ctx, objects)
    hinge = plant.GetJointByName("hinge", model)
    hinge.set_angle(ctx, 0.2)
    closed = measure(plant, ctx, objects, heights, goals)
    assert closed.values["folding_chair.hinge"] == pytest.approx(0.2)
    assert not closed.achieved and "hinge" in closed.failed()[0]
    hinge.set_angle(ctx, 0.6)
    tilted = RigidTransform(RotationMatrix.MakeYRotation(0.3), [0.0, 0.0, 0.05])
    plant.SetFreeBodyPose(ctx, frame_a, tilted)
    opened = measure(plant, ctx, objects, heights, goals)
    assert opened.achieved and opened.failed() == []
    assert opened.values["folding_chair.tilt"] == pytest.approx(0.3)
    assert opened.values["folding_chair.rise"] == pytest.approx(0.05)
    assert "met" in opened.summary() and opened.to_json()["achieved"] is True


@pytest.mark.parametrize(
    "task,body",
    [("task2", "scale"), ("task3", "scale"), ("task1", "briefcase"), ("task4", "frame_a")],
)
def test_objects_lie_still_in_the_workcell(task, body):
    """At the step each task runs at (10 ms; the chair's and the table's scenes 20 ms for
    slow programs) no object moves by itself before a robot touches it (the scale at
    modulus 5e6 flipped itself over within a second; at a 20 ms step the scale on the
    floor slides 0.26 m in 1.5 s, so the flip scenes keep 10 ms)."""
    from tamp.refine.architecture import default_architecture
    from tamp.refine.loader import load_program
    from tamp.sim.core.runner import make_simulator
    from tamp.sim.refine.scenario import load_scene
    from tamp.sim.refine.station import build_station

    program = load_program(task)
    cell = build_station(program, default_architecture(), load_scene(program.scene))
    assert cell.time_step == (0.02 if task in ("task3", "task4") else 0.01)
    sim = make_simulator(cell.diagram)
    sim.Initialize()
    ctx = cell.plant.GetMyContextFromRoot(sim.get_mutable_context())
    b = cell.plant.GetBodyByName(body)
    X0 = cell.plant.EvalBodyPoseInWorld(ctx, b)
    sim.AdvanceTo(1.5)
    X1 = cell.plant.EvalBodyPoseInWorld(ctx, b)
    assert np.linalg.norm(X1.translation() - X0.translation()) < 2e-3
    angle = X0.rotation().InvertAndCompose(X1.rotation()).ToAngleAxis().angle()
    assert angle < 0.01
