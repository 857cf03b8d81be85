"""The model data: found as ``tamp.models`` (Drake's ``tamp_models``), parsed offline only."""

from __future__ import annotations

import pytest
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from tamp.sim.core.models import model_url, models_dir, package_xml, sdf_path
from tamp.sim.core.parsing import make_parser


def new_plant():
    """A plant registered with a SceneGraph (so collision geometry is kept)."""
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    return plant


def test_models_dir_holds_the_sdfs_and_the_weights():
    root = models_dir()
    assert package_xml() == root / "package.xml" and "<name>tamp_models</name>" in (
        package_xml().read_text()
    )
    for name in ("youbot", "bottle", "obstacle", "floor", "area_marker"):
        assert sdf_path(name).is_file(), name
        assert model_url(name) == f"package://tamp_models/sdf/{name}.sdf"
    assert (root / "weights" / "hrgnet_synth_rgbd.pt").stat().st_size > 100_000


def test_parser_refuses_remote_packages():
    plant = new_plant()
    parser = make_parser(plant)
    assert not parser.package_map().Contains("drake_models")
    assert parser.package_map().GetPath("tamp_models") == str(models_dir())
    with pytest.raises(RuntimeError):
        parser.AddModelsFromUrl("package://drake_models/iiwa_description/sdf/iiwa14.sdf")


def test_area_marker_and_floor_parse():
    plant = new_plant()
    parser = make_parser(plant)
    (marker,) = parser.AddModelsFromUrl(model_url("area_marker"))
    (floor,) = parser.AddModelsFromUrl(model_url("floor"))
    plant.Finalize()
    marker_body = plant.GetBodyByName("marker", marker)
    assert plant.GetCollisionGeometriesForBody(marker_body) == []  # visual only
    assert plant.GetCollisionGeometriesForBody(plant.GetBodyByName("floor", floor))
