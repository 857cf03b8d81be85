"""The LOTS plant sets objects down as they are: a flat object let go a few millimetres above
the table lands flat and stays there (the hydroelastic margin, `HYDROELASTIC_MARGIN`)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import tamp.sim.lots.plant as lots_plant
from tamp.sim.core.models import with_hydroelastic_margin
from tamp.sim.lots.catalogue import CLASSES
from tamp.sim.lots.scenario import CellObject, load_cell_scenario

#: the person lets go with the object's underside 7 mm up (`person.GRIP_GAP + DROP_GAP`);
#: a place lets go lower. 1 mm was the worst height without the margin.
HEIGHTS = (0.001, 0.004)


def drop(cls: str, height: float) -> tuple[float, float]:
    """Let an object of ``cls`` fall flat from ``height`` onto the bare table of the tower
    cell (4 ms SAP steps); the largest angular speed on the way (rad/s) and its final tilt
    (rad) after 0.6 s."""
    cell = load_cell_scenario("tower")
    obj = CellObject(f"{cls}_0", cls, "A", (0.0, 0.0), 0.0, (0.5, 0.5, 0.5))
    cell = dataclasses.replace(cell, objects=(obj,))
    builder = DiagramBuilder()
    cp = lots_plant.add_cell_plant(builder, cell)
    diagram = builder.Build()
    sim = Simulator(diagram)
    plant, body = cp.plant, cp.bodies[obj.id]
    context = plant.GetMyContextFromRoot(sim.get_mutable_context())
    X = plant.EvalBodyPoseInWorld(context, body)
    plant.SetFreeBodyPose(context, body, RigidTransform(X.translation() + [0, 0, height]))
    fastest = 0.0
    for k in range(1, 61):
        sim.AdvanceTo(0.01 * k)
        V = plant.EvalBodySpatialVelocityInWorld(context, body)
        fastest = max(fastest, float(np.linalg.norm(V.rotational())))
    rpy = RollPitchYaw(plant.EvalBodyPoseInWorld(context, body).rotation()).vector()
    return fastest, float(np.hypot(rpy[0], rpy[1]))


@pytest.mark.parametrize("cls", sorted(CLASSES))
def test_an_object_let_go_flat_lands_flat(cls):
    for height in HEIGHTS:
        spin, tilt = drop(cls, height)
        assert spin < 0.2, (cls, height, spin)
        assert tilt < 0.01, (cls, height, tilt)


def test_without_the_margin_a_light_object_is_thrown_spinning(monkeypatch):
    """The control: margin 0 (Drake's default) lets the step carry the car into the table and
    throw it back: the spin this module's test rules out."""
    monkeypatch.setattr(lots_plant, "HYDROELASTIC_MARGIN", 0.0)
    spins = [drop(cls, 0.001)[0] for cls in ("toy_car", "wrench", "saw")]
    assert max(spins) > 5.0, spins


def test_the_margin_goes_on_compliant_collisions_that_lack_one():
    sdf = (
        "<collision name='a'><drake:proximity_properties><drake:compliant_hydroelastic/>"
        "</drake:proximity_properties></collision>"
        "<collision name='b'><drake:proximity_properties><drake:rigid_hydroelastic/>"
        "</drake:proximity_properties></collision>"
        "<collision name='c'><drake:proximity_properties><drake:compliant_hydroelastic/>"
        "<drake:hydroelastic_margin>0.0001</drake:hydroelastic_margin>"
        "</drake:proximity_properties></collision>"
    )
    out = with_hydroelastic_margin(sdf, 0.002)
    a, b, c = out.split("</collision>")[:3]
    assert "<drake:hydroelastic_margin>0.002</drake:hydroelastic_margin>" in a
    assert "margin" not in b
    assert c.count("hydroelastic_margin>") == 2 and "0.0001" in c and "0.002" not in c
