"""Simulation scenario files: the packaged ones load, bad ones fail naming file and field."""

from __future__ import annotations

import math

import pytest

from tamp.commands.main import main
from tamp.errors import InputError
from tamp.sim.smp.robot import OBJECT_KINDS
from tamp.sim.smp.scenario import load_scenario, parse_action

from .helpers import packaged, write_one_bottle


@pytest.mark.parametrize("case", [1, 2, 3])
def test_packaged_cases_load_with_the_demonstration(case):
    s = load_scenario(packaged(f"case{case}.yaml"))
    assert s.name == f"case{case}"
    demo_ids = set(s.demo.objects)
    assert demo_ids <= {o.id for o in s.objects}
    for o in s.objects:
        if o.id in demo_ids:  # positions come from the demonstration (robot frame)
            p = s.demo.objects[o.id]
            assert o.xy == pytest.approx((p.x, p.y))
            assert o.kind is OBJECT_KINDS["bottle"]


def test_case3_obstacle_appears_at_l1_after_the_pick_of_o1():
    s = load_scenario(packaged("case3.yaml"))
    oa = s.object("Oa")
    assert oa.kind is OBJECT_KINDS["obstacle"]
    assert oa.appear.area == "L1" and oa.appear.after == ("Pick", ("O1",))
    assert math.isnan(oa.xy[0])
    assert not s.in_workspace(*s.parking(0))


def test_parse_action():
    assert parse_action("Place(O1, L1)") == ("Place", ("O1", "L1"))
    assert parse_action("Fly(O1)") is None


def _bad(tmp_path, extra: str) -> InputError:
    path = write_one_bottle(tmp_path, extra)
    with pytest.raises(InputError) as info:
        load_scenario(path)
    assert info.value.file == str(path)
    return info.value


def test_unknown_model_names_the_field(tmp_path):
    err = _bad(tmp_path, "objects:\n  - {id: X, model: teapot, pose: [0.5, 1.0, 0.0]}\n")
    assert err.field == "objects[0].model"
    assert "teapot" in str(err)


def test_overlapping_objects_name_the_later_object(tmp_path):
    err = _bad(
        tmp_path,
        "objects:\n  - {id: X, model: bottle, pose: [1.03, 0.0, 0.0]}\n",
    )
    assert err.field == "objects[0]"
    assert "overlap" in err.reason


def test_goal_outside_the_workspace_is_unreachable(tmp_path):
    path = write_one_bottle(tmp_path)
    text = path.read_text().replace("y: [-1.5, 2.0]", "y: [-1.5, 0.6]")
    path.write_text(text)
    with pytest.raises(InputError) as info:
        load_scenario(path)
    assert info.value.field == "workspace"
    assert "goal G0" in info.value.reason and "unreachable" in info.value.reason


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        ("colour: red\n", "colour"),
        (
            "objects:\n  - {id: Y, model: obstacle, appear: {area: L9, time: 1.0}}\n",
            "objects[0].appear.area",
        ),
        ("objects:\n  - {id: Y, model: obstacle, appear: {area: L0}}\n", "objects[0].appear.time"),
        ("failures:\n  - {action: 'Place(O0, L0)'}\n", "failures[0].action"),
        ("failures:\n  - {action: 'Pick(O0)', attempts: [0]}\n", "failures[0].attempts[0]"),
        ("plant: {time_step: 0.5}\n", "plant.time_step"),
        ("robot: {start: [1.0, 0.1, 0.0]}\n", "robot.start"),
    ],
)
def test_bad_fields_are_named(tmp_path, extra, field):
    assert _bad(tmp_path, extra).field == field


def test_cli_exits_2_naming_the_field(tmp_path, capsys):
    path = write_one_bottle(tmp_path, "objects:\n  - {id: X, model: teapot, pose: [0.5, 1, 0]}\n")
    code = main(["simulate", "smp-mro", "--scenario", str(path), "--json"])
    assert code == 2
    err = capsys.readouterr().err
    assert "objects[0].model" in err and str(path) in err
