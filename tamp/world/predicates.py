"""Condition templates as hashable pure functions of a WorldState: the five of SMP-MRO §V-A2,
and four over object *kinds* for the LOTS arm (Zhou et al. §III: the robot picks "a hammer",
not a named object; its skills are `tamp/world/domains/lots_arm.yaml`).

Each predicate also knows how to *make itself true* (``achieve``), which is how action
effects are applied symbolically, and which other predicates it *contradicts* (two
conditions that no state satisfies together), which is what the BT layer's conflict check
needs (§IV-C3: IsGraspedObject(O1) vs IsGraspedObject(Oa)).

Choices where the paper is silent (written down here on purpose):
- ``IsObjectAt(o, l)`` is false while ``o`` is held: a carried object is not *at* an area.
  It is also false while ``o`` rests on top of another object (`resting_on`), whatever its
  x and y: areas are places on the floor, and the Drake workcell judges success the same way
  in 3-D (`tamp.sim.smp.placement.why_not_in`: an O0 pushed onto O_a, its centre at
  z = 0.25 m, must not look placed to the tree either). States carry centres, not sizes, so
  "on top" is read from the centres: another unheld object closer than `STACK_RADIUS` in
  the plane (two objects standing side by side are at least the sum of their footprint radii
  apart, 7 cm for the packaged kinds) and more than `STACK_TOL` lower. Symbolic effects never stack
  (they keep an object's height), so only observed plant states can make it false.
- ``IsAreaFree(l)`` ignores the held object, which travels with the robot.
- ``IsRobotCloseTo(ref, d)`` takes an object or area name; ``d`` defaults to the domain's
  reach (0.9 m, the paper's default). The paper writes ``IsRobotCloseTo(l.pos, l.radius)``
  for MoveTo/Place, which would put a mobile base on top of the goal area; a reach radius
  is what a mobile manipulator can satisfy. For the LOTS arm the "robot" pose is where its
  eye-in-hand camera looks (the workspace under it is the one it sees).
- ``IsGraspedKind(k)`` made true grasps the unheld object of kind ``k`` nearest the robot
  (ties: the smaller uid); the LOTS ``Pick(k, l)`` moves the arm over ``l`` first, so that
  is an object in ``l``. ``IsHandFreeOver(l)`` made true releases the held object over ``l``:
  it lands at ``l``'s centre. ``IsKindAt`` and ``IsHolding`` are only preconditions.
"""

from __future__ import annotations

import math
from dataclasses import Field, dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from tamp.world.geometry import Point, Pose, Quaternion
from tamp.world.state import WorldState

DEFAULT_REACH = 0.9
#: m: centres closer than this in the plane cannot both stand on the floor (footprints 2 × 3.5 cm)
STACK_RADIUS = 0.07
#: m: a centre higher than another's by more than this, above it, rests on it
STACK_TOL = 0.01


def resting_on(state: WorldState, uid: str) -> list[str]:
    """The unheld objects that object ``uid`` stands on (its centre above theirs, see the
    module notes), in uid order; empty for an object on the floor."""
    o = state.objects[uid].pos
    return sorted(
        other
        for other, s in state.objects.items()
        if other != uid
        and other != state.held
        and s.pos.z < o.z - STACK_TOL
        and s.pos.planar_distance(o) < STACK_RADIUS
    )


class Predicate:
    """Base class: ``holds(state)``, ``achieve(state)``, ``contradicts(other)``."""

    name: str = ""
    if TYPE_CHECKING:  # every predicate is a dataclass: `dataclasses.fields` reads its arguments
        __dataclass_fields__: ClassVar[dict[str, Field[Any]]]

    def holds(self, state: WorldState) -> bool:  # pragma: no cover - abstract
        raise NotImplementedError

    def achieve(self, state: WorldState) -> WorldState:
        """The state after an action whose effect is this predicate (§IV-C1 ``a.eef``)."""
        raise NotImplementedError(f"{self} cannot be made true directly")

    def contradicts(self, other: Predicate) -> bool:
        return False

    @property
    def args(self) -> tuple:
        return ()

    def __str__(self) -> str:
        return f"{self.name}({', '.join(str(a) for a in self.args)})"


