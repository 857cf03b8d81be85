"""Reading a declared stack by its heights: what a learned detector names in a tower.

Zhou et al. (IEEE T-ASE 2023) §V-B2, Fig. 10 build a tower in W^B: bottom, body, peak, each
on the one below. Seen from the wrist camera, a tower's parts are hard to name one by one:
the lower parts show only thin strips round the part on them, and a crop classifier names
those strips ``unknown``, or names one part's two visible rim strips twice (the learned
tower campaign's failures, docs/campaigns.md). What a robot does know is its parts' models
(the catalogue's SDFs: each class's height) and the order its task stacks them in (the cell
scenario's ``stack``). `read_stack` uses both: the detections standing at one spot of the
stack's workspace (a *column*) whose top lies at the height of the first k parts stacked
(`StackModel.tops`) are those k parts, level by level; each level gets the column's pixels
between its underside and its top (a level the camera cannot see at all, under the one on
it, gets none: perception's memory keeps it, `tamp.sim.core.perception.recall`).

Assumptions, stated where they are used: the stack's parts are centred on each other within
`COLUMN_RADIUS` (the robot places on the part it saw, the person on the stack's top, within
1.5 cm: `tamp.sim.core.segdata.STACK_OFFSET`); anything in the workspace whose top stands at
a stack height and shows two levels is read as a stack (an unknown object of such a shape in
W^B would be counted; a lone object is never renamed); a column holding an object of another
task class (a toy car on the tower) is left as the detector named it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import connected_components

from tamp.sim.core.instances import (
    UNKNOWN,
    ObjectDetection,
    cut_at_heights,
    located,
    world_heights,
)
from tamp.sim.core.messages import Seen

#: detections whose centroids lie this close (m, on the table) stand in one column: a
#: stacked part's centre lies within 1.5 cm of the one below; a lower part's strip seen
#: beside the part on it has its centroid up to a corner's distance (4.2 cm for the 6 cm
#: bottom) off the middle (measured: 3.7 cm). Parts side by side on the table may lie
#: closer (two bodies' long sides touching: 4 cm), but only a column whose top stands at
#: the height of two or more parts stacked is read
COLUMN_RADIUS = 0.045
#: a column's top matches a stack height within this (m): half the smallest part's height
#: less the depth noise and the top's scatter (the parts are 4-5 cm high)
TOP_TOLERANCE = 0.015
#: a column's top is the height below which all but this many of its points lie (a lone
#: noisy point is no top; the peak's apex is a few pixels wide)
TOP_RANK = 5
#: a level's pixels lie up to this far (m) above the stack height of its top (its face's
#: scatter, a part seated a millimetre proud on the one below)
LEVEL_MARGIN = 0.005


@dataclass(frozen=True)
class StackModel:
    """A declared stack: the workspace it stands in (``side``), its classes base first
    (``order``) and each class's height (``heights``, m, from the catalogue's models)."""

    side: str
    order: tuple[str, ...]
    heights: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.order) != len(self.heights) or not self.order:
            raise ValueError("a stack model needs one height per class")

    @property
    def tops(self) -> tuple[float, ...]:
        """The height of the stack's top over its base with 1, 2, ... parts stacked."""
        return tuple(float(x) for x in np.cumsum(self.heights))

    def levels_at(self, top: float, tolerance: float = TOP_TOLERANCE) -> int:
        """How many parts stand in a column whose top is ``top`` over the base (0: its top
        is at no stack height)."""
        for k, t in enumerate(self.tops, start=1):
            if abs(top - t) <= tolerance:
                return k
        return 0


def columns(
    points_xy: Sequence[np.ndarray],
    radius: float = COLUMN_RADIUS,
    tall: Sequence[bool] | None = None,
) -> list[list[int]]:
    """The groups of indices whose (x, y) lie within ``radius`` of another in the group, or
    within twice it when both are ``tall`` (their points rise above the stack's first
    level: each holds part of an upper level, as only a tower's pieces do; a lower part's
    side seen with the lower side of the part on it has its centroid 4.9 cm off the middle,
    measured)."""
    n = len(points_xy)
    if n == 0:
        return []
    xy = np.asarray(points_xy, float).reshape(n, 2)
    apart = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=2)
    near = apart <= radius
    if tall is not None:
        up = np.asarray(tall, bool)
        near |= (apart <= 2 * radius) & up[:, None] & up[None, :]
    k, label = connected_components(near, directed=False)
    return [[i for i in range(n) if label[i] == j] for j in range(k)]


