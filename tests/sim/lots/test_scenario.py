"""The workcell scenario loader: packaged files load; bad input names file and field."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tamp.errors import InputError
from tamp.sim.lots.catalogue import CLASSES
from tamp.sim.lots.scenario import load_cell_scenario, rectangles_overlap
from tests.sim.lots.helpers import write_scenario
from tests.sim.lots.snapshot import SNAPSHOT, normalise, packaged_files


def snapshot_layout(loaded: dict) -> dict:
    """A normalised scenario in the snapshot's layout (the snapshot was written by the loader
    the typed one replaced): the ``plant`` section's fields at the top, no ``description``
    and no ``classes`` of their own (packaged files have none), no ``stack`` (a field the
    replaced loader did not have: `tests/sim/lots/test_stack.py` checks it), no
    ``camera.detector`` (every packaged file reads its views with the oracle), no
    ``grasp.descent.approach`` (every packaged file approaches closed loop, a field the
    replaced loader did not have), and the never-set ``extra`` mapping."""
    out = dict(loaded)
    out.update(out.pop("plant"))
    assert out.pop("description") == "" and out.pop("classes") == {}
    out.pop("stack")
    assert out["camera"].pop("detector") == "oracle"
    assert out["grasp"]["descent"].pop("approach") == "closed"
    out["extra"] = {}
    return out


def test_the_typed_loader_reads_every_packaged_file_as_the_snapshot_says():
    want = json.loads(SNAPSHOT.read_text())
    files = packaged_files()
    assert sorted(p.name for p in files) == sorted(want)
    for path in files:
        got = json.loads(json.dumps(snapshot_layout(normalise(load_cell_scenario(path)))))
        assert got == want[path.name], path.name


def test_packaged_model_building_loads():
    s = load_cell_scenario("model_building")
    assert [o.cls for o in s.objects] == ["saw", "scissors", "scissors", "hammer"]
    assert {o.workspace for o in s.objects} == {"A"}
    # instances of one class get different colours
    assert s.objects[1].rgb != s.objects[2].rgb
    assert s.camera.width == 320 and s.camera.height == 180


@pytest.mark.parametrize(
    ("objects", "changes", "field"),
    [
        ([{"class": "anvil", "workspace": "A", "xy": [0, 0]}], {}, "objects[0].class"),
        ([{"class": "saw", "workspace": "C", "xy": [0, 0]}], {}, "objects[0].workspace"),
        ([{"class": "saw", "workspace": "A", "xy": [0.12, 0]}], {}, "objects[0].xy"),
        (
            [{"class": "body", "workspace": "A", "xy": [0, 0], "colour": [1, 0, 0]}],
            {},
            "objects[0].colour",
        ),
        (
            [
                {"class": "body", "workspace": "A", "xy": [0, 0]},
                {"class": "body", "workspace": "A", "xy": [0.03, 0]},
            ],
            {},
            "objects[1]",
        ),
        ([], {"camera": {"width": 8}}, "camera.width"),
        ([], {"grasp": {"descent": {"window": 2, "min_views": 3}}}, "grasp.descent.min_views"),
        ([], {"grasp": {"predictor": "yolo"}}, "grasp.predictor"),
        ([], {"grasp": {"descent": {"approach": "sideways"}}}, "grasp.descent.approach"),
        ([], {"grasp": {"network": "yolo"}}, "grasp.network"),
        ([], {"waste_basket": [0.5, 0.05]}, "waste_basket"),
        ([], {"waste_basket": [2.0, 0.0]}, "waste_basket"),
        ([], {"plant": {"time_step": 0.5}}, "plant.time_step"),
        ([], {"speed": 1}, "speed"),
        # relations between fields, checked once the sections are read
        (
            [],
            {"control": {"period": 0.003, "perception_period": 0.02, "command_period": 0.001}},
            "control.period",  # shorter than the plant's step (0.004 s)
        ),
        ([], {"control": {"perception_period": 0.005}}, "control.perception_period"),
        ([], {"safety": {"check_period": 0.015}}, "safety.check_period"),
        (
            [],
            {"grasp": {"descent": {"explore_speed": 0.2, "commit_speed": 0.1}}},
            "grasp.descent.commit_speed",
        ),
        (
            [],
            {
                "workspaces": {
                    "A": {"center": [0.5, 0.25], "size": [0.34, 0.34], "tray": True},
                    "B": {"center": [0.5, -0.25], "size": [0.34, 0.34]},
                }
            },
            "workspaces.A.tray",
        ),
        (
            [
                {"class": "body", "workspace": "A", "xy": [0, 0.1], "id": "b"},
                {"class": "body", "workspace": "A", "xy": [0, -0.1], "id": "b"},
            ],
            {},
            "objects[1].id",
        ),
        (
            [{"class": "body", "workspace": "A", "xy": [0, 0], "color": [1, 2, 0]}],
            {},
            "objects[0].color",
        ),
    ],
)
def test_bad_scenarios_name_the_field(tmp_path, objects, changes, field):
    path = write_scenario(tmp_path, objects, **changes)
    with pytest.raises(InputError) as err:
        load_cell_scenario(path)
    assert err.value.field == field
    assert err.value.file == str(path)


def test_every_network_loads_with_its_shipped_weights_or_names_the_field(tmp_path, monkeypatch):
    from tamp.sim.lots import scenario

    for net in scenario.NETWORKS:
        path = write_scenario(tmp_path, [], grasp={"network": net})
        assert load_cell_scenario(path).grasp.network == net
    # a network without shipped weights (and none given) is refused, naming the field
    monkeypatch.setattr(scenario, "DEFAULT_WEIGHTS", {"hrgnet": "weights/hrgnet_synth_rgbd.pt"})
    path = write_scenario(tmp_path, [], grasp={"network": "ggcnn"})
    with pytest.raises(InputError) as err:
        load_cell_scenario(path)
    assert err.value.field == "grasp.network" and "no shipped weights" in str(err.value)


def test_workspaces_must_be_apart(tmp_path):
    ws = {
        "A": {"center": [0.5, 0.1], "size": [0.3, 0.3]},
        "B": {"center": [0.5, -0.1], "size": [0.3, 0.3]},
    }
    with pytest.raises(InputError, match="side by side"):
        load_cell_scenario(write_scenario(tmp_path, [], workspaces=ws))


def test_footprints_come_from_the_sdf():
    hammer = CLASSES["hammer"].footprint
    assert (hammer.xmin, hammer.xmax, hammer.ymin, hammer.top) == (-0.1, 0.1, -0.045, 0.035)
    for c in CLASSES.values():  # low tools, each fits a 0.34 m workspace
        assert 0.0 < c.footprint.top <= 0.06, c.name
        assert c.footprint.xmax - c.footprint.xmin <= 0.25, c.name


def test_rectangles_overlap():
    a = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    assert rectangles_overlap(a, a + [0.5, 0.5])
    assert not rectangles_overlap(a, a + [1.2, 0])
    assert rectangles_overlap(a, a + [1.005, 0], gap=0.01)
    turned = np.array([[1.5, 0.5], [2.0, 0.0], [2.5, 0.5], [2.0, 1.0]])
    assert not rectangles_overlap(a, turned)
