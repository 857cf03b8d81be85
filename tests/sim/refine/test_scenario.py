"""Refinement scenes are YAML: the packaged five as they were, a user's scene with a model
of its own simulated through the public API, and bad scene files refused naming the field."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml

from tamp.commands.main import main as tamp_main
from tamp.errors import InputError
from tamp.refine.loader import load_program, packaged_scenes
from tamp.refine.measure import Goal
from tamp.scenarios import resolve
from tamp.sim.core.models import model_url
from tamp.sim.refine.scenario import load_scene

#: The scenes as the workcell held them before they were files: name -> objects
#: (model, x, y, z, yaw, fixed) and goals (quantity, at_least, what).
PACKAGED = {
    "flip_briefcase": (
        [("briefcase", 0.0, 0.0, 0.06, math.pi / 2, False)],
        [("briefcase.tilt", 1.45, "the briefcase turned over")],
    ),
    "flip_scale": (
        [("scale", 0.0, 0.0, 0.025, math.pi / 2, False)],
        [("scale.tilt", 1.45, "the scale turned over")],
    ),
    "lift_scale": (
        [("table", 0.10, 0.0, 0.0, 0.0, True), ("scale", 0.0, 0.0, 0.305, 0.0, False)],
        [
            ("scale.tilt", 0.15, "the scale tilted up off the table"),
            ("scale.rise", 0.02, "the scale's centre rose"),
        ],
    ),
    "table": ([("table", 0.10, 0.0, 0.0, 0.0, True)], []),
    "open_chair": (
        [("folding_chair", 0.0, 0.0, 0.0, 0.0, False)],
        [("folding_chair.hinge", 0.35, "the chair opened at its hinge")],
    ),
}

#: A small crate with a hinged lid: a model the project does not ship.
CRATE_SDF = """<?xml version="1.0"?>
<sdf version="1.9">
  <model name="crate">
    <link name="body">
      <inertial><mass>1.0</mass>
        <inertia><ixx>0.004</ixx><iyy>0.004</iyy><izz>0.007</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>
      <collision name="body"><geometry><box><size>0.2 0.2 0.1</size></box></geometry>
        <drake:proximity_properties>
          <drake:compliant_hydroelastic/>
          <drake:hydroelastic_modulus>1e6</drake:hydroelastic_modulus>
        </drake:proximity_properties>
      </collision>
      <visual name="body"><geometry><box><size>0.2 0.2 0.1</size></box></geometry></visual>
    </link>
    <link name="lid">
      <pose>0 0 0.055 0 0 0</pose>
      <inertial><mass>0.1</mass>
        <inertia><ixx>0.0003</ixx><iyy>0.0003</iyy><izz>0.0006</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>
      <visual name="lid"><geometry><box><size>0.2 0.2 0.01</size></box></geometry></visual>
    </link>
    <joint name="lid_hinge" type="revolute">
      <parent>body</parent><child>lid</child>
      <pose>-0.1 0 0 0 0 0</pose>
      <axis><xyz>0 1 0</xyz><limit><lower>0</lower><upper>1.5</upper></limit></axis>
    </joint>
  </model>
