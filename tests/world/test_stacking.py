"""The tree's IsObjectAt and the Drake workcell's 3-D judge agree: an object on top
of another is not at the area, whatever its x and y; on the floor inside the area it is."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.demo import load_demonstration
from tamp.sim.smp.placement import Body, why_not_in
from tamp.sim.smp.robot import OBJECT_KINDS
from tamp.world import IsAreaFree, IsObjectAt
from tamp.world.geometry import Area, Point, Pose
from tamp.world.predicates import resting_on
from tamp.world.state import ObjectState, WorldState

KINDS = sorted(OBJECT_KINDS)


def _state(bodies: list[Body], areas: dict[str, Area], held: str | None = None) -> WorldState:
    """What the workcell's estimator gives the tree: centres from the plant (z included)."""
    objects = {b.id: ObjectState(b.id, Pose(Point(b.x, b.y, b.z))) for b in bodies}
    return WorldState(robot=Pose(Point(-2.0, 0.0)), held=held, objects=objects, areas=areas)


def _agree(bodies: list[Body], areas: dict[str, Area]) -> None:
    state = _state(bodies, areas)
    for b in bodies:
        for name, area in areas.items():
            tree = IsObjectAt(b.id, name).holds(state)
            judge = why_not_in(b, area, bodies) is None
            assert tree == judge, (b, name, why_not_in(b, area, bodies))


def test_the_issue_example_o0_on_oa_is_not_at_its_area():
    area = Area("L0", Point(1.0, 0.0), 0.15)
    oa = Body("Oa", 1.0, 0.0, OBJECT_KINDS["obstacle"].half_height, OBJECT_KINDS["obstacle"])
    top = 2 * oa.kind.half_height + OBJECT_KINDS["bottle"].half_height
    o0 = Body("O0", 1.01, 0.0, top, OBJECT_KINDS["bottle"])
    state = _state([oa, o0], {"L0": area})
    assert not IsObjectAt("O0", "L0").holds(state) and resting_on(state, "O0") == ["Oa"]
    assert IsObjectAt("Oa", "L0").holds(state)
    assert "on top of Oa" in why_not_in(o0, area, [oa, o0])
    assert not IsAreaFree("L0").holds(state)  # the area is taken either way
    _agree([oa, o0], {"L0": area})
    # held high above, O0 is carried, not stacked: Oa is still at L0
    held = _state([oa, o0], {"L0": area}, held="O0")
    assert IsObjectAt("Oa", "L0").holds(held) and not IsObjectAt("O0", "L0").holds(held)


def test_packaged_cases_goal_states_agree_on_the_floor_and_stacked():
    """Each packaged case's goals, reached on the floor: both say at; the same object put on
    top of another object standing in its area: both say not at."""
    for case in ("case1", "case2", "case3"):
        demo = load_demonstration(f"{case}.yaml")
        areas = {a.name: a for a in (g.area for g in demo.goals)}
        for g in demo.goals:
            area = g.area
            kind = OBJECT_KINDS["bottle"]
            floor = Body(g.object, area.pos.x, area.pos.y, kind.half_height, kind)
            _agree([floor], areas)
            assert IsObjectAt(g.object, area.name).holds(_state([floor], areas))
            under_kind = OBJECT_KINDS["obstacle"]
            under = Body("Oa", area.pos.x, area.pos.y, under_kind.half_height, under_kind)
            z = 2 * under_kind.half_height + kind.half_height
            stacked = Body(g.object, area.pos.x + 0.01, area.pos.y, z, kind)
            _agree([under, stacked], areas)
            assert not IsObjectAt(g.object, area.name).holds(_state([under, stacked], areas))


@st.composite
def scene(draw):
    """Two objects, each on the floor or the second on top of the first (physically
    consistent: footprints on the floor do not overlap; a stacked centre is above the
    lower object's footprint)."""
    k1, k2 = (OBJECT_KINDS[draw(st.sampled_from(KINDS))] for _ in range(2))
    x1 = draw(st.floats(-0.3, 0.3))
    y1 = draw(st.floats(-0.3, 0.3))
    lower = Body("A", x1, y1, k1.half_height, k1)
    ang = draw(st.floats(0, 2 * math.pi))
    if draw(st.booleans()):  # B on top of A
        r = draw(st.floats(0, k1.radius * 0.9))
        z = 2 * k1.half_height + k2.half_height
    else:  # B beside A on the floor
        r = draw(st.floats(k1.radius + k2.radius + 0.001, 0.5))
        z = k2.half_height
    upper = Body("B", x1 + r * math.cos(ang), y1 + r * math.sin(ang), z, k2)
    area = Area("L", Point(draw(st.floats(-0.3, 0.3)), draw(st.floats(-0.3, 0.3))), 0.15)
    return [lower, upper], {"L": area}


@settings(max_examples=300, deadline=None)
@given(scene())
def test_tree_and_3d_judge_agree_on_consistent_scenes(s):
    bodies, areas = s
    _agree(bodies, areas)