def read_stack(
    found: list[ObjectDetection],
    model: StackModel,
    depth: np.ndarray,
    intrinsics: Sequence[float],
    X_WC,
    *,
    base: float = 0.0,
    inside=None,
    min_pixels: int = 25,
) -> list[ObjectDetection]:
    """A view's detections with every column of the declared stack read level by level
    (module docstring). ``base``: the height the stack stands on; ``inside``: whether a
    world point lies in the stack's workspace (None: everywhere). A column is read when its
    detections are all of the stack's classes or ``unknown``, its top lies at a stack
    height of k >= 2 parts and it shows two levels (pixels of at least two levels, or two
    detections); its detections are then replaced by one per level with ``min_pixels`` in
    view, named by the stack's order. Everything else is returned as it was."""
    cands = [
        i
        for i, d in enumerate(found)
        if (d.cls in model.order or d.cls == UNKNOWN)
        and d.points.shape[1] > 0
        and (inside is None or inside(d.centroid))
    ]
    if not cands:
        return found
    z = None  # the view's heights over the base, computed for the first column read
    replaced: set[int] = set()
    read: list[ObjectDetection] = []
    first = model.tops[0] + TOP_TOLERANCE
    tall = [_top(found[i].points[2] - base) > first for i in cands]
    for group in columns([found[i].centroid[:2] for i in cands], tall=tall):
        members = [found[cands[j]] for j in group]
        heights = np.concatenate([d.points[2] for d in members]) - base
        if heights.size <= TOP_RANK:
            continue
        top = _top(heights)
        k = model.levels_at(top)
        if k < 2:
            continue
        if z is None:
            z = world_heights(depth, intrinsics, X_WC) - base
        union = np.logical_or.reduce([d.mask for d in members])
        bands = cut_at_heights(union, z, [t + LEVEL_MARGIN for t in model.tops[: k - 1]])
        shown = [int(b.sum()) >= min_pixels for b in bands]
        if sum(shown) < 2 and len(members) < 2:
            continue  # one object showing one level: not told from a tall object
        found_at = [
            (cls, band, located(band, depth, intrinsics, X_WC) if ok else None)
            for cls, band, ok in zip(model.order[:k], bands, shown, strict=False)
        ]
        found_at = [(cls, band, where) for cls, band, where in found_at if where is not None]
        if not found_at:
            continue
        # every level stands under the top one's middle (the parts are centred on each
        # other): a lower part's visible strips are off its middle by up to half its width,
        # and its remembered track (seen whole before the next part went on it) is there
        x, y = found_at[-1][2]["centroid"][:2]
        score = max(d.score for d in members)
        for cls, band, where in found_at:
            where["centroid"] = (x, y, where["centroid"][2])
            read.append(ObjectDetection(cls, score, band, **where, extra={"level": cls}))
        replaced |= {cands[j] for j in group}
    if not replaced:
        return found
    return [d for i, d in enumerate(found) if i not in replaced] + read


def _top(heights: np.ndarray) -> float:
    """The height below which all but `TOP_RANK` of ``heights`` lie (-inf when too few)."""
    return float(np.sort(heights)[-TOP_RANK]) if heights.size > TOP_RANK else -np.inf


def remembered_in_columns(
    remembered: Sequence[Seen],
    levels: Sequence[tuple[str, Sequence[float]]],
    radius: float = COLUMN_RADIUS,
) -> frozenset[int]:
    """The tracks of ``remembered`` instances (kept as hidden) that are a level read in this
    view: of its class, in its column (within ``radius`` on the table). A column holds one
    part per level, so a lower part remembered from an earlier view where its strips placed
    it aside is the part read now, not a second one (``levels``: each read level's class
    and world centroid, `read_stack`'s detections marked ``extra["level"]``)."""
    out = set()
    for m in remembered:
        for cls, p in levels:
            if cls == m.cls and np.hypot(m.position[0] - p[0], m.position[1] - p[1]) <= radius:
                out.add(m.track)
                break
    return frozenset(out)
