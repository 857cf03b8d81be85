"""Graspable objects built from primitives, with grasps known from their geometry.

The LOTS workcell objects (hammer, screwdriver, screw, saw, scissors, tower blocks) and
random primitives (boxes, lying and standing cylinders). Each object lies on the table in
its own frame O (origin on the table surface, z up); every part is a box or a cylinder
with its pose in O, and every grasp is a top-down antipodal grasp: a centre on the top of
the part, a closing direction in the table plane, an opening and a jaw size (metres).
This module is pure numpy so that the grasp geometry can be tested without Drake; the
renderer in :mod:`tamp.grasp.synthetic` turns it into images and Jacquard rectangles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: Largest opening of the gripper (Panda hand: 8 cm); wider grasps are not generated.
MAX_OPENING = 0.08
#: Finger clearance added to the object's width to get the gripper opening.
CLEARANCE = 0.01
#: Jaw (finger pad) size across the closing direction.
JAW = 0.02

TOOLS = ("hammer", "screwdriver", "screw", "saw", "scissors", "block")
PRIMITIVES = ("box", "cylinder_lying", "cylinder_standing")


@dataclass(frozen=True, slots=True)
class Part:
    """A box (``size`` = x, y, z extents) or a cylinder (``size`` = radius, length).

    ``xyz`` is the part centre in O; ``yaw`` turns it about z; a cylinder with
    ``lying=True`` has its axis along the part's x-axis, otherwise along z.
    """

    shape: str
    size: tuple[float, ...]
    xyz: tuple[float, float, float]
    yaw: float = 0.0
    lying: bool = False
    rgba: tuple[float, float, float, float] = (0.5, 0.5, 0.5, 1.0)

    @property
    def top(self) -> float:
        """Height of the part's top above the table."""
        if self.shape == "box":
            return self.xyz[2] + self.size[2] / 2
        r, length = self.size
        return self.xyz[2] + (r if self.lying else length / 2)


@dataclass(frozen=True, slots=True)
class Grasp3D:
    """A top-down grasp in O: centre (on the part's top), closing yaw, opening, jaw size."""

    center: tuple[float, float, float]
    yaw: float
    opening: float
    jaw: float = JAW


@dataclass(frozen=True, slots=True)
class GraspObject:
    """A named object made of parts, with its grasps and a bounding radius for placement."""

    name: str
    parts: tuple[Part, ...]
    grasps: tuple[Grasp3D, ...]
    radius: float = field(default=0.1)


def _color(rng: np.random.Generator) -> tuple[float, float, float, float]:
    c = rng.uniform(0.15, 0.95, size=3)
    return (float(c[0]), float(c[1]), float(c[2]), 1.0)


#: Spacing of the grasps listed along a bar: dense (half a jaw), so that every point of the
#: bar's centre line is covered by some ground-truth rectangle, as in Jacquard's dense
#: annotations; sparse samples would make the quality map learn an arbitrary phase.
SPACING = 0.01


def _bar_grasps(
    x0: float, x1: float, width: float, top: float, yaw: float = 0.0, y: float = 0.0
) -> list[Grasp3D]:
    """Grasps across a bar of ``width`` lying along x from ``x0`` to ``x1`` (rotated by yaw),
    every :data:`SPACING` along it with the jaw inside the bar."""
    if width + CLEARANCE > MAX_OPENING:
        return []
    length = x1 - x0
    jaw = min(JAW, length)
    free = length - jaw
    n = int(math.floor(free / SPACING + 1e-9)) + 1
    start = x0 + jaw / 2 + (free - (n - 1) * SPACING) / 2
    c, s = math.cos(yaw), math.sin(yaw)
    out = []
    for i in range(n):
        t = start + i * SPACING
        out.append(
            Grasp3D((t * c - y * s, t * s + y * c, top), yaw + math.pi / 2, width + CLEARANCE, jaw)
        )
    return out


def box_object(name: str, size, rgba, yaw_grasps_both: bool | None = None) -> GraspObject:
    """A box lying on the table: grasps across its narrow axis, along its length."""
    lx, ly, lz = (float(v) for v in size)
    if lx < ly:
        lx, ly = ly, lx
    part = Part("box", (lx, ly, lz), (0.0, 0.0, lz / 2), rgba=rgba)
    grasps = _bar_grasps(-lx / 2, lx / 2, ly, lz)
    both = lx + CLEARANCE <= MAX_OPENING if yaw_grasps_both is None else yaw_grasps_both
    if both:  # a near-cube can be taken across either pair of faces
        grasps += _bar_grasps(-ly / 2, ly / 2, lx, lz, yaw=math.pi / 2)
    return GraspObject(name, (part,), tuple(grasps), radius=math.hypot(lx, ly) / 2)


def cylinder_lying(name: str, radius: float, length: float, rgba) -> GraspObject:
    part = Part("cylinder", (radius, length), (0.0, 0.0, radius), lying=True, rgba=rgba)
    grasps = _bar_grasps(-length / 2, length / 2, 2 * radius, 2 * radius)
    return GraspObject(name, (part,), tuple(grasps), radius=math.hypot(length / 2, radius))


