"""A scenario declares an object class of its own (``classes:``): a user's SDF, no code.

The class loads like a packaged one (footprint, body and primary colour read from the SDF,
instance colours from the palette), objects of it are placed and checked like the
packaged tools, the LOTS task and the person's script may name it, and in the simulated
cell it lies on the table, is counted by a look and is picked by friction (slow).
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from tamp.errors import InputError
from tamp.sim.lots.scenario import load_cell_scenario
from tests.sim.lots.helpers import write_scenario

#: a small block, 0.06 x 0.03 x 0.035 m, 50 g: the tower body's SDF idiom
WIDGET_SDF = """<?xml version="1.0"?>
<sdf version="1.9" xmlns:drake="http://drake.mit.edu">
  <model name="widget_model">
    <link name="widget_link">
      <inertial><pose>0 0 0.0175 0 0 0</pose><mass>0.05</mass><inertia><ixx>9e-06</ixx>
        <iyy>2e-05</iyy><izz>1.9e-05</izz><ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia>
      </inertial>
      <visual name="v0"><pose>0 0 0.0175 0 0 0</pose>
        <geometry><box><size>0.06 0.03 0.035</size></box></geometry>
        <material><diffuse>0.9 0.5 0.1 1</diffuse></material></visual>
      <collision name="c0"><pose>0 0 0.0175 0 0 0</pose>
        <geometry><box><size>0.06 0.03 0.035</size></box></geometry>
        <drake:proximity_properties><drake:compliant_hydroelastic/>
          <drake:hydroelastic_modulus>5e6</drake:hydroelastic_modulus>
          <drake:mesh_resolution_hint>0.02</drake:mesh_resolution_hint>
          <drake:hunt_crossley_dissipation>5</drake:hunt_crossley_dissipation>
          <drake:mu_dynamic>0.8</drake:mu_dynamic><drake:mu_static>0.8</drake:mu_static>
        </drake:proximity_properties></collision>
    </link>
  </model>
