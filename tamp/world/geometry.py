"""Geometric value types of SMP-MRO §V-A1: Point, Quaternion, Pose, and circular Area."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Point:
    """A position in 3-D (metres, robot map frame unless said otherwise)."""

    x: float
    y: float
    z: float = 0.0

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.z)

    def planar_distance(self, other: Point) -> float:
        """Distance in the floor plane; areas and robot proximity are planar (§V-A2)."""
        return math.hypot(self.x - other.x, self.y - other.y)

    def distance(self, other: Point) -> float:
        return math.dist(self.as_tuple(), other.as_tuple())

    @staticmethod
    def of(values: tuple[float, ...] | list[float]) -> Point:
        if len(values) == 2:
            return Point(float(values[0]), float(values[1]), 0.0)
        return Point(float(values[0]), float(values[1]), float(values[2]))


@dataclass(frozen=True, slots=True)
class Quaternion:
    """A unit quaternion (x, y, z, w), as in the paper's Pose structure."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    w: float = 1.0

    @staticmethod
    def from_yaw(yaw: float) -> Quaternion:
        return Quaternion(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))

    def yaw(self) -> float:
        return math.atan2(
            2.0 * (self.w * self.z + self.x * self.y), 1.0 - 2.0 * (self.y**2 + self.z**2)
        )


@dataclass(frozen=True, slots=True)
class Pose:
    """Position and orientation (the paper's ``Pose``: Point pos, Quaternion orientation)."""

    pos: Point
    orientation: Quaternion = Quaternion()

    @staticmethod
    def at(x: float, y: float, z: float = 0.0, yaw: float = 0.0) -> Pose:
        return Pose(Point(x, y, z), Quaternion.from_yaw(yaw))


@dataclass(frozen=True, slots=True)
class Area:
    """A circular region on the floor (§V-A1: Point pos, double radius); ``p ∈ l`` is planar."""

    name: str
    pos: Point
    radius: float

    def contains(self, p: Point) -> bool:
        return self.pos.planar_distance(p) <= self.radius + 1e-9

    def overlaps(self, other: Area) -> bool:
        """True when the two discs share more than a boundary point."""
        return self.pos.planar_distance(other.pos) < self.radius + other.radius - 1e-9
