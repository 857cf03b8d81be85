"""The LOTS plant's contact geometry: objects' compliant boxes meshed as convex shapes
(`tamp.sim.lots.plant.coarse_compliant_boxes`) rest steadily with few contact polygons."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tamp.sim.lots.plant import box_obj
from tamp.sim.lots.scenario import load_cell_scenario


def test_box_obj_is_the_box_centred_on_its_frame():
    text = box_obj((0.07, 0.04, 0.05))
    lines = text.splitlines()
    verts = np.array([[float(v) for v in ln.split()[1:]] for ln in lines if ln[0] == "v"])
    faces = [ln for ln in lines if ln[0] == "f"]
    assert verts.shape == (8, 3) and len(faces) == 12
    assert np.allclose(verts.max(axis=0), [0.035, 0.02, 0.025])
    assert np.allclose(verts.min(axis=0), [-0.035, -0.02, -0.025])


def _cell(contact_model: str = "hydroelastic_with_fallback"):
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder

    from tamp.sim.lots.plant import add_cell_plant

    base = load_cell_scenario("tower")
    scenario = dataclasses.replace(
        base, plant=dataclasses.replace(base.plant, contact_model=contact_model)
    )
    builder = DiagramBuilder()
    cell = add_cell_plant(builder, scenario)
    sim = Simulator(builder.Build())
    pc = cell.plant.GetMyContextFromRoot(sim.get_mutable_context())
    q = cell.q0[cell.actuator_order]
    cell.plant.get_desired_state_input_port(cell.arm).FixValue(pc, np.r_[q, np.zeros(len(q))])
    return cell, sim, pc


def _shapes(cell) -> list[str]:
    inspector = cell.scene_graph.model_inspector()
    return [
        type(inspector.GetShape(g)).__name__
        for body in cell.bodies.values()
        for g in cell.plant.GetCollisionGeometriesForBody(body)
    ]


@pytest.mark.slow
def test_objects_rest_on_few_contact_polygons():
    cell, sim, pc = _cell()
    assert set(_shapes(cell)) == {"Convex"}
    start = {u: cell.plant.EvalBodyPoseInWorld(pc, b).translation() for u, b in cell.bodies.items()}
    sim.AdvanceTo(0.5)
    results = cell.plant.get_contact_results_output_port().Eval(pc)
    faces = [
        results.hydroelastic_contact_info(i).contact_surface().num_faces()
        for i in range(results.num_hydroelastic_contacts())
    ]
    # one surface per resting box (the peak: two boxes, one on the table); Drake's own box
    # mesh made 26-35 polygons each
    assert len(faces) == len(cell.bodies) and max(faces) <= 16
    for uid, body in cell.bodies.items():
        p = cell.plant.EvalBodyPoseInWorld(pc, body).translation()
        assert np.linalg.norm(p - start[uid]) < 3e-4, uid  # at rest: sunk < 0.3 mm, no drift


@pytest.mark.slow
def test_point_contact_keeps_the_boxes():
    cell, _, _ = _cell("point")
    assert set(_shapes(cell)) == {"Box"}
