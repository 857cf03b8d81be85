"""A chunked run whose physics goes non-finite stops there and says so (``sim_diverged``);
any other error from the diagram still propagates."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.geometry import Sphere
from pydrake.math import RigidTransform
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import (
    AddMultibodyPlantSceneGraph,
    CoulombFriction,
    ExternallyAppliedSpatialForce,
)
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder, LeafSystem

from tamp.sim.core.outcome import CAUSES
from tamp.sim.core.runner import make_simulator, run_in_chunks


class Push(LeafSystem):
    """A force on the ball: ``value`` (N, upwards) from ``after`` s of sim time on."""

    def __init__(self, body_index, value: float, after: float):
        super().__init__()
        self._body, self._value, self._after = body_index, value, after
        self.DeclareAbstractOutputPort(
            "force", lambda: AbstractValue.Make([ExternallyAppliedSpatialForce()]), self._calc
        )

    def _calc(self, context, output):
        if context.get_time() < self._after:
            output.set_value([])
            return
        f = ExternallyAppliedSpatialForce()
        f.body_index = self._body
        f.p_BoBq_B = np.zeros(3)
        f.F_Bq_W = SpatialForce(np.zeros(3), [0.0, 0.0, self._value])
        output.set_value([f])


def ball_run(value: float):
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, 0.004)
    ball = plant.AddRigidBody("ball", SpatialInertia.SolidSphereWithMass(0.1, 0.02))
    # a collision shape: the plant asks SceneGraph for contacts every step (its pose check)
    plant.RegisterCollisionGeometry(
        ball, RigidTransform(), Sphere(0.02), "c", CoulombFriction(0.5, 0.5)
    )
    plant.Finalize()
    push = builder.AddSystem(Push(ball.index(), value, after=0.3))
    builder.Connect(push.get_output_port(), plant.get_applied_spatial_force_input_port())
    simulator = make_simulator(builder.Build())
    return run_in_chunks(simulator, chunk=0.1, limit=1.0, between=lambda t: False)


def test_a_run_whose_plant_goes_non_finite_stops_and_says_when():
    run = ball_run(1e308)  # finite, but the next state is not
    assert run.diverged is not None and run.stopped
    assert "diverged at 0.30 s" in run.diverged and "non-finite" in run.diverged
    assert run.sim_time == pytest.approx(0.3, abs=0.01)
    assert "sim_diverged" in CAUSES


def test_a_finite_run_reaches_its_limit():
    run = ball_run(0.5)
    assert run.diverged is None and not run.stopped and run.sim_time == pytest.approx(1.0)


def test_other_errors_propagate():
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, 0.004)
    plant.Finalize()

    def boom(t: float) -> bool:
        raise RuntimeError("a bug in the caller")

    with pytest.raises(RuntimeError, match="a bug"):
        run_in_chunks(make_simulator(builder.Build()), chunk=0.1, limit=1.0, between=boom)