</sdf>
"""
PALETTE = [[0.9, 0.1, 0.1], [0.1, 0.2, 0.9]]
WIDGETS = [
    {"class": "widget", "workspace": "A", "xy": [0.0, 0.0], "yaw": 0},
    {"class": "widget", "workspace": "A", "xy": [0.0, 0.1], "yaw": 90},
    {"class": "body", "workspace": "A", "xy": [0.0, -0.1]},
]


def widget_scenario(tmp: Path, objects=None, **widget) -> Path:
    """A scenario in ``tmp`` declaring ``widget`` (its SDF in ``tmp/models``)."""
    (tmp / "models").mkdir(exist_ok=True)
    (tmp / "models" / "widget.sdf").write_text(WIDGET_SDF)
    entry = {"sdf": "models/widget.sdf", "palette": PALETTE, **widget}
    return write_scenario(tmp, WIDGETS if objects is None else objects, classes={"widget": entry})


def test_a_declared_class_loads_like_a_packaged_one(tmp_path):
    s = load_cell_scenario(widget_scenario(tmp_path))
    widget = s.object_class("widget")
    assert widget.sdf == (tmp_path / "models" / "widget.sdf").resolve()
    assert widget.body == "widget_link" and widget.colour == "0.9 0.5 0.1 1"
    f = widget.footprint
    assert (f.xmin, f.xmax, f.ymin, f.ymax, f.top) == (-0.03, 0.03, -0.015, 0.015, 0.035)
    assert "widget" in s.class_names and "body" in s.class_names
    assert [o.id for o in s.objects] == ["widget_0", "widget_1", "body_0"]
    assert [o.rgb for o in s.objects[:2]] == [tuple(c) for c in PALETTE]
    assert s.object_class("body").name == "body"  # the packaged classes stay


def test_a_package_url_names_a_packaged_sdf(tmp_path):
    objects = [{"class": "bolt", "workspace": "A", "xy": [0.0, 0.0]}]
    entry = {"sdf": "package://tamp_models/sdf/lots_screw.sdf"}
    path = write_scenario(tmp_path, objects, classes={"bolt": entry})
    s = load_cell_scenario(path)
    bolt = s.object_class("bolt")
    assert bolt.body == "screw" and bolt.footprint == s.object_class("screw").footprint
    assert s.objects[0].rgb == (0.7, 0.7, 0.2)  # no palette: the SDF's own colour


def test_the_footprint_still_keeps_objects_apart_and_inside(tmp_path):
    overlapping = [WIDGETS[0], {"class": "widget", "workspace": "A", "xy": [0.05, 0.0]}]
    with pytest.raises(InputError) as err:
        load_cell_scenario(widget_scenario(tmp_path, overlapping))
    assert err.value.field == "objects[1]" and "overlap" in str(err.value)
    outside = [{"class": "widget", "workspace": "A", "xy": [0.15, 0.0]}]
    with pytest.raises(InputError) as err:
        load_cell_scenario(widget_scenario(tmp_path, outside))
    assert err.value.field == "objects[0].xy"


@pytest.mark.parametrize(
    ("widget", "field", "why"),
    [
        ({"sdf": "models/nothing.sdf"}, "classes.widget.sdf", "no model file"),
        ({"sdf": "package://other/x.sdf"}, "classes.widget.sdf", "unknown package"),
        ({"mass": 0.1}, "classes.widget.mass", "unknown key"),
        ({"palette": [[0.9, 1.5, 0.1]]}, "classes.widget.palette[0][1]", "must be <= 1.0"),
        ({"palette": [[0.9, 0.1]]}, "classes.widget.palette[0]", "list of 3 numbers"),
        ({"palette": []}, "classes.widget.palette", "at least 1 item"),
    ],
)
def test_bad_declarations_name_the_field(tmp_path, widget, field, why):
    path = widget_scenario(tmp_path, **widget)
    with pytest.raises(InputError) as err:
        load_cell_scenario(path)
    assert err.value.field == field and why in str(err.value)
    assert err.value.file == str(path)


@pytest.mark.parametrize(
    ("name", "why"),
    [("Widget", "lower-case identifiers"), ("hammer", "a packaged class")],
)
def test_a_class_name_is_new_and_lower_case(tmp_path, name, why):
    (tmp_path / "w.sdf").write_text(WIDGET_SDF)
    path = write_scenario(tmp_path, [], classes={name: {"sdf": "w.sdf"}})
    with pytest.raises(InputError) as err:
        load_cell_scenario(path)
    assert err.value.field == f"classes.{name}" and why in str(err.value)


@pytest.mark.parametrize(
    ("text", "why"),
    [
        (WIDGET_SDF.replace("<box><size>0.06 0.03 0.035</size></box>", "<mesh/>"), "geometry"),
        (WIDGET_SDF.replace("</link>", '</link><link name="lid"/>'), "2 links"),
        (WIDGET_SDF.replace("0.06 0.03 0.035", "0.12 0.09 0.035"), "gripper"),
        ("<sdf><model", "not an SDFormat file"),
    ],
)
def test_a_model_the_cell_cannot_use_is_refused_at_its_sdf(tmp_path, text, why):
    (tmp_path / "w.sdf").write_text(text)
    path = write_scenario(tmp_path, [], classes={"widget": {"sdf": "w.sdf"}})
    with pytest.raises(InputError) as err:
        load_cell_scenario(path)
    assert err.value.field == "classes.widget.sdf" and why in str(err.value)


def test_an_undeclared_class_is_still_refused(tmp_path):
    path = write_scenario(tmp_path, [{"class": "widget", "workspace": "A", "xy": [0, 0]}])
    with pytest.raises(InputError) as err:
        load_cell_scenario(path)
    assert err.value.field == "objects[0].class" and "'widget'" in str(err.value)


def test_the_task_and_the_person_may_name_a_declared_class(tmp_path):
    from tamp.lots.task import Event, load_task
    from tamp.sim.lots.person import staged_objects
    from tamp.sim.lots.simulate import check_matches, check_person_classes

    scenario = load_cell_scenario(widget_scenario(tmp_path))
    task = {
        "version": 1,
        "name": "widgets",
        "formula": "GF p",
        "propositions": {"p": {"class": "widget"}},
        "initial": {"A": {"widget": 2, "body": 1}, "B": {}},
    }
    (tmp_path / "task.yaml").write_text(yaml.safe_dump(task))
    check_matches(load_task(tmp_path / "task.yaml"), scenario)
    events = [Event(after=1, kind="add", cls="widget", side="B")]
    check_person_classes(events, scenario)
    (staged,) = staged_objects(events, scenario)
    assert staged.cls == "widget" and staged.rgb == tuple(PALETTE[0])
    with pytest.raises(InputError, match="no 'gizmo' objects"):
        check_person_classes([Event(after=1, kind="add", cls="gizmo", side="B")], scenario)


@pytest.mark.slow
def test_the_declared_object_lies_in_the_cell_is_seen_and_picked(tmp_path):
    """Station built from the user's files: the widget rests on W^A, a look counts it by
    its class, and ``Pick(widget)`` (views, HRG-Net's grasp, a friction lift) holds it."""
    from tamp.sim.lots.driver import CellDriver
    from tamp.sim.lots.station import build_station
    from tamp.world.interface import Status

    scenario = load_cell_scenario(widget_scenario(tmp_path, WIDGETS[:1]))
    cell = build_station(scenario)
    body = cell.cell.bodies["widget_0"]
    assert body.name() == "widget_link" and cell.cell.classes["widget_0"] == "widget"
    d = CellDriver(cell)
    d.advance(0.5)
    x, y, z = body.EvalPoseInWorld(d.plant_context()).translation()
    assert (x, y) == pytest.approx((0.5, 0.25), abs=0.005) and abs(z) < 0.003  # at rest
    assert d.run("LookAt(A)").detail == "widget=1"
    st = d.run("Pick(widget)", timeout=60)
    assert st.status is Status.SUCCESS and st.detail == "holding widget", d.skill_state().log
    assert body.EvalPoseInWorld(d.plant_context()).translation()[2] > 0.08