@dataclass(frozen=True, slots=True)
class IsObjectAt(Predicate):
    """True when object ``obj`` lies (not held) inside area ``area``, on the floor there (not
    on top of another object: `resting_on`)."""

    obj: str
    area: str
    name = "IsObjectAt"

    @property
    def args(self) -> tuple:
        return (self.obj, self.area)

    def holds(self, state: WorldState) -> bool:
        o = state.objects.get(self.obj)
        if o is None or state.held == self.obj:
            return False
        return state.area(self.area).contains(o.pos) and not resting_on(state, self.obj)

    def achieve(self, state: WorldState) -> WorldState:
        target = state.area(self.area).pos
        old = state.objects[self.obj].pose
        pose = Pose(Point(target.x, target.y, old.pos.z), old.orientation)
        out = state.with_object_at(self.obj, pose)
        return out.with_held(None) if out.held == self.obj else out

    def contradicts(self, other: Predicate) -> bool:
        if isinstance(other, IsGraspedObject):
            return other.obj == self.obj
        return False


@dataclass(frozen=True, slots=True)
class IsRobotCloseTo(Predicate):
    """True when the robot base is within ``d`` (planar) of the object or area ``ref``."""

    ref: str
    d: float = DEFAULT_REACH
    name = "IsRobotCloseTo"

    @property
    def args(self) -> tuple:
        return (self.ref,) if self.d == DEFAULT_REACH else (self.ref, self.d)

    def holds(self, state: WorldState) -> bool:
        # an object the world no longer holds (a camera lost sight of one it had believed
        # in) is nowhere to be close to, as `IsObjectAt` is in no area
        if self.ref not in state.objects and self.ref not in state.areas:
            return False
        return state.robot.pos.planar_distance(state.position_of(self.ref)) <= self.d + 1e-9

    def achieve(self, state: WorldState) -> WorldState:
        # Symbolically the base drives to the target point itself (travel cost = distance).
        p = state.position_of(self.ref)
        here = state.robot.pos
        yaw = math.atan2(p.y - here.y, p.x - here.x) if here.planar_distance(p) > 1e-9 else None
        q = Quaternion.from_yaw(yaw) if yaw is not None else state.robot.orientation
        return state.with_robot_at(Pose(Point(p.x, p.y, here.z), q))

    def contradicts(self, other: Predicate) -> bool:
        return False  # proximity to two places can hold together; decided by geometry


@dataclass(frozen=True, slots=True)
class IsHandFree(Predicate):
    """True when the robot holds nothing (h = None)."""

    name = "IsHandFree"

    def holds(self, state: WorldState) -> bool:
        return state.held is None

    def achieve(self, state: WorldState) -> WorldState:
        return state.with_held(None)

    def contradicts(self, other: Predicate) -> bool:
        return isinstance(other, IsGraspedObject | IsGraspedKind | IsHolding)


@dataclass(frozen=True, slots=True)
class IsGraspedObject(Predicate):
    """True when the robot holds object ``obj`` (h = uid)."""

    obj: str
    name = "IsGraspedObject"

    @property
    def args(self) -> tuple:
        return (self.obj,)

    def holds(self, state: WorldState) -> bool:
        return state.held == self.obj

    def achieve(self, state: WorldState) -> WorldState:
        return state.with_held(self.obj)

    def contradicts(self, other: Predicate) -> bool:
        if isinstance(other, IsGraspedObject):
            return other.obj != self.obj
        if isinstance(other, IsHandFree | IsHandFreeOver):
            return True
        if isinstance(other, IsObjectAt):
            return other.obj == self.obj
        return False


