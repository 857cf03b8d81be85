"""The tower of Zhou et al. (IEEE T-ASE 2023) §V-B2, Fig. 10, as a stack: "the blocks on W^A
are required to be moved to W^B and stacked in order to build a tower" (bottom, body, peak).

A workcell scenario declares the order, base first (``stack: [bottom, body, peak]``,
`tamp.sim.lots.scenario.CellScenario.stack`); the stack stands in W^B, where a LOTS task
delivers. Three users, one geometry:

- the robot's ``Place(B)`` (`tamp.sim.lots.skills`) puts an object of a stack class on the
  object of the class below it, where perception saw that one (`support`: the top of its
  instances as detected or remembered, a point back-projected through its median depth), never
  where the plant has it;
- the scripted person (`tamp.sim.lots.person`), who sees the world, puts an object of a stack
  class on the top of the stack and takes only objects that nothing rests on (`resting_on`);
- the run's judge (`judge_stack`) reads the plant: how many levels stand on each other in
  W^B, base on the floor, each level resting on the one below.

No Drake here: poses are 4 x 4 homogeneous matrices (object frame in the world).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tamp.sim.lots.catalogue import Footprint

#: the workspace the stack stands in (a LOTS task delivers to W^B)
STACK_SIDE = "B"
#: a level rests on the one below when its origin (the middle of its underside) lies this
#: close (m) to the top of the one below; hydroelastic contact sinks a millimetre or two, and a
#: block dropped from the release gap may bounce: 1 cm tells it from one lying beside (its
#: origin on the floor, a block's height lower)
SEAT_TOLERANCE = 0.01
#: and its axis stays within this angle (rad) of the one below's: a level that toppled onto its
#: side is no level
TILT_TOLERANCE = math.radians(10.0)


def below(order: Sequence[str], cls: str) -> str | None:
    """The class an object of ``cls`` stands on in stack ``order`` (base first); None for the
    base and for a class that is not in the stack (both go on the floor)."""
    if cls not in order:
        return None
    k = list(order).index(cls)
    return order[k - 1] if k > 0 else None


def support(
    cls: str, seen: Iterable[tuple[str, Sequence[float]]]
) -> tuple[float, float, float] | None:
    """Where to stack onto an object of class ``cls``, from what the robot saw in W^B:
    ``seen`` holds (class, world point) pairs, each point about the middle of an instance's
    top (a detection back-projected through its median depth, or a remembered instance
    hidden now). The highest instance of ``cls`` (the stack's top when several lie there);
    None when none was seen."""
    points = [tuple(float(v) for v in p) for c, p in seen if c == cls]
    if not points:
        return None
    return max(points, key=lambda p: p[2])


def _up(X: np.ndarray) -> np.ndarray:
    return np.asarray(X, float)[:3, 2]


def resting_on(
    X_below: np.ndarray, below_fp: Footprint, X_above: np.ndarray, *, tol: float = SEAT_TOLERANCE
) -> bool:
    """Whether the object at ``X_above`` rests on the one at ``X_below`` (footprint
    ``below_fp``, whose ``top`` is its height): its origin (under its centre) lies within the
    lower one's footprint, within ``tol`` of its top, and the two are within
    `TILT_TOLERANCE` of parallel."""
    X_below, X_above = np.asarray(X_below, float), np.asarray(X_above, float)
    p = X_below[:3, :3].T @ (X_above[:3, 3] - X_below[:3, 3])  # in the lower one's frame
    inside = below_fp.xmin <= p[0] <= below_fp.xmax and below_fp.ymin <= p[1] <= below_fp.ymax
    cos = float(np.clip(_up(X_below) @ _up(X_above), -1.0, 1.0))
    return inside and abs(p[2] - below_fp.top) <= tol and math.acos(cos) <= TILT_TOLERANCE


def covered(
    uid: str,
    objects: Mapping[str, tuple[str, np.ndarray]],
    footprints: Mapping[str, Footprint],
    *,
    tol: float = SEAT_TOLERANCE,
) -> bool:
    """Whether another of ``objects`` (id -> (class, pose)) rests on ``uid`` (``footprints``
    by class)."""
    cls, X_u = objects[uid]
    return any(
        resting_on(X_u, footprints[cls], X, tol=tol)
        for other, (_, X) in objects.items()
        if other != uid
    )


def free_top(
    cls: str,
    objects: Mapping[str, tuple[str, np.ndarray]],
    footprints: Mapping[str, Footprint],
) -> tuple[float, float, float] | None:
    """The middle of the top (x, y, z; world) of the first object of class ``cls`` among
    ``objects`` (id -> (class, pose), in id order) that nothing rests on; None when there is
    none. What a person who sees the world stacks onto."""
    f = footprints.get(cls)
    for uid, (c, X) in sorted(objects.items()):
        if c == cls and not covered(uid, objects, footprints):
            p = np.asarray(X, float) @ [(f.xmin + f.xmax) / 2, (f.ymin + f.ymax) / 2, f.top, 1.0]
            return float(p[0]), float(p[1]), float(p[2])
    return None


@dataclass(frozen=True)
class StackCheck:
    """How high the declared stack stands on the plant: ``levels`` are the object ids from the
    base up (the tallest such column in W^B), ``height`` their number; ``complete`` when every
    class of ``order`` stands in it."""

    order: tuple[str, ...]
    levels: tuple[str, ...] = ()
    heights: tuple[float, ...] = ()  # each level's origin above the table (m)
    tolerance: float = SEAT_TOLERANCE
    #: how many levels the task needs (`required_height`; None: all of ``order``)
    required: int | None = None

    @property
    def height(self) -> int:
        return len(self.levels)

    @property
    def needed(self) -> int:
        return len(self.order) if self.required is None else self.required

    @property
    def complete(self) -> bool:
        """The stack stands as high as the task needs."""
        return self.height >= self.needed

    def describe(self) -> str:
        if not self.levels:
            return f"no {self.order[0]} on the floor of W^{STACK_SIDE}: the stack is 0 high"
        shown = " on ".join(reversed(self.levels))
        return f"stack {self.height} of {self.needed} high in W^{STACK_SIDE}: {shown}" + (
            "" if self.complete else f" (no {self.order[self.height]} resting on it)"
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "order": list(self.order),
            "levels": list(self.levels),
            "heights": [round(h, 4) for h in self.heights],
            "height": self.height,
            "required": self.needed,
            "complete": self.complete,
            "tolerance": self.tolerance,
        }


def required_height(order: Sequence[str], planned: Mapping[str, int]) -> int:
    """How many levels of stack ``order`` (base first) the task's planned W^B needs: the
    longest prefix of ``order`` whose classes it holds (a task that delivers only the base
    needs a stack one high; Fig. 10's tower needs all three)."""
    n = 0
    for cls in order:
        if planned.get(cls, 0) < 1:
            break
        n += 1
    return n


def judge_stack(
    order: Sequence[str],
    objects: Mapping[str, tuple[str, np.ndarray]],
    footprints: Mapping[str, Footprint],
    in_workspace,
    floor: float = 0.0,
    *,
    tol: float = SEAT_TOLERANCE,
    required: int | None = None,
) -> StackCheck:
    """The tallest column of the stack ``order`` (base first) on the plant: ``objects`` maps
    each id to (class, pose 4 x 4), ``footprints`` each class to its footprint,
    ``in_workspace(x, y)`` tells whether a point lies in the stack's workspace, ``floor`` is
    the height of its floor (a tray's). The base lies in the workspace with its origin within
    ``tol`` of the floor, upright; each next level of the next class `resting_on` the one
    below. ``required``: the levels the task needs (`required_height`; None: all)."""
    order = tuple(order)
    best: list[str] = []

    def upright(X: np.ndarray) -> bool:
        return math.acos(float(np.clip(_up(X)[2], -1.0, 1.0))) <= TILT_TOLERANCE

    def grow(column: list[str]) -> None:
        nonlocal best
        if len(column) > len(best):
            best = list(column)
        if len(column) == len(order):
            return
        top = column[-1]
        cls_top, X_top = objects[top]
        for uid, (cls, X) in sorted(objects.items()):
            if cls == order[len(column)] and uid not in column:
                if resting_on(X_top, footprints[cls_top], X, tol=tol):
                    grow([*column, uid])

    for uid, (cls, X) in sorted(objects.items()):
        x, y, z = (float(v) for v in np.asarray(X)[:3, 3])
        if cls == order[0] and in_workspace(x, y) and abs(z - floor) <= tol and upright(X):
            grow([uid])
    heights = tuple(float(np.asarray(objects[u][1])[2, 3]) for u in best)
    return StackCheck(order, tuple(best), heights, tol, required)
