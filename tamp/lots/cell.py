"""The LOTS workcell as a `tamp.world.WorldState`, and what its eye-in-hand camera sees of it.

Zhou et al. §III: a table with two workspaces, W^A (where the robot picks) and W^B (where the
task is built), and a waste basket; objects are known by class. Here they are the areas
``A``, ``B`` and ``waste`` of a `WorldState`, objects carry their class as
`ObjectState.kind`, and the robot pose is where the camera looks. The robot's skills are the
``lots_arm`` domain (`tamp/world/domains/lots_arm.yaml`): ``LookAt(l)``, ``Pick(k, l)``,
``Place(l)``, ``Wait(l)``, executed by the one `tamp.world.SymbolicWorld` (or by the Drake
workcell, which implements the same `tamp.world.World` contract).

Local observation (Alg. 1 lines 5-11): the controller only ever reads `visible_counts` — the
counts per class of the workspace under the camera, a pure function of the state. In Drake the
same counts come from the camera's label image; `view_state` is the `WorldState` such a view
stands for, so a world that knows only what its camera sees can still answer ``observe()``.
"""

from __future__ import annotations

from functools import lru_cache

from tamp.world.actions import Action, Domain, packaged_domain
from tamp.world.geometry import Area, Point, Pose
from tamp.world.state import ObjectState, WorldState

#: The two workspaces the camera can look at, and the waste basket (Zhou et al. Fig. 1).
SIDES = ("A", "B")
WASTE = "waste"
#: Symbolic layout (m): only which area contains what matters; the Drake cell has its own.
AREAS = (
    Area("A", Point(0.0, 0.0), 0.3),
    Area("B", Point(1.0, 0.0), 0.3),
    Area(WASTE, Point(0.5, -0.6), 0.15),
)
#: The camera's starting point: over no workspace (the robot must look before it knows).
HOME = Pose.at(0.5, 0.5)


@lru_cache(maxsize=1)
def lots_domain() -> Domain:
    """The LOTS arm's skills (``lots_arm.yaml``), loaded once."""
    return packaged_domain("lots_arm")


def skill(name: str, *args: str) -> Action:
    """A ground LOTS skill, e.g. ``skill("Pick", "body", "A")``."""
    return lots_domain().action(name, *args)


def initial_state(initial: dict[str, dict[str, int]]) -> WorldState:
    """The workcell with ``initial[side][cls]`` objects per workspace; the hand is empty.

    The objects of a class in a workspace are one pile (`tamp.world.state.ObjectState.count`)
    named ``<class>_<n>`` at the area's centre: counts stay integers however large.
    """
    areas = {a.name: a for a in AREAS}
    state = WorldState(HOME, None, {}, areas)
    for side in SIDES:
        for cls, n in initial.get(side, {}).items():
            if n > 0:
                state = add_object(state, cls, side, n)
    return state


def new_uid(state: WorldState, cls: str) -> str:
    """The next free ``<class>_<n>`` name."""
    return state.fresh_uid(cls)


def add_object(state: WorldState, cls: str, area: str, count: int = 1) -> WorldState:
    """``state`` with a new pile of ``count`` objects of class ``cls`` at ``area``'s centre."""
    c = state.area(area).pos
    return state.with_object_at(new_uid(state, cls), Pose(Point(c.x, c.y, 0.0)), cls, count)


def camera_side(state: WorldState) -> str | None:
    """The workspace under the camera (the robot pose), or None while it looks elsewhere."""
    for side in SIDES:
        if side in state.areas and state.area(side).contains(state.robot.pos):
            return side
    return None


def visible_counts(state: WorldState, side: str) -> dict[str, int] | None:
    """Counts per class in workspace ``side`` if the camera is over it now, else None.

    This is everything the LOTS controller observes (local observation, Zhou et al. §III-A).
    """
    if camera_side(state) != side:
        return None
    return state.kinds_in(state.area(side))


def objects_of(state: WorldState, cls: str, area: str) -> list[str]:
    """The (unheld) objects, or piles of them, of class ``cls`` in ``area``, by uid."""
    return sorted(u for u in state.objects_in(state.area(area)) if state.objects[u].kind == cls)


def held_kind(state: WorldState) -> str | None:
    """The class of the object in the gripper, if any."""
    return None if state.held is None else state.objects[state.held].kind


def side_counts(state: WorldState) -> dict[str, dict[str, int]]:
    """Ground truth (never shown to the controller): counts in W^A, W^B and the basket."""
    return {name: state.kinds_in(state.area(name)) for name in (*SIDES, WASTE)}


def view_state(side: str | None, counts: dict[str, int], in_hand: str | None = None) -> WorldState:
    """The state a camera view over ``side`` stands for: those objects there, nothing else,
    and ``in_hand`` (a class) in the gripper when the camera sees one there.

    What a world that knows only its camera's view (the Drake workcell) returns from
    ``observe()``: `visible_counts` of it gives ``counts`` back, `held_kind` ``in_hand``.
    ``side`` None: the camera over neither workspace (``counts`` must be empty).
    """
    areas = {a.name: a for a in AREAS}
    here = HOME if side is None else Pose(Point(areas[side].pos.x, areas[side].pos.y, 0.0))
    objects = {
        f"{cls}_1": ObjectState(f"{cls}_1", here, cls, n) for cls, n in sorted(counts.items()) if n
    }
    held = None
    if in_hand is not None:
        held = f"{in_hand}_held"
        objects[held] = ObjectState(held, here, in_hand)
    return WorldState(here, held, objects, areas)
