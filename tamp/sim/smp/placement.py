"""Where objects stand, judged in 3-D on plant poses (no Drake import).

Two questions the workcell asks of the plant, answered one way everywhere:

- `why_not_in(...)`: does an object *rest in* an area? Its centre lies within the area's
  radius in the floor plane AND it stands upright on the floor (its centre at the object's
  half height, within `ON_FLOOR_TOL`). An object resting on top of another one is not in
  the area, whatever its x and y (an O0 pushed onto O_a rests with its centre at z = 0.25 m,
  not 0.10 m, inside the area's circle: not placed). The Place
  skill's final check and the run's success (`tamp.sim.smp.runner`) both use it.
- `blocker(...)` / `free_spot(...)`: is a place occupied for an object a person puts down
  there (another object's footprint overlaps its own and the other object is not held high
  above, or the robot's base stands there)? If so, the nearest spot outside every area and
  every footprint (rings of candidates around the place, nearest first).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from tamp.sim.smp.robot import ObjectKind
from tamp.world.geometry import Area

ON_FLOOR_TOL = 0.01  # m: |z - half_height| of an object standing upright on the floor
GAP = 0.01  # m: gap kept between footprints when a person puts an object down
RING_STEP = 0.05  # m between rings of candidate spots around an occupied place
RING_CANDIDATES = 24  # candidates per ring (every 15 degrees, starting on +x)
MAX_RING_RADIUS = 3.0  # m: beyond this no spot is looked for


@dataclass(frozen=True)
class Body:
    """An object as the plant has it now: centre (m) and model kind."""

    id: str
    x: float
    y: float
    z: float
    kind: ObjectKind

    @property
    def bottom(self) -> float:
        return self.z - self.kind.half_height


def why_not_in(body: Body, area: Area, others: Iterable[Body] = ()) -> str | None:
    """None when ``body`` rests in ``area`` (planar centre inside, upright on the floor);
    else why not, naming the object it stands on when one lies below it."""
    if math.hypot(body.x - area.pos.x, body.y - area.pos.y) > area.radius:
        return f"{body.id} ended outside {area.name}"
    if abs(body.z - body.kind.half_height) > ON_FLOOR_TOL:
        under = [
            o.id
            for o in others
            if o.id != body.id
            and o.z < body.z
            and math.hypot(o.x - body.x, o.y - body.y) < o.kind.radius + body.kind.radius
        ]
        on = f", on top of {', '.join(under)}" if under else ""
        return (
            f"{body.id} is not resting on the floor (z = {body.z:.3f} m, on the floor "
            f"{body.kind.half_height:.3f} m{on})"
        )
    return None


def blocker(
    x: float,
    y: float,
    kind: ObjectKind,
    bodies: Iterable[Body],
    robot: tuple[float, float, float] | None = None,
) -> str | None:
    """What occupies the spot (x, y) for an object of ``kind`` put down on the floor there:
    an object whose footprint overlaps (unless it is carried above the new object's top),
    or ``"the robot"`` when the base stands there (``robot`` = (x, y, footprint radius))."""
    top = 2.0 * kind.half_height
    for b in bodies:
        if b.bottom >= top:
            continue  # carried above: the new object fits under it
        if math.hypot(b.x - x, b.y - y) < b.kind.radius + kind.radius + GAP:
            return b.id
    if robot is not None and math.hypot(robot[0] - x, robot[1] - y) < robot[2] + kind.radius:
        return "the robot"
    return None


def free_spot(
    x: float,
    y: float,
    kind: ObjectKind,
    *,
    bodies: Iterable[Body],
    areas: Mapping[str, Area],
    workspace: tuple[float, float, float, float],
    robot: tuple[float, float, float] | None = None,
) -> tuple[float, float] | None:
    """The nearest spot to (x, y) outside every area and footprint, inside the workspace.

    Rings every `RING_STEP` around (x, y), `RING_CANDIDATES` per ring; the first ring with a
    valid candidate wins, the smallest angle among equals. None when none lies within
    `MAX_RING_RADIUS`.
    """
    bodies = list(bodies)
    xmin, xmax, ymin, ymax = workspace
    m = kind.radius
    rings = int(round(MAX_RING_RADIUS / RING_STEP))
    for ring in range(1, rings + 1):
        r = ring * RING_STEP
        for k in range(RING_CANDIDATES):
            ang = 2.0 * math.pi * k / RING_CANDIDATES
            cx, cy = x + r * math.cos(ang), y + r * math.sin(ang)
            if not (xmin + m <= cx <= xmax - m and ymin + m <= cy <= ymax - m):
                continue
            if any(
                math.hypot(cx - a.pos.x, cy - a.pos.y) < a.radius + m + GAP for a in areas.values()
            ):
                continue
            if blocker(cx, cy, kind, bodies, robot) is not None:
                continue
            return (cx, cy)
    return None
