"""Ordering constraints C derived from the demonstration (SMP-MRO §IV-A2, §V-C1).

Two kinds, both written ``G_i ≤ G_j`` ("G_i is achieved before G_j"):

* **intent** — successive goals of the same object keep the demonstrated order;
* **physical** — two objects never occupy overlapping areas at the same time. Each object
  occupies a sequence of places (its initial place P, then the area of each of its goals),
  each for an *interval* of the demonstration that ends when the object's next goal moves
  it away. For two intervals of different objects whose areas overlap, the one the person
  created first must end before the other begins: ``G_leave ≤ G_arrive``.

Case 2 of the paper (swap O0 and O1 through free space) gives exactly
``{G0 ≤ G2, G1 ≤ G3}`` (intent) and ``{G0 ≤ G3, G1 ≤ G2}`` (physical).

A person may put O0 where O1 still stands and move O1 away afterwards: the robot cannot,
but it can move O1 first. Such a pair gives the same physical constraint, which then points
*backwards* in the demonstrated order ("reordered" in its reason). Forward constraints are
acyclic by construction; backward ones can close a cycle — a swap with no room, where each
object must leave before the other arrives. When the demonstration declares free areas,
each such cycle is broken as in the paper's recovery: one object of the cycle is first put
in a free area (a *buffer* goal, inserted just before the step that needed its place) and
the constraints are derived again. Without a free area the cycle is infeasible
(`InfeasibleError`, exit 1) and the message names its objects. A cycle that needs a
constraint the person specified explicitly is bad input (exit 2), as is an area occupied
forever (its object never leaves) or two objects overlapping at their initial places.

Cost: overlapping pairs are found by spatial hashing of the areas (cells as wide as the
largest area), so deriving C is linear in the steps plus the overlapping pairs.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass

import networkx as nx

from tamp.errors import InfeasibleError, InputError
from tamp.world.geometry import Area, Point


@dataclass(frozen=True)
class Step:
    """One goal in chronological order: ``obj`` is put in ``area`` (goal ``gid``)."""

    gid: str
    obj: str
    area: Area
    label: str  # "steps[k]" or "buffer via free_areas[i]" for messages


@dataclass(frozen=True)
class Buffer:
    """A goal the robot adds: ``obj`` waits in free area ``area`` before ``before``."""

    goal: str
    obj: str
    area: str
    before: str
    why: str

    def to_json(self) -> dict:
        return {
            "goal": self.goal,
            "object": self.obj,
            "area": self.area,
            "before": self.before,
            "why": self.why,
        }

    def __str__(self) -> str:
        return f"{self.goal}: {self.obj} -> {self.area} before {self.before} ({self.why})"


@dataclass(frozen=True)
class Interval:
    """Object ``obj`` stands in ``area`` from step ``start`` (−1: initially) until ``end``.

    ``start`` and ``end`` are positions in the chronological step list.
    """

    obj: str
    area: Area
    start: int
    end: int | None  # position of the step that moves it away; None: never
    label: str  # "objects[i]" or "steps[k]" for messages


@dataclass(frozen=True)
class Derived:
    """The steps in chronological order (buffers included), C and a reason per constraint."""

    steps: list[Step]
    constraints: frozenset[tuple[str, str]]
    reasons: dict[tuple[str, str], str]
    buffers: list[Buffer]
    free_left: list[Area]


def occupancy_intervals(
    objects: dict[str, Point], object_labels: dict[str, str], steps: list[Step], radius: float
) -> list[Interval]:
    """Every (object, place, time span) of the demonstration, in O(objects + steps)."""
    own: dict[str, list[int]] = defaultdict(list)
    for k, s in enumerate(steps):
        own[s.obj].append(k)
    intervals = []
    for obj, p in objects.items():
        mine = own.get(obj, [])
        intervals.append(
            Interval(
                obj, Area(f"P_{obj}", p, radius), -1, mine[0] if mine else None, object_labels[obj]
            )
        )
        for i, k in enumerate(mine):
            end = mine[i + 1] if i + 1 < len(mine) else None
            intervals.append(Interval(obj, steps[k].area, k, end, steps[k].label))
    return intervals


def overlapping_pairs(intervals: list[Interval]) -> list[tuple[int, int]]:
    """Index pairs (i < j) of intervals of different objects whose areas overlap.

    Spatial hashing: each area goes in the grid cell of its centre, cells as wide as the
    largest diameter, so overlapping areas lie in neighbouring cells.
    """
    if not intervals:
        return []
    cell = max(2 * iv.area.radius for iv in intervals) or 1.0
    grid: dict[tuple[int, int], list[int]] = defaultdict(list)
    for i, iv in enumerate(intervals):
        grid[(math.floor(iv.area.pos.x / cell), math.floor(iv.area.pos.y / cell))].append(i)
    pairs = []
    for (cx, cy), members in grid.items():
        near = [
            j for dx in (-1, 0, 1) for dy in (-1, 0, 1) for j in grid.get((cx + dx, cy + dy), ())
        ]
        for i in members:
            a = intervals[i]
            for j in near:
                if j <= i:
                    continue
                b = intervals[j]
                if a.obj != b.obj and a.area.overlaps(b.area):
                    pairs.append((i, j))
    pairs.sort()
    return pairs


def _physical(
    objects, object_labels, steps: list[Step], radius: float, file: str
) -> tuple[dict[tuple[str, str], str], set[tuple[str, str]]]:
    """Physical constraints with reasons, and which of them point backwards in time."""
    reasons: dict[tuple[str, str], str] = {}
    backward: set[tuple[str, str]] = set()
    intervals = occupancy_intervals(objects, object_labels, steps, radius)
    for i, j in overlapping_pairs(intervals):
        a, b = intervals[i], intervals[j]
        first, second = (a, b) if a.start <= b.start else (b, a)
        if first.start == -1 and second.start == -1:
            raise InputError(
                f"objects {first.obj} and {second.obj} overlap at their initial places",
                file=file,
                field=f"{first.label} / {second.label}",
            )
        if first.end is None:
            where = "initial place" if first.start == -1 else f"goal {steps[first.start].gid}"
            raise InputError(
                f"{second.label} moves {second.obj} into the area of {first.obj}'s {where} "
                f"({first.label}), which {first.obj} never leaves: that area is occupied "
                "forever",
                file=file,
                field=second.label,
            )
        pair = (steps[first.end].gid, steps[second.start].gid)
        if first.end > second.start:
            why = (
                f"physical (reordered): {first.obj} must leave the area ({first.label}) "
                f"before {second.obj} is placed there ({second.label}); the person placed "
                f"{second.obj} while {first.obj} still stood there, until {steps[first.end].label}"
            )
            if pair not in reasons:
                backward.add(pair)
        else:
            why = (
                f"physical: {first.obj} must leave the area ({first.label}) before "
                f"{second.obj} is placed there ({second.label})"
            )
        reasons.setdefault(pair, why)
    return reasons, backward


def derive_constraints(
    objects: dict[str, Point],
    object_labels: dict[str, str],
    steps: list[tuple[str, Point]],
    radius: float,
    explicit: list[tuple[str, str]],
    file: str,
    free_areas: list[Area] | None = None,
) -> Derived:
    """C = intent ∪ physical ∪ explicit, with a reason per constraint; refuses bad demos.

    Steps ``k`` are goals ``G<k>``; buffer goals (see the module notes) are numbered after
    them and placed in the chronological step list where they happen.
    """
    chron = [
        Step(f"G{k}", o, Area(f"L{k}", p, radius), f"steps[{k}]") for k, (o, p) in enumerate(steps)
    ]
    ids = {s.gid for s in chron}
    for i, (gi, gj) in enumerate(explicit):
        for g in (gi, gj):
            if g not in ids:
                raise InputError(f"unknown goal {g!r}", file=file, field=f"constraints[{i}]")
        if gi == gj:
            raise InputError(f"{gi} <= {gi} is not an order", file=file, field=f"constraints[{i}]")
    free = list(free_areas or [])
    buffers: list[Buffer] = []
    while True:
        reasons: dict[tuple[str, str], str] = {}
        last: dict[str, str] = {}
        for s in chron:
            if s.obj in last:
                reasons[(last[s.obj], s.gid)] = f"intent: successive goals of {s.obj}"
            last[s.obj] = s.gid
        physical, backward = _physical(objects, object_labels, chron, radius, file)
        for pair, why in physical.items():
            reasons.setdefault(pair, why)
        for gi, gj in explicit:
            reasons.setdefault((gi, gj), "specified by the person")
        cycle = _cycle(reasons)
        if cycle is None:
            return Derived(chron, frozenset(reasons), reasons, buffers, free)
        edges = list(zip(cycle, cycle[1:] + cycle[:1], strict=True))
        by_id = {s.gid: s for s in chron}
        chain = " <= ".join([*cycle, cycle[0]])
        if any(reasons[e] == "specified by the person" for e in edges) or not any(
            e in backward for e in edges
        ):
            steps_named = ", ".join(by_id[g].label for g in cycle)
            raise InputError(
                f"the ordering constraints are cyclic ({chain}); steps involved: {steps_named}",
                file=file,
                field="constraints",
            )
        objs = sorted({by_id[g].obj for g in cycle})
        if not free:
            raise InfeasibleError(
                f"objects {', '.join(objs)} must each leave a place before another arrives there "
                f"(cycle {chain}; {', '.join(by_id[g].label for g in cycle)}): a swap with no "
                "room. Declare a free area (free_areas:) to pass one of them through it"
            )
        leave, arrive = next(e for e in edges if e in backward)
        chron, buf = _insert_buffer(
            chron, by_id[leave], by_id[arrive], free.pop(0), len(steps) + len(buffers), objs
        )
        buffers.append(buf)


def _cycle(reasons: dict[tuple[str, str], str]) -> list[str] | None:
    """The goals of one cycle of C in order, or None."""
    try:
        cycle = nx.find_cycle(nx.DiGraph(list(reasons)))
    except nx.NetworkXNoCycle:
        return None
    return [u for u, _ in cycle]


def _insert_buffer(
    chron: list[Step], leave: Step, arrive: Step, area: Area, number: int, objs: list[str]
) -> tuple[list[Step], Buffer]:
    """Put ``leave``'s object in free ``area`` just before ``arrive`` needs its place."""
    at = chron.index(arrive)
    # the object that must leave: whoever stood where ``arrive`` goes until ``leave``
    obj = leave.obj
    gid = f"G{number}"
    step = Step(gid, obj, area, f"buffer via free area {area.name}")
    why = (
        f"breaks the cycle of {', '.join(objs)}: {obj} must leave before {arrive.gid} "
        f"and cannot go to its next place yet"
    )
    return [*chron[:at], step, *chron[at:]], Buffer(gid, obj, area.name, arrive.gid, why)
