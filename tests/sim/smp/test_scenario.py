"""Simulation scenario files: the packaged ones load, bad ones fail naming file and field."""

from __future__ import annotations

import math

import pytest

from tamp.commands.main import main
from tamp.errors import InputError
from tamp.sim.smp.robot import OBJECT_KINDS
from tamp.sim.smp.scenario import load_scenario
from tamp.world.events import AfterAction, Appear, AtTime, Fail, parse_appear, parse_fail
from tamp.world.geometry import Point

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
    assert oa.appear == Appear("Oa", "L1", AfterAction("Pick", ("O1",)))
    assert str(oa.appear) == "Oa@L1@after:Pick(O1)"  # the --appear flag's own text
    assert math.isnan(oa.xy[0])
    assert not s.in_workspace(*s.parking(0))


def test_failed_grasp_case_uses_the_fail_vocabulary():
    s = load_scenario(packaged("case1_failed_grasp.yaml"))
    assert s.failures == (Fail("Pick", ("O2",), 1),)


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
        ("objects:\n  - {id: Y, model: obstacle}\nappear: ['Y@L9@t=1']\n", "appear[0]"),
        ("objects:\n  - {id: Y, model: obstacle}\n", "objects[0].pose"),
        ("appear: ['Y@L0@when:1']\n", "appear[0]"),
        ("appear: ['O0@L0@t=1']\n", "appear[0]"),  # a demonstration object
        ("appear: ['Y@L0@after:Fly(O0)']\n", "appear[0]"),
        ("appear: ['Y@20,0@t=1']\n", "appear[0]"),  # outside the workspace
        (
            "objects:\n  - {id: Y, model: obstacle, pose: [1.0, -0.7, 0]}\nappear: ['Y@L0']\n",
            "appear[0]",
        ),
        ("appear: [{area: L0}]\n", "appear[0]"),
        ("fail: ['Place(O0, L0)']\n", "fail[0]"),
        ("fail: ['Pick(O9)']\n", "fail[0]"),
        ("fail: ['Pick(O0)x0']\n", "fail[0]"),
        ("fail: ['Pick(O0)', 'Pick(O0)x2']\n", "fail[1]"),
        ("plant: {time_step: 0.5}\n", "plant.time_step"),
        ("robot: {start: [1.0, 0.1, 0.0]}\n", "robot.start"),
    ],
)
def test_bad_fields_are_named(tmp_path, extra, field):
    assert _bad(tmp_path, extra).field == field


def test_cli_exits_2_naming_the_field(tmp_path, capsys):
    path = write_one_bottle(tmp_path, "objects:\n  - {id: X, model: teapot, pose: [0.5, 1, 0]}\n")
    code = main(["simulate", "smp-mro", str(path), "--json"])
    assert code == 2
    err = capsys.readouterr().err
    assert "objects[0].model" in err and str(path) in err


def test_appear_and_fail_entries_read_as_the_flags_do(tmp_path):
    path = write_one_bottle(
        tmp_path,
        "objects:\n  - {id: Y, model: obstacle}\n"
        "appear: ['Y@L0@t=2.5', 'Z@1.5,-0.5', 'W@L0@4']\nfail: ['Pick x2']\n",
    )
    s = load_scenario(path)
    assert s.object("Y").appear == Appear("Y", "L0", AtTime(2.5))
    assert s.object("Y").kind is OBJECT_KINDS["obstacle"]
    z = s.object("Z")
    assert z.kind is OBJECT_KINDS["bottle"] and z.appear.when is None  # when within reach
    assert s.place_of(z.appear) == Point(1.5, -0.5, 0.0)
    assert str(s.object("W").appear) == "W@L0@4"
    assert s.failures == (Fail("Pick", None, 2),)


def test_with_events_adds_and_overrides_per_object(tmp_path):
    path = write_one_bottle(
        tmp_path,
        "objects:\n  - {id: Y, model: obstacle, pose: [1.0, -0.7, 0]}\nfail: ['Pick(O0)']\n",
    )
    s = load_scenario(path)
    t = s.with_events(
        [parse_appear("Y@L0@after:Pick(O0)"), parse_appear("Q@L0@t=5")],
        [parse_fail("Pick(O0)x3")],
    )
    y = t.object("Y")
    assert y.kind is OBJECT_KINDS["obstacle"] and math.isnan(y.xy[0])  # the flag wins
    assert y.appear == Appear("Y", "L0", AfterAction("Pick", ("O0",)))
    assert t.object("Q").kind is OBJECT_KINDS["bottle"]
    assert t.failures == (Fail("Pick", ("O0",), 3),)  # replaces the file's Pick(O0)
    assert s.object("Y").appear is None and s.failures == (Fail("Pick", ("O0",), 1),)
    assert s.with_events([], [parse_fail("Pick")]).failures == (
        Fail("Pick", ("O0",), 1),
        Fail("Pick", None, 1),
    )


@pytest.mark.parametrize(
    ("appear", "fail", "flag", "words"),
    [
        (["Y@L9"], [], "--appear", "unknown area"),
        (["O0@L0"], [], "--appear", "demonstration object"),
        (["Y@L0@after:Fly(O0)"], [], "--appear", "unknown action"),
        ([], ["MoveTo(L0)"], "--fail", "only Pick"),
        ([], ["Pick(Nope)"], "--fail", "Pick takes one object"),
    ],
)
def test_with_events_errors_name_the_flag(tmp_path, appear, fail, flag, words):
    s = load_scenario(write_one_bottle(tmp_path))
    with pytest.raises(InputError) as info:
        s.with_events([parse_appear(a) for a in appear], [parse_fail(f) for f in fail])
    assert info.value.field == flag and words in info.value.reason


@pytest.mark.parametrize(
    ("appear", "field", "who"),
    [
        (["Y@1.0,0.0@0"], "appear[0]", "O0"),  # onto O0's start place, at tick 0
        (["Y@1.02,0.05@t=0"], "appear[0]", "O0"),  # footprints overlap, at t=0
        (["Y@0.1,0.0@0"], "appear[0]", "the robot"),  # under the robot's base
        (["Y@L0@0", "Z@L0@0"], "appear[1]", "Y"),  # two at once onto the same place
    ],
)
def test_an_appearance_at_time_0_onto_an_occupied_place_is_refused(tmp_path, appear, field, who):
    """Issue 17: an object put down inside another one at the start is certain from the
    file alone: exit 2 naming the entry (later ones are set aside at run time)."""
    lines = "".join(f"  - '{a}'\n" for a in appear)
    info = _bad(tmp_path, f"appear:\n{lines}")
    assert info.field == field
    assert f"occupied by {who} at the start" in info.reason


def test_a_later_appearance_onto_an_occupied_place_loads(tmp_path):
    """At tick 1 or later the place may be free by then: the runner decides (it sets the
    object aside with a warning when it is not)."""
    s = load_scenario(write_one_bottle(tmp_path, "appear: ['Y@1.0,0.0@1', 'Z@L0@0']\n"))
    assert s.object("Y").appear.when is not None and s.object("Z").appear is not None


def test_an_appearance_flag_at_time_0_onto_an_occupied_place_exits_2(tmp_path, capsys):
    path = write_one_bottle(tmp_path)
    s = load_scenario(path)
    with pytest.raises(InputError) as info:
        s.with_events([parse_appear("Y@1.0,0.0@0")])
    assert info.value.field == "--appear" and "occupied by O0" in info.value.reason
    code = main(["simulate", "smp-mro", str(path), "--appear", "Y@1.0,0.0@0"])
    err = capsys.readouterr().err
    assert code == 2 and "--appear" in err and "occupied by O0" in err
