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

Because every derived constraint points forward in the demonstrated order, they are
acyclic by construction; a cycle can only come from constraints the person specified
explicitly, and is refused. Demonstrations that cannot be executed are refused with the
steps involved: an area occupied forever (its object never leaves), or two objects in
overlapping areas at the same stage.
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx

from tamp.errors import InputError
from tamp.world.geometry import Area, Point


@dataclass(frozen=True)
class Interval:
    """Object ``obj`` stands in ``area`` from step ``start`` (−1: initially) until ``end``."""

    obj: str
    area: Area
    start: int
    end: int | None  # step index of the goal that moves it away; None: never
    label: str  # "objects[i]" or "steps[k]" for messages


def occupancy_intervals(
    objects: dict[str, Point],
    object_labels: dict[str, str],
    steps: list[tuple[str, Point]],
    radius: float,
) -> list[Interval]:
    """Every (object, place, time span) of the demonstration."""
    intervals = []
    for obj, p in objects.items():
        own = [k for k, (o, _) in enumerate(steps) if o == obj]
        intervals.append(
            Interval(
                obj, Area(f"P_{obj}", p, radius), -1, own[0] if own else None, object_labels[obj]
            )
        )
        for i, k in enumerate(own):
            end = own[i + 1] if i + 1 < len(own) else None
            intervals.append(
                Interval(obj, Area(f"L{k}", steps[k][1], radius), k, end, f"steps[{k}]")
            )
    return intervals


def derive_constraints(
    objects: dict[str, Point],
    object_labels: dict[str, str],
    steps: list[tuple[str, Point]],
    radius: float,
    explicit: list[tuple[str, str]],
    file: str,
) -> tuple[frozenset[tuple[str, str]], dict[tuple[str, str], str]]:
    """C = intent ∪ physical ∪ explicit, with a reason per constraint; refuses bad demos."""
    reasons: dict[tuple[str, str], str] = {}

    last: dict[str, int] = {}
    for k, (obj, _) in enumerate(steps):
        if obj in last:
            reasons[(f"G{last[obj]}", f"G{k}")] = f"intent: successive goals of {obj}"
        last[obj] = k

    intervals = occupancy_intervals(objects, object_labels, steps, radius)
    for i, a in enumerate(intervals):
        for b in intervals[i + 1 :]:
            if a.obj == b.obj or not a.area.overlaps(b.area):
                continue
            first, second = (a, b) if a.start <= b.start else (b, a)
            if first.start == -1 and second.start == -1:
                raise InputError(
                    f"objects {first.obj} and {second.obj} overlap at their initial places",
                    file=file,
                    field=f"{first.label} / {second.label}",
                )
            if first.end is None:
                where = "initial place" if first.start == -1 else f"goal G{first.start}"
                raise InputError(
                    f"{second.label} moves {second.obj} into the area of {first.obj}'s {where} "
                    f"({first.label}), which {first.obj} never leaves: that area is occupied "
                    "forever",
                    file=file,
                    field=second.label,
                )
            if first.end > second.start:
                raise InputError(
                    f"{second.label} puts {second.obj} in an area that {first.obj} still "
                    f"occupies ({first.label} until steps[{first.end}]): overlapping goal areas "
                    "of different objects at the same stage",
                    file=file,
                    field=second.label,
                )
            pair = (f"G{first.end}", f"G{second.start}")
            reasons.setdefault(
                pair,
                f"physical: {first.obj} must leave the area ({first.label}) before "
                f"{second.obj} is placed there ({second.label})",
            )

    ids = {f"G{k}" for k in range(len(steps))}
    for i, (gi, gj) in enumerate(explicit):
        for g in (gi, gj):
            if g not in ids:
                raise InputError(f"unknown goal {g!r}", file=file, field=f"constraints[{i}]")
        if gi == gj:
            raise InputError(f"{gi} <= {gi} is not an order", file=file, field=f"constraints[{i}]")
        reasons.setdefault((gi, gj), "specified by the person")

    graph = nx.DiGraph(list(reasons))
    try:
        cycle = nx.find_cycle(graph)
    except nx.NetworkXNoCycle:
        cycle = None
    if cycle:
        goals = [u for u, _ in cycle]
        steps_named = ", ".join(f"steps[{g[1:]}]" for g in goals)
        chain = " <= ".join([*goals, goals[0]])
        raise InputError(
            f"the ordering constraints are cyclic ({chain}); steps involved: {steps_named}",
            file=file,
            field="constraints",
        )
    return frozenset(reasons), reasons