def cylinder_standing(name: str, radius: float, height: float, rgba) -> GraspObject:
    """An upright cylinder: round, so every closing direction works (six listed, 30 deg)."""
    part = Part("cylinder", (radius, height), (0.0, 0.0, height / 2), rgba=rgba)
    grasps = []
    if 2 * radius + CLEARANCE <= MAX_OPENING:
        jaw = min(JAW, 2 * radius)
        grasps = [
            Grasp3D((0.0, 0.0, height), math.radians(a), 2 * radius + CLEARANCE, jaw)
            for a in range(0, 180, 30)
        ]
    return GraspObject(name, (part,), tuple(grasps), radius=radius)


def make_object(kind: str, rng: np.random.Generator) -> GraspObject:
    """One object of ``kind`` (a tool of :data:`TOOLS` or a primitive of :data:`PRIMITIVES`)."""
    col = _color(rng)
    if kind == "hammer":
        hl, hw = rng.uniform(0.18, 0.24), rng.uniform(0.02, 0.03)
        handle = Part("box", (hl, hw, 0.02), (0.0, 0.0, 0.01), rgba=col)
        head_w = rng.uniform(0.08, 0.11)
        head = Part("box", (0.03, head_w, 0.03), (hl / 2 + 0.015, 0.0, 0.015), rgba=_color(rng))
        grasps = _bar_grasps(-hl / 2, hl / 2 - 0.03, hw, 0.02)
        grasps.append(Grasp3D((hl / 2 + 0.015, 0.0, 0.03), 0.0, 0.03 + CLEARANCE, JAW))
        return GraspObject(kind, (handle, head), tuple(grasps), radius=hl / 2 + 0.04)
    if kind == "screwdriver":
        r, hl = rng.uniform(0.011, 0.017), rng.uniform(0.08, 0.10)
        shaft_l = rng.uniform(0.07, 0.11)
        handle = Part("cylinder", (r, hl), (-hl / 2, 0.0, r), lying=True, rgba=col)
        shaft = Part("cylinder", (0.004, shaft_l), (shaft_l / 2, 0.0, r), lying=True,
                     rgba=(0.7, 0.7, 0.72, 1.0))  # fmt: skip
        grasps = _bar_grasps(-hl, 0.0, 2 * r, 2 * r)
        return GraspObject(kind, (handle, shaft), tuple(grasps), radius=max(hl, shaft_l) + 0.01)
    if kind == "screw":
        length = rng.uniform(0.035, 0.05)
        shank = Part("cylinder", (0.005, length), (0.0, 0.0, 0.008), lying=True, rgba=col)
        head = Part("cylinder", (0.008, 0.005), (-length / 2 - 0.0025, 0.0, 0.008), lying=True,
                    rgba=col)  # fmt: skip
        grasps = _bar_grasps(-length / 2 + 0.005, length / 2 - 0.005, 0.01, 0.013)
        return GraspObject(kind, (shank, head), tuple(grasps), radius=length / 2 + 0.01)
    if kind == "saw":
        bl, bw = rng.uniform(0.18, 0.24), rng.uniform(0.06, 0.08)
        blade = Part("box", (bl, bw, 0.004), (bl / 2, 0.0, 0.002), rgba=(0.75, 0.75, 0.78, 1.0))
        hw = rng.uniform(0.025, 0.035)
        handle = Part("box", (0.10, hw, 0.03), (-0.05, 0.0, 0.015), rgba=col)
        grasps = _bar_grasps(-0.09, -0.01, hw, 0.03)
        return GraspObject(kind, (blade, handle), tuple(grasps), radius=0.1 + bl / 2)
    if kind == "scissors":
        blade = Part("box", (0.10, 0.02, 0.01), (0.05, 0.0, 0.005), rgba=(0.75, 0.75, 0.78, 1.0))
        ring1 = Part("cylinder", (0.018, 0.01), (-0.02, 0.02, 0.005), rgba=col)
        ring2 = Part("cylinder", (0.018, 0.01), (-0.02, -0.02, 0.005), rgba=col)
        grasps = _bar_grasps(0.02, 0.09, 0.02, 0.01)
        return GraspObject(kind, (blade, ring1, ring2), tuple(grasps), radius=0.1)
    if kind == "block":
        if rng.random() < 0.5:
            s = rng.uniform(0.03, 0.05)
            size = (s, s, s)
        else:
            size = (rng.uniform(0.06, 0.10), rng.uniform(0.025, 0.04), rng.uniform(0.025, 0.04))
        return box_object(kind, size, col)
    if kind == "box":
        narrow = rng.uniform(0.02, 0.06)
        size = (rng.uniform(narrow, 0.15), narrow, rng.uniform(0.015, 0.06))
        return box_object(kind, size, col)
    if kind == "cylinder_lying":
        return cylinder_lying(kind, rng.uniform(0.01, 0.03), rng.uniform(0.05, 0.15), col)
    if kind == "cylinder_standing":
        return cylinder_standing(kind, rng.uniform(0.012, 0.035), rng.uniform(0.02, 0.08), col)
    raise ValueError(f"unknown object kind {kind!r}; expected one of {TOOLS + PRIMITIVES}")


def grasp_world(grasp: Grasp3D, x: float, y: float, yaw: float) -> tuple[np.ndarray, float]:
    """Grasp centre in the world and closing yaw, for an object placed at (x, y, yaw)."""
    c, s = math.cos(yaw), math.sin(yaw)
    gx, gy, gz = grasp.center
    return np.array([x + c * gx - s * gy, y + s * gx + c * gy, gz]), grasp.yaw + yaw
