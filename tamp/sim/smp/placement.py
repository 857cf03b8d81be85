"""Where objects stand, judged in 3-D on plant poses (no Drake import).

Three questions the workcell asks of the plant, answered one way everywhere:

- `why_not_in(...)`: does an object *rest in* an area? Its centre lies within the area's
  radius in the floor plane AND it stands upright on the floor (its centre at the object's
  half height, within `ON_FLOOR_TOL`, and, where the caller knows it, its axis within
  `TILT_TOL` of the vertical). An object resting on top of another one is not in the
  area, whatever its x and y (an O0 pushed onto O_a rests with its centre at z = 0.25 m,
  not 0.10 m, inside the area's circle: not placed). The Place skill's final check
  (positions only, no tilt) and the run's success (`tamp.sim.smp.runner`, with tilts) both
  use it.
- `blocker(...)` / `free_spot(...)`: is a place occupied for an object a person puts down
  there (another object's footprint overlaps its own and the other object is not held high
  above, or the robot's base stands there)? If so, the nearest spot outside every area and
  every footprint (rings of candidates around the place, nearest first).
- `disturbances(...)`: which objects, goal objects or not, the run left in a state a task
  must not leave them in: knocked over (tilted beyond `TILT_TOL`), standing on top of
  another object, or, never picked by the robot, moved more than `MOVE_TOL` in the plane
  from where the scenario or the scripted person last put them. SMP-MRO's tasks (Nakamura
  & Sekiyama, IEEE Access, §V) ask for goal objects in goal areas; a run that reaches them
  by toppling an obstacle it never believed was there has not done its task. The run's
  verdict (`tamp.sim.smp.runner.judge`) fails on any of them.
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

TILT_TOL = math.radians(10.0)
"""rad between an object's axis and the vertical beyond which it is *knocked over*. An
object standing on the flat floor tilts well under 1 degree (contact compliance); the
packaged models tip over past atan(radius / half height), 19 degrees for the bottle and 33
for the obstacle box, so 10 degrees flags one leaning on a neighbour before it would fall
and stays ten times above the settling noise."""

MOVE_TOL = 0.03
"""m in the floor plane an object the robot never picked may end away from where it was
put (its start pose, or where the person put it down). Settling after a put moves an
untouched object by millimetres; 3 cm is less than the smallest packaged footprint
radius (the bottle's 3.5 cm), so a larger shift means something pushed it."""


@dataclass(frozen=True)
class Body:
    """An object as the plant has it now: centre (m) and model kind."""

    id: str
    x: float
    y: float
    z: float
    kind: ObjectKind
    #: rad between the object's own vertical axis and the world's (0: standing upright)
    tilt: float = 0.0

    @property
    def bottom(self) -> float:
        return self.z - self.kind.half_height

    @property
    def upright(self) -> bool:
        """Standing on its base: tilted no more than `TILT_TOL`."""
        return self.tilt <= TILT_TOL

    @property
    def reach(self) -> float:
        """How far it reaches from its centre in the floor plane: its footprint radius
        upright, its half-diagonal (radius, half height) once knocked over."""
        if self.upright:
            return self.kind.radius
        return math.hypot(self.kind.radius, self.kind.half_height)


def under(body: Body, others: Iterable[Body]) -> list[str]:
    """The objects below ``body``'s centre whose reach overlaps its own in the plane: what
    it stands on when it does not stand on the floor."""
    return [
        o.id
        for o in others
        if o.id != body.id
        and o.z < body.z
        and math.hypot(o.x - body.x, o.y - body.y) < o.reach + body.reach
    ]


def why_not_in(body: Body, area: Area, others: Iterable[Body] = ()) -> str | None:
    """None when ``body`` rests in ``area`` (planar centre inside, on the floor, tilted no
    more than `TILT_TOL`); else why not, naming the object it stands on when one lies
    below it. The tilt matters on its own: a bottle leaning 32° on its bottom rim has its
    centre 3 mm above its upright height, on the floor by height alone."""
    if math.hypot(body.x - area.pos.x, body.y - area.pos.y) > area.radius:
        return f"{body.id} ended outside {area.name}"
    if abs(body.z - body.kind.half_height) > ON_FLOOR_TOL:
        below = under(body, others)
        on = f", on top of {', '.join(below)}" if below else ""
        return (
            f"{body.id} is not resting on the floor (z = {body.z:.3f} m, on the floor "
            f"{body.kind.half_height:.3f} m{on})"
        )
    if not body.upright:
        return f"{body.id} is not upright in {area.name} (tilt {math.degrees(body.tilt):.0f}°)"
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


@dataclass(frozen=True)
class Disturbance:
    """One object the run left disturbed: knocked over, on top of other objects, and/or
    moved without being picked (``moved``: m in the plane from where it was put; None when
    the robot picked it or nobody put it anywhere known)."""

    id: str
    tilt: float  # rad
    on: tuple[str, ...] = ()
    moved: float | None = None

    @property
    def knocked_over(self) -> bool:
        return self.tilt > TILT_TOL

    @property
    def displaced(self) -> bool:
        return self.moved is not None and self.moved > MOVE_TOL

    @property
    def reason(self) -> str:
        """``Oa knocked over (tilt 88°), moved 6.2 cm though the robot never picked it``."""
        what = []
        if self.knocked_over:
            what.append(f"knocked over (tilt {math.degrees(self.tilt):.0f}°)")
        if self.on:
            what.append(f"on top of {', '.join(self.on)}")
        if self.displaced:
            what.append(f"moved {self.moved * 100:.1f} cm though the robot never picked it")
        return f"{self.id} {', '.join(what)}"

    def to_json(self) -> dict:
        return {
            "object": self.id,
            "reason": self.reason,
            "tilt_deg": round(math.degrees(self.tilt), 1),
            "on": list(self.on),
            "moved": None if self.moved is None else round(self.moved, 4),
        }


def disturbances(
    bodies: Iterable[Body],
    put: Mapping[str, tuple[float, float]],
    picked: Iterable[str],
) -> list[Disturbance]:
    """The objects of ``bodies`` (every object present at the end, goal or not) left
    knocked over (`TILT_TOL`), standing on top of another object (upright, its base more
    than `ON_FLOOR_TOL` above the floor, an object below it: `under`), or, when not in
    ``picked`` (the objects the robot picked), more than `MOVE_TOL` in the plane from
    ``put`` (object -> (x, y) where the scenario or the person last put it). Objects the
    robot moved on purpose (picked) pass when upright and on the floor."""
    bodies = list(bodies)
    picked = set(picked)
    out = []
    for b in bodies:
        on = tuple(under(b, bodies)) if b.upright and b.bottom > ON_FLOOR_TOL else ()
        moved = None
        if b.id not in picked and b.id in put:
            moved = math.hypot(b.x - put[b.id][0], b.y - put[b.id][1])
        d = Disturbance(b.id, b.tilt, on, moved)
        if d.knocked_over or d.on or d.displaced:
            out.append(d)
    return out