@dataclass(frozen=True, slots=True)
class IsAreaFree(Predicate):
    """True when no (unheld) object lies in area ``area``."""

    area: str
    name = "IsAreaFree"

    @property
    def args(self) -> tuple:
        return (self.area,)

    def holds(self, state: WorldState) -> bool:
        return not state.objects_in(state.area(self.area))

    def blockers(self, state: WorldState) -> list[str]:
        """The objects that make this condition false (what a recovery must move away)."""
        return sorted(state.objects_in(state.area(self.area)))


@dataclass(frozen=True, slots=True)
class IsKindAt(Predicate):
    """True when some object of kind ``kind`` lies (not held) in area ``area``."""

    kind: str
    area: str
    name = "IsKindAt"

    @property
    def args(self) -> tuple:
        return (self.kind, self.area)

    def holds(self, state: WorldState) -> bool:
        area = state.area(self.area)
        return any(state.objects[u].kind == self.kind for u in state.objects_in(area))


@dataclass(frozen=True, slots=True)
class IsGraspedKind(Predicate):
    """True when the robot holds an object of kind ``kind``."""

    kind: str
    name = "IsGraspedKind"

    @property
    def args(self) -> tuple:
        return (self.kind,)

    def holds(self, state: WorldState) -> bool:
        return state.held is not None and state.objects[state.held].kind == self.kind

    def achieve(self, state: WorldState) -> WorldState:
        if self.holds(state):
            return state
        here = state.robot.pos
        candidates = [
            (here.planar_distance(o.pos), uid)
            for uid, o in state.objects.items()
            if o.kind == self.kind and uid != state.held
        ]
        if not candidates:
            raise ValueError(f"{self}: no object of kind {self.kind!r} to grasp")
        state, uid = state.split(min(candidates)[1])  # one object off a pile
        return state.with_held(uid)

    def contradicts(self, other: Predicate) -> bool:
        if isinstance(other, IsGraspedKind):
            return other.kind != self.kind
        return isinstance(other, IsHandFree | IsHandFreeOver)


@dataclass(frozen=True, slots=True)
class IsHolding(Predicate):
    """True when the robot holds some object (h ≠ None)."""

    name = "IsHolding"

    def holds(self, state: WorldState) -> bool:
        return state.held is not None

    def contradicts(self, other: Predicate) -> bool:
        return isinstance(other, IsHandFree | IsHandFreeOver)


@dataclass(frozen=True, slots=True)
class IsHandFreeOver(Predicate):
    """True when the hand is free and the robot is over area ``area`` (inside its disc)."""

    area: str
    name = "IsHandFreeOver"

    @property
    def args(self) -> tuple:
        return (self.area,)

    def holds(self, state: WorldState) -> bool:
        return state.held is None and state.area(self.area).contains(state.robot.pos)

    def achieve(self, state: WorldState) -> WorldState:
        c = state.area(self.area).pos
        robot = state.robot
        out = state.with_robot_at(Pose(Point(c.x, c.y, robot.pos.z), robot.orientation))
        if state.held is None:
            return out
        old = state.objects[state.held].pose
        pose = Pose(Point(c.x, c.y, old.pos.z), old.orientation)
        return out.with_object_at(state.held, pose).with_held(None)

    def contradicts(self, other: Predicate) -> bool:
        return isinstance(other, IsGraspedObject | IsGraspedKind | IsHolding)


#: Predicate constructors by name, with the kind of each positional argument.
PREDICATES: dict[str, tuple[type[Predicate], tuple[str, ...]]] = {
    "IsObjectAt": (IsObjectAt, ("object", "area")),
    "IsRobotCloseTo": (IsRobotCloseTo, ("place",)),
    "IsHandFree": (IsHandFree, ()),
    "IsGraspedObject": (IsGraspedObject, ("object",)),
    "IsAreaFree": (IsAreaFree, ("area",)),
    "IsKindAt": (IsKindAt, ("kind", "area")),
    "IsGraspedKind": (IsGraspedKind, ("kind",)),
    "IsHolding": (IsHolding, ()),
    "IsHandFreeOver": (IsHandFreeOver, ("area",)),
}