</sdf>
"""


def scene_data(**changes) -> dict:
    data = {
        "version": 1,
        "name": "crate_scene",
        "description": "A crate of the user's own beside the robots' line.",
        "objects": [
            {"model": "models/crate.sdf", "name": "my_crate", "x": 0.0, "y": -0.6, "z": 0.05}
        ],
        "goals": [
            {
                "quantity": "my_crate.tilt",
                "at_least": 0.0,
                "at_most": 0.1,
                "what": "the crate stayed upright",
            },
            {"quantity": "my_crate.lid_hinge", "at_least": 0.0, "what": "the lid is there"},
        ],
    }
    data.update(changes)
    return data


def write_scene(tmp_path: Path, data: dict, name: str = "crate_scene.yaml") -> Path:
    (tmp_path / "models").mkdir(exist_ok=True)
    (tmp_path / "models" / "crate.sdf").write_text(CRATE_SDF)
    f = tmp_path / name
    f.write_text(yaml.safe_dump(data, sort_keys=False))
    return f


def program_in(tmp_path: Path, scene: str) -> Path:
    """The short Task 4 program with its scene replaced (architecture made absolute)."""
    src = resolve("task4_short", "refine")
    data = yaml.safe_load(src.read_text())
    data["scene"] = scene
    data["architecture"] = str(src.parent / data["architecture"])
    f = tmp_path / "program.yaml"
    f.write_text(yaml.safe_dump(data, sort_keys=False))
    return f


def test_the_packaged_scenes_hold_what_the_workcell_held():
    assert packaged_scenes() == tuple(sorted(PACKAGED))
    for name, (objects, goals) in PACKAGED.items():
        scene = load_scene(name)
        assert scene.name == name and scene.description
        got = [(o.name, o.x, o.y, o.z, o.yaw, o.fixed) for o in scene.objects]
        assert got == objects, name
        assert [o.model for o in scene.objects] == [model_url(o[0]) for o in objects]
        assert scene.goals == tuple(Goal(q, lo, what) for q, lo, what in goals), name


def test_every_packaged_program_names_a_packaged_scene():
    for name in ("task1", "task2", "task3", "task4", "task4_short", "table_collision"):
        assert load_scene(load_program(name).scene).name == load_program(name).scene


def test_a_users_scene_with_its_own_model_is_simulated(tmp_path):
    """A new scene (a crate from an SDF beside the scene file) named by a program file as a
    path relative to it: loaded, built and run for a second through the public API."""
    from tamp.refine.architecture import load_architecture
    from tamp.sim.refine.simulate import simulate

    write_scene(tmp_path, scene_data())
    program = load_program(program_in(tmp_path, "crate_scene.yaml"))
    assert program.scene == str(tmp_path / "crate_scene.yaml")
    scene = load_scene(program.scene)
    (crate,) = scene.objects
    assert crate.model == str((tmp_path / "models" / "crate.sdf").resolve())
    assert crate.name == "my_crate"
    assert (crate.yaw, crate.fixed) == (0.0, False)  # the defaults
    run = simulate(program, load_architecture(program.architecture), max_sim_time=1.0)
    values = run.outcome.values
    assert set(values) == {"my_crate.tilt", "my_crate.rise", "my_crate.lid_hinge"}
    assert abs(values["my_crate.rise"]) < 0.01  # it lies on the floor (0.05 m)
    assert run.outcome.achieved, run.outcome.failed()
    assert "my_crate.tilt" in run.outcome.summary() and "in [0, 0.1]" in run.outcome.summary()
    assert run.collisions == {}
    assert run.sim_time == pytest.approx(1.0, abs=0.06)


def test_refine_refuses_a_bad_scene_with_exit_2(tmp_path, capsys):
    bad = scene_data(
        goals=[{"quantity": "my_crate.tilt", "at_least": 0.2, "at_most": 0.1, "what": "x"}]
    )
    write_scene(tmp_path, bad)
    program = program_in(tmp_path, "crate_scene.yaml")
    assert tamp_main(["refine", str(program), "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["file"] == str(tmp_path / "crate_scene.yaml")
    assert doc["field"] == "goals[0].at_most"


def test_a_program_naming_no_scene_is_refused(tmp_path):
    with pytest.raises(InputError) as e:
        load_program(program_in(tmp_path, "missing_scene.yaml"))
    assert e.value.field == "scene" and "no packaged scene 'missing_scene.yaml'" in str(e.value)


OBJ = "objects[0]"


@pytest.mark.parametrize(
    "change,field,words",
    [
        ({"colour": "red"}, "colour", "unknown key"),
        ({"objects": []}, "objects", "at least 1"),
        (
            {"objects": [{"model": "crate.sdf", "x": 0, "y": 0, "z": 0}]},
            f"{OBJ}.model",
            "no model file 'crate.sdf'",
        ),
        (
            {"objects": [{"model": "./crate_scene.yaml", "x": 0, "y": 0, "z": 0}]},
            f"{OBJ}.model",
            "expected an SDFormat file (.sdf)",
        ),
        (
            {"objects": [{"model": "barrel", "x": 0, "y": 0, "z": 0}]},
            f"{OBJ}.model",
            "no packaged model 'barrel'",
        ),
        (
            {"objects": [{"model": "package://other/x.sdf", "x": 0, "y": 0, "z": 0}]},
            f"{OBJ}.model",
            "unknown package",
        ),
        ({"objects": [{"model": "table", "x": 0, "y": 0}]}, f"{OBJ}.z", "missing field"),
        (
            {"objects": [{"model": "table", "x": 0, "y": 0, "z": 0, "size": 2}]},
            f"{OBJ}.size",
            "unknown key",
        ),
        (
            {"objects": [{"model": "table", "x": 0, "y": 0, "z": 0, "fixed": "yes"}]},
            f"{OBJ}.fixed",
            "expected true or false",
        ),
        (
            {"objects": [{"model": "table", "x": 0, "y": 0, "z": 0, "name": "a table"}]},
            f"{OBJ}.name",
            "identifiers",
        ),
        (
            {
                "objects": [
                    {"model": "table", "x": 0, "y": 0, "z": 0},
                    {"model": "table", "x": 1, "y": 0, "z": 0},
                ]
            },
            "objects[1].name",
            "two objects are named 'table'",
        ),
        (
            {"goals": [{"quantity": "my_crate.tilt", "at_least": "high", "what": "x"}]},
            "goals[0].at_least",
            "expected a number",
        ),
        (
            {
                "goals": [
                    {"quantity": "my_crate.tilt", "at_least": 0.2, "at_most": 0.1, "what": "x"}
                ]
            },
            "goals[0].at_most",
            "must be >= at_least",
        ),
        (
            {"goals": [{"quantity": "my_crate.tilt", "what": "x"}]},
            "goals[0].at_least",
            "missing field",
        ),
        (
            {"goals": [{"quantity": "tilt", "at_least": 0.1, "what": "x"}]},
            "goals[0].quantity",
            "expected <object>.<joint|tilt|rise>",
        ),
        (
            {"goals": [{"quantity": "chair.hinge", "at_least": 0.1, "what": "x"}]},
            "goals[0].quantity",
            "no object 'chair'",
        ),
    ],
)
def test_bad_scene_files_name_the_field(tmp_path, change, field, words):
    f = write_scene(tmp_path, scene_data(**change))
    with pytest.raises(InputError) as e:
        load_scene(f)
    assert e.value.file == str(f) and e.value.field == field
    assert words in str(e.value)


def test_a_goal_on_a_joint_the_model_lacks_is_refused_when_built(tmp_path):
    from tamp.refine.architecture import load_architecture
    from tamp.sim.refine.station import build_station

    goal = {"quantity": "my_crate.hinge", "at_least": 0.1, "what": "x"}
    f = write_scene(tmp_path, scene_data(goals=[goal]))
    program = load_program(program_in(tmp_path, f.name))
    with pytest.raises(InputError) as e:
        build_station(program, load_architecture(program.architecture), load_scene(f))
    assert e.value.field == "goals[0].quantity" and "lid_hinge" in str(e.value)


def test_a_package_url_names_a_packaged_model_file(tmp_path):
    from tamp.sim.core.models import sdf_path

    obj = {"model": "package://tamp_models/sdf/table.sdf", "x": 0.1, "y": 0, "z": 0}
    scene = load_scene(write_scene(tmp_path, scene_data(objects=[obj], goals=[])))
    (table,) = scene.objects
    assert table.model == str(sdf_path("table").resolve()) and table.name == "table"
