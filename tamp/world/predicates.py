"""The five condition templates of SMP-MRO §V-A2, as hashable pure functions of a WorldState.

Each predicate also knows how to *make itself true* (``achieve``), which is how action
effects are applied symbolically, and which other predicates it *contradicts* (two
conditions that no state satisfies together), which is what the BT layer's conflict check
needs (§IV-C3: IsGraspedObject(O1) vs IsGraspedObject(Oa)).

Choices where the paper is silent (written down here on purpose):
- ``IsObjectAt(o, l)`` is false while ``o`` is held: a carried object is not *at* an area.
- ``IsAreaFree(l)`` ignores the held object, which travels with the robot.
- ``IsRobotCloseTo(ref, d)`` takes an object or area name; ``d`` defaults to the domain's
  reach (0.9 m, the paper's default). The paper writes ``IsRobotCloseTo(l.pos, l.radius)``
  for MoveTo/Place, which would put a mobile base on top of the goal area; a reach radius
  is what a mobile manipulator can satisfy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from tamp.world.geometry import Point, Pose, Quaternion
from tamp.world.state import WorldState

DEFAULT_REACH = 0.9


class Predicate:
    """Base class: ``holds(state)``, ``achieve(state)``, ``contradicts(other)``."""

    name: str = ""

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
    """True when object ``obj`` lies (not held) inside area ``area``."""

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
        return state.area(self.area).contains(o.pos)

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
        return isinstance(other, IsGraspedObject)


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
        if isinstance(other, IsHandFree):
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


#: Predicate constructors by name, with the kind of each positional argument.
PREDICATES: dict[str, tuple[type[Predicate], tuple[str, ...]]] = {
    "IsObjectAt": (IsObjectAt, ("object", "area")),
    "IsRobotCloseTo": (IsRobotCloseTo, ("place",)),
    "IsHandFree": (IsHandFree, ()),
    "IsGraspedObject": (IsGraspedObject, ("object",)),
    "IsAreaFree": (IsAreaFree, ("area",)),
}
