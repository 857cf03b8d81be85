"""World model: predicates, action templates and the domain loader."""

from __future__ import annotations

import pytest

from tamp.errors import InputError
from tamp.world import (
    Area,
    IsAreaFree,
    IsGraspedObject,
    IsHandFree,
    IsObjectAt,
    IsRobotCloseTo,
    ObjectState,
    Point,
    Pose,
    WorldState,
    default_domain,
    load_domain,
)


def _world() -> WorldState:
    return WorldState(
        robot=Pose.at(0.0, 0.0),
        objects={"O1": ObjectState("O1", Pose.at(1.0, 0.0, 0.1))},
        areas={"L1": Area("L1", Point(2.0, 1.0), 0.15), "F": Area("F", Point(-1.0, 0.0), 0.2)},
    )


def test_pick_and_place_by_templates() -> None:
    d = default_domain()
    s = _world()
    assert not IsRobotCloseTo("O1", 0.9).holds(s)  # 1 m away, reach 0.9
    pick = d.action("Pick", "O1")
    assert not pick.applicable(s)
    s = d.action("MoveTo", "O1").apply(s)
    assert pick.applicable(s)
    s = pick.apply(s)
    assert IsGraspedObject("O1").holds(s) and not IsHandFree().holds(s)
    assert not IsObjectAt("O1", "L1").holds(s)
    place = d.action("Place", "O1", "L1")
    assert not place.applicable(s)
    s = place.apply(d.action("MoveTo", "L1").apply(s))
    assert IsObjectAt("O1", "L1").holds(s) and IsHandFree().holds(s)
    assert not IsAreaFree("L1").holds(s) and IsAreaFree("F").holds(s)


def test_held_object_is_not_at_an_area_and_does_not_block_it() -> None:
    s = _world().with_held("O1")
    assert not IsObjectAt("O1", "L1").holds(s)
    moved = s.with_object_at("O1", Pose.at(2.0, 1.0))
    assert IsAreaFree("L1").holds(moved)


def test_contradictions_used_by_bt_conflicts() -> None:
    assert IsGraspedObject("O1").contradicts(IsGraspedObject("Oa"))
    assert IsGraspedObject("O1").contradicts(IsHandFree())
    assert not IsGraspedObject("O1").contradicts(IsGraspedObject("O1"))


def test_achievers_of_conditions() -> None:
    d = default_domain()
    assert d.template("Place").bindings_achieving(IsObjectAt("O1", "L1")) == [
        {"o": "O1", "l": "L1"}
    ]
    assert d.template("Place").bindings_achieving(IsHandFree()) == [{}]
    assert d.template("Pick").bindings_achieving(IsObjectAt("O1", "L1")) == []
    assert d.template("MoveTo").bindings_achieving(IsRobotCloseTo("O1")) == [{"target": "O1"}]


@pytest.mark.parametrize(
    "body, field",
    [
        ("robot: r\nactions: [{name: A, params: {o: thing}, eff: ['IsHandFree()']}]", "params.o"),
        ("robot: r\nactions: [{name: A, params: {o: object}, eff: ['IsNice(o)']}]", "eff[0]"),
        ("robot: r\nactions: [{name: A, eff: ['IsGraspedObject(o)']}]", "eff[0]"),
        ("robot: r\nbogus: 1\nactions: []", "bogus"),
        ("robot: r\nactions: [{name: A, params: {l: area}, eff: ['IsGraspedObject(l)']}]", "eff"),
    ],
)
def test_domain_errors_name_the_field(tmp_path, body: str, field: str) -> None:
    p = tmp_path / "d.yaml"
    p.write_text("version: 1\n" + body)
    with pytest.raises(InputError) as err:
        load_domain(p)
    assert str(p) in str(err.value) and field in str(err.value)


@pytest.mark.parametrize("content", [b"\xff\xfe\x00binary", b"version: 1\nrobot: [unclosed\n", b""])
def test_unreadable_files_are_bad_input(tmp_path, content: bytes) -> None:
    from tamp.commands.main import main

    p = tmp_path / "demo.yaml"
    p.write_bytes(content)
    with pytest.raises(InputError) as err:
        load_domain(p)
    assert str(p) in str(err.value)
    assert main(["plan", str(p)]) == 2


def test_domain_effect_no_skill_can_make_true_is_refused_at_load(tmp_path):
    import pytest

    from tamp.errors import InputError
    from tamp.world.actions import load_domain

    p = tmp_path / "dom.yaml"
    p.write_text(
        "version: 1\nrobot: r\nactions:\n"
        "  - {name: Clear, params: {l: area}, con: [], eff: [IsAreaFree(l)]}\n"
    )
    with pytest.raises(InputError, match="no skill can make IsAreaFree true") as err:
        load_domain(p)
    assert err.value.field == "actions[0].eff[0]"
