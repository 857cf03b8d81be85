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
from tamp.world.actions import packaged_domain
from tamp.world.predicates import IsGraspedKind, IsHandFreeOver, IsHolding, IsKindAt


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


# -- object kinds and the LOTS arm's domain (Zhou et al.: objects known by class) ------------
def _cell() -> WorldState:
    areas = {
        "A": Area("A", Point(0.0, 0.0), 0.3),
        "B": Area("B", Point(1.0, 0.0), 0.3),
        "waste": Area("waste", Point(0.5, -0.6), 0.15),
    }
    objects = {
        "body_1": ObjectState("body_1", Pose.at(0.05, 0.0), "body"),
        "body_2": ObjectState("body_2", Pose.at(0.95, 0.0), "body"),
        "peak_1": ObjectState("peak_1", Pose.at(0.0, 0.1), "peak"),
    }
    return WorldState(robot=Pose.at(0.5, 0.5), objects=objects, areas=areas)


def test_objects_keep_their_kind_and_areas_count_kinds() -> None:
    s = _cell()
    assert s.kinds_in(s.area("A")) == {"body": 1, "peak": 1}
    s = s.with_object_at("body_1", Pose.at(1.0, 0.0))  # moved: still a body
    assert s.objects["body_1"].kind == "body" and s.kinds_in(s.area("B")) == {"body": 2}
    s = s.with_object_at("cube_1", Pose.at(0.0, 0.0), "cube")
    assert s.kinds_in(s.area("A")) == {"cube": 1, "peak": 1}
    assert s.with_held("peak_1").kinds_in(s.area("A")) == {"cube": 1}  # carried, not there


def test_lots_arm_skills_pick_by_kind_and_release_over_an_area() -> None:
    d = packaged_domain("lots_arm")
    assert set(d.templates) == {"LookAt", "Pick", "Place", "Wait"}
    s = _cell()
    assert not d.action("Place", "B").applicable(s)  # nothing held
    assert not d.action("Pick", "peak", "B").applicable(s)  # no peak in W^B
    s = d.action("Pick", "body", "A").apply(s)
    assert s.held == "body_1"  # the body in W^A, not the nearer-to-home one in W^B
    assert IsGraspedKind("body").holds(s) and IsHolding().holds(s)
    assert not d.action("Pick", "peak", "A").applicable(s)  # one object at a time
    s = d.action("Place", "waste").apply(s)
    assert s.held is None and s.kinds_in(s.area("waste")) == {"body": 1}
    assert IsHandFreeOver("waste").holds(s) and not IsHandFreeOver("A").holds(s)
    s = d.action("LookAt", "A").apply(s)
    assert IsRobotCloseTo("A", d.reach).holds(s) and not IsRobotCloseTo("B", d.reach).holds(s)
    assert IsKindAt("peak", "A").holds(s) and not IsKindAt("body", "A").holds(s)


def test_kind_predicates_contradict_a_free_hand() -> None:
    assert IsHandFree().contradicts(IsGraspedKind("body"))
    assert IsGraspedKind("body").contradicts(IsHandFreeOver("B"))
    assert IsGraspedKind("body").contradicts(IsGraspedKind("peak"))
    assert not IsGraspedKind("body").contradicts(IsGraspedKind("body"))
    assert IsHolding().contradicts(IsHandFree()) and IsHandFreeOver("A").contradicts(IsHolding())


def test_unknown_packaged_domain_is_bad_input() -> None:
    with pytest.raises(InputError) as err:
        packaged_domain("spaceship")
    assert "lots_arm" in str(err.value) and "youbot" in str(err.value)


def test_an_object_the_world_no_longer_holds_is_nowhere_to_be_close_to() -> None:
    """A camera cell's world drops an object it loses sight of for good (a noisy detector's
    false sighting made it believed, then nothing confirmed it): the tree's conditions on
    it are false, as `IsObjectAt` is, instead of a crash (Case 3 camera, noise `high`,
    seed 11)."""
    s = _world()
    assert IsRobotCloseTo("O1", 1.5).holds(s)
    gone = WorldState(robot=s.robot, objects={}, areas=s.areas)
    assert not IsRobotCloseTo("O1", 1.5).holds(gone) and not IsObjectAt("O1", "L1").holds(gone)
    assert IsRobotCloseTo("F", 1.5).holds(gone)  # areas stay
