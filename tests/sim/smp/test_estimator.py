"""WorldStateEstimator: the symbolic state read from the plant matches the demonstration."""

from __future__ import annotations

import math

import pytest
from pydrake.math import RigidTransform

from tamp.sim.smp.scenario import load_scenario
from tamp.sim.smp.station import build_station
from tamp.world.interface import Status
from tamp.world.predicates import IsAreaFree, IsHandFree, IsObjectAt, IsRobotCloseTo

from .helpers import packaged


class Idle:
    """A policy that never acts (picklable, module level)."""

    reason = ""

    def tick(self, world):
        return Status.RUNNING


@pytest.mark.parametrize("case", [1, 2, 3])
def test_initial_world_state_matches_the_demonstration(case):
    scenario = load_scenario(packaged(f"case{case}.yaml"))
    system = build_station(scenario, Idle())
    root = system.diagram.CreateDefaultContext()
    est = system.estimator
    world = est.world_state_port.Eval(est.GetMyContextFromRoot(root))
    demo_world = scenario.demo.initial_world()
    assert world.held is None and IsHandFree().holds(world)
    assert set(world.areas) == set(demo_world.areas)
    # appearing objects wait unseen outside the workspace
    assert set(world.objects) == set(demo_world.objects)
    for uid, o in demo_world.objects.items():
        assert world.objects[uid].pos.planar_distance(o.pos) < 1e-6
        assert world.objects[uid].pos.z == pytest.approx(0.1, abs=0.002)  # centre of a bottle
    r = demo_world.robot
    assert world.robot.pos.planar_distance(r.pos) < 1e-9
    assert world.robot.orientation.yaw() == pytest.approx(r.orientation.yaw())
    # the same predicates hold on both
    for name in demo_world.areas:
        assert IsAreaFree(name).holds(world) == IsAreaFree(name).holds(demo_world)
    for uid in demo_world.objects:
        assert IsRobotCloseTo(uid).holds(world) == IsRobotCloseTo(uid).holds(demo_world)
        for g in scenario.demo.goals:
            pred = IsObjectAt(uid, g.area.name)
            assert pred.holds(world) == pred.holds(demo_world)


def test_an_object_moved_in_the_plant_is_seen_there():
    scenario = load_scenario(packaged("case3.yaml"))
    system = build_station(scenario, Idle())
    root = system.diagram.CreateDefaultContext()
    plant_ctx = system.plant.GetMyMutableContextFromRoot(root)
    area = system.areas["L1"]
    system.plant.SetFreeBodyPose(
        plant_ctx, system.bodies["Oa"], RigidTransform([area.pos.x, area.pos.y, 0.075])
    )
    est = system.estimator
    world = est.world_state_port.Eval(est.GetMyContextFromRoot(root))
    assert "Oa" in world.objects
    assert not IsAreaFree("L1").holds(world)
    assert math.isclose(world.objects["Oa"].pos.x, area.pos.x)
