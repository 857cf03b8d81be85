"""Recordings and live views open framed on the workcell: Meshcat's camera looks at the
bounds of the cell's geometry, and the saved HTML carries that camera; the Drake diagram is
drawn through Graphviz by the file's suffix."""

from __future__ import annotations

import base64
import math
import re
import struct

import numpy as np
import pytest
from pydrake.geometry import Meshcat

from tamp.sim.core.recording import camera_for, live_view, new_meshcat
from tamp.sim.core.workcell import get

CAMERA = b"/Cameras/default/rotated/<object>"


def camera_position(html: str) -> tuple[float, float, float] | None:
    """The camera position a static Meshcat page sets (its msgpack command, decoded)."""
    for blob in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html):
        data = base64.b64decode(blob)
        if CAMERA in data and b"position" in data:
            i = data.index(b"\xa5value\x93") + len(b"\xa5value\x93")
            values = []
            for _ in range(3):
                assert data[i] == 0xCB  # msgpack float 64
                values.append(struct.unpack(">d", data[i + 1 : i + 9])[0])
                i += 9
            return tuple(values)
    return None


def test_camera_for_fits_the_box_in_the_field_of_view():
    position, target = camera_for([0, 0, 0], [2, 1, 0.5], fov_deg=60)
    assert np.allclose(target, [1, 0.5, 0.25])
    radius = 0.5 * math.sqrt(4 + 1 + 0.25)
    distance = np.linalg.norm(position - target)
    assert math.isclose(distance * math.sin(math.radians(30)), radius)
    assert position[2] > target[2]  # from above


@pytest.mark.parametrize("name, main", [("smp-mro", "case1"), ("lots", "tower")])
def test_the_saved_page_opens_on_the_cell(name, main, tmp_path):
    meshcat = Meshcat(0)
    assert camera_position(meshcat.StaticHtml()) is None  # Meshcat's default view
    cell = get(name)
    cell.build(cell.load(main), meshcat=meshcat)
    position = camera_position(meshcat.StaticHtml())
    assert position is not None
    assert 0.5 < float(np.linalg.norm(position)) < 15.0  # near the cell, not at infinity


def test_a_live_view_is_the_meshcat_every_run_draws_into():
    with live_view() as viewer:
        assert new_meshcat() is viewer
    assert new_meshcat() is not viewer


def test_the_diagram_is_drawn_by_its_suffix(tmp_path):
    from tamp.commands.simulate import write_diagram

    cell = get("smp-mro")
    scenario = cell.load("case1")
    write_diagram(cell, scenario, str(tmp_path / "d.svg"))
    svg = (tmp_path / "d.svg").read_text()
    assert "<svg" in svg and "plant" in svg


def test_the_bounds_are_the_shapes_own_boxes_not_spheres_around_them():
    """A 1 x 0.5 x 0.1 m table top at 0.4 m, turned 90 degrees about z, and a 5 cm sphere:
    the bounds are exact (a sphere around the box would reach 0.56 m down and up)."""
    from pydrake.geometry import Box, Sphere
    from pydrake.math import RigidTransform, RollPitchYaw
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.multibody.tree import SpatialInertia
    from pydrake.systems.framework import DiagramBuilder

    from tamp.sim.core.recording import cell_bounds

    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    X_top = RigidTransform(RollPitchYaw(0, 0, math.pi / 2), [0, 0, 0.4])
    plant.RegisterVisualGeometry(plant.world_body(), X_top, Box(1.0, 0.5, 0.1), "top", [1] * 4)
    ball = plant.AddRigidBody("ball", SpatialInertia.SolidSphereWithMass(0.1, 0.05))
    plant.RegisterVisualGeometry(ball, RigidTransform(), Sphere(0.05), "ball", [1] * 4)
    plant.SetDefaultFreeBodyPose(ball, RigidTransform([0.3, 0.0, 0.5]))
    plant.Finalize()
    lower, upper = cell_bounds(builder, scene_graph)
    assert np.allclose(lower, [-0.25, -0.5, 0.35], atol=1e-9)
    assert np.allclose(upper, [0.35, 0.5, 0.55], atol=1e-9)
