"""Build a `Demonstration` directly in the robot frame (used by the loader, tests, benchmarks)."""

from __future__ import annotations

import math

from tamp.demo.constraints import derive_constraints
from tamp.demo.model import Demonstration, Goal
from tamp.world.events import Appear
from tamp.world.geometry import Area, Point, Pose, Quaternion


def make_demonstration(
    objects: dict[str, Point],
    steps: list[tuple[str, Point]],
    radius: float,
    *,
    free_areas: list[Area] | None = None,
    start: Pose | None = None,
    explicit: list[tuple[str, str]] | None = None,
    object_height: float = 0.2,
    domain_file: str | None = None,
    source: str = "<memory>",
    object_labels: dict[str, str] | None = None,
    appear: tuple[Appear, ...] = (),
) -> Demonstration:
    """Goals ``G<k>`` for step k, constraints C derived (and checked) from the steps.

    A swap with no room is broken through a free area when there is one (a buffer goal,
    numbered after the steps; that free area is then a goal area, no longer free).
    """
    labels = object_labels or {o: f"objects[{i}]" for i, o in enumerate(objects)}
    derived = derive_constraints(
        objects, labels, steps, radius, explicit or [], source, list(free_areas or [])
    )
    goals = [Goal(s.gid, s.obj, s.area.pos, s.area, int(s.gid[1:])) for s in derived.steps]
    return Demonstration(
        objects=dict(objects),
        goals=goals,
        constraints=derived.constraints,
        free_areas=derived.free_left,
        robot_start=start or Pose(Point(0.0, 0.0, 0.0)),
        area_radius=radius,
        object_height=object_height,
        domain_file=domain_file,
        source=source,
        constraint_reasons=derived.reasons,
        appear=tuple(appear),
        buffers=tuple(derived.buffers),
    )


def cyclic_swap(
    n: int, *, layout: str = "shelf", spacing: float = 0.6, slot: float = 0.5
) -> Demonstration:
    """The benchmark family: n objects each move to the start place of the next one.

    A cyclic permutation needs buffers: the person first puts every object O_i in its own
    free area F_i, then each O_i in the start place of O_{i+1 mod n}. The derived
    constraints are G_i ≤ G_{n+i} (intent) and G_{i+1} ≤ G_{n+i} (O_{i+1} must have left
    before O_i arrives): a partial order whose RG grows like 2.6^n.

    ``layout="shelf"`` (the benchmark's): the objects stand in a row along a shelf
    (``spacing`` apart along x, starting at the robot) and the buffers form a 4-wide grid
    of ``slot``-spaced places on a staging table beside the start of the shelf.
    ``layout="staging"``: the row runs across the robot's front (x = 1 m) with the staging
    grid behind it. ``layout="ring"``: objects on a circle around the robot, each buffer
    radially outside its object — maximally symmetric, the hardest case for the search.
    """
    objects: dict[str, Point] = {}
    buffers: list[Point] = []
    if layout == "shelf":
        for i in range(n):
            objects[f"O{i}"] = Point(i * spacing, 0.0, 0.0)
            buffers.append(Point(-1.0 - (i % 4) * slot, 1.0 + (i // 4) * slot, 0.0))
    elif layout == "staging":
        for i in range(n):
            objects[f"O{i}"] = Point(1.0, i * spacing, 0.0)
            buffers.append(Point(-0.5 - (i // 4) * slot, 1.0 + (i % 4) * slot, 0.0))
    elif layout == "ring":
        ring = max(1.0, n * spacing / (2 * math.pi))
        for i in range(n):
            a = 2 * math.pi * i / n
            objects[f"O{i}"] = Point(ring * math.cos(a), ring * math.sin(a), 0.0)
            r = ring + 0.8
            buffers.append(Point(r * math.cos(a), r * math.sin(a), 0.0))
    else:
        raise ValueError(f"unknown layout {layout!r} (shelf, staging, ring)")
    places = list(objects.values())
    steps = [(f"O{i}", buffers[i]) for i in range(n)]
    steps += [(f"O{i}", places[(i + 1) % n]) for i in range(n)]
    start = Pose(Point(0.0, 0.0, 0.0), Quaternion())
    return make_demonstration(
        objects, steps, 0.15, start=start, source=f"<cyclic_swap n={n} layout={layout}>"
    )
