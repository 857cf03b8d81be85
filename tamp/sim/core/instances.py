"""Instances from a per-pixel class map and depth: masks, 3-D centroids and point clouds.

The detector's network (`tamp.sim.core.segnet`) says what class each pixel shows; a
consumer needs objects: LOTS counts instances per class (Zhou et al., IEEE T-ASE 2023,
§III-B), grasping needs one object's mask, tracking needs positions. `extract` makes them:

1. the pixels whose most probable class is an object class (any of them: a class that
   flickers inside one object must not split it),
2. their connected components (8-neighbourhood), split where depth jumps by more than
   ``jump`` between neighbouring pixels (two touching objects at different heights, or one
   in front of another); fragments smaller than ``min_pixels`` (a box's steep side seen
   edge-on is one such strip) and the jump pixels themselves go back to the nearest large
   part,
3. a part split again by class where two classes each hold at least ``share`` of it (two
   touching objects of different classes at one height),
4. kept when at least ``min_pixels`` large; its class is the object class of highest mean
   probability over the mask, that mean is the score, and below ``unknown_below`` the part
   is reported as ``unknown`` (a shape the network is unsure of is not given a task class),
5. back-projected through the depth, the intrinsics and the camera pose (the arm's own
   kinematics, never the plant's object poses) into a world-frame point cloud; the centroid
   is the per-axis median of the points (robust to the stray pixel at an edge).

Touching objects of one class at the same height and depth stay one instance: no depth jump
separates them (measured by the detector benchmark).

`proposals` makes instance candidates from geometry alone, the classic tabletop pipeline
(support plane, points above it, clusters; e.g. Rusu et al., "Towards 3D Point Cloud Based
Object Maps for Household Environments", RAS 56(11), 2008, §5): every pixel is
back-projected through the intrinsics and the camera pose (`world_heights`), the support
plane is the lowest height band that holds a good share of the view (`support_plane`: the
table at z = 0, a mat 1 mm up, whatever the view shows), pixels more than ``above`` over it
are object pixels, and their components are split at depth jumps (`split_at_jumps`, as
above). The detector classifies each proposal (`tamp.sim.core.cropnet`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from tamp.grasp.pinhole import pixel_to_camera

#: depth difference between neighbouring pixels that separates two instances (m); 1 cm split
#: more objects into fragments than it separated touching ones (the shipped weights on 240
#: held-out views: every count right in 13.8 % of the views at 1 cm, 15.0 % at 2 cm)
DEPTH_JUMP = 0.02
#: the finer split of a proposal the classifier calls ``several`` (touching objects): an
#: 8 mm step between neighbouring pixels (at 2 cm, 11 % of the held-out objects stay merged;
#: on training scenes held back from the classifier's fit, 5 mm split more single objects
#: into false positives and 12 mm left more touching ones merged)
FINE_JUMP = 0.008
#: fewest pixels of an instance at the network's resolution (160 x 90; 60 at 320 x 180)
MIN_PIXELS = 15
#: a component whose mean class probability is below this is reported as ``unknown``
UNKNOWN_BELOW = 0.5
#: a region is split by class where two classes each hold at least this share of it
CLASS_SHARE = 0.3
UNKNOWN = "unknown"
#: a pixel this far above the support plane is an object pixel (m): the rendered table's
#: heights scatter +-1 mm and a mat lies 1 mm proud of it; the thinnest catalogue object (the
#: wrench) stands 12 mm high
ABOVE_PLANE = 0.004
#: the support plane is the lowest height band (`PLANE_BIN` wide) holding this share of the
#: view's pixels with a depth return
PLANE_SHARE = 0.05
PLANE_BIN = 0.002
#: the gripper's region: a part whose median depth is nearer the camera than this is the
#: object held between the fingers (measured: at most 9 cm; the top of a bottle under the
#: camera, 12 cm above the tallest object, is 11 cm or more away), not an object on the table
IN_HAND_DEPTH = 0.10
#: a stack's part's top (a horizontal face) holds at least this share of the proposal's
#: pixels in two adjacent height bands (a tower's bottom seen round the body on it: 17 %
#: at 0.47 m straight above; 6 % with the body turned on it near the image's edge)
LEVEL_SHARE = 0.05
#: a stack is cut this far above the top of a lower part's level (the upper edge of its
#: two height bands, m, which already hold the face's +-1 mm scatter), far below the next
#: part's top (the shortest tower part is 4 cm)
LEVEL_MARGIN = 0.002


@dataclass(frozen=True, eq=False)
class ObjectDetection:
    """One detected object in one view: class (a catalogue class, ``unknown`` or ``hand``),
    score (mean class probability over the mask), mask (H x W bool, at the image's
    resolution), pixel centroid (u, v) and median depth, and its 3-D centroid and points
    (3 x N) in the world frame."""

    cls: str
    score: float
    mask: np.ndarray
    centroid: tuple[float, float, float]
    points: np.ndarray
    u: float = 0.0
    v: float = 0.0
    depth: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def pixels(self) -> int:
        return int(self.mask.sum())


def as_matrix(X_WC) -> np.ndarray:
    """A 4 x 4 pose from a numpy matrix or a Drake ``RigidTransform``."""
    return np.asarray(X_WC.GetAsMatrix4() if hasattr(X_WC, "GetAsMatrix4") else X_WC, float)


def backproject_mask(
    mask: np.ndarray, depth: np.ndarray, intrinsics: Sequence[float], X_WC
) -> np.ndarray:
    """World points (3 x N) of the mask's pixels with a depth return."""
    vs, us = np.nonzero(mask & (depth > 0) & np.isfinite(depth))
    p_C = pixel_to_camera(
        us.astype(float), vs.astype(float), depth[vs, us].astype(float), intrinsics
    )
    X = as_matrix(X_WC)
    return X[:3, :3] @ p_C.reshape(3, -1) + X[:3, 3:4]


def depth_jumps(depth: np.ndarray, jump: float = DEPTH_JUMP) -> np.ndarray:
    """Pixels with a 4-neighbour whose depth differs by more than ``jump`` (either side)."""
    d = np.where(np.isfinite(depth), depth, 0.0)
    out = np.zeros(d.shape, bool)
    dy = np.abs(np.diff(d, axis=0)) > jump
    dx = np.abs(np.diff(d, axis=1)) > jump
    out[:-1] |= dy
    out[1:] |= dy
    out[:, :-1] |= dx
    out[:, 1:] |= dx
    return out


_EIGHT = np.ones((3, 3), bool)


def split_at_jumps(
    mask: np.ndarray,
    depth: np.ndarray,
    *,
    jump: float = DEPTH_JUMP,
    min_pixels: int = MIN_PIXELS,
    edges: np.ndarray | None = None,
) -> list[np.ndarray]:
    """The instances of one class's mask (module docstring, steps 1-2 and the size rule);
    ``edges``: the view's `depth_jumps`, when already computed."""
    labels, n = ndimage.label(mask, structure=_EIGHT)
    out = []
    edges = depth_jumps(depth, jump) if edges is None else edges
    for k in range(1, n + 1):
        comp = labels == k
        if comp.sum() < min_pixels:
            continue
        parts, m = ndimage.label(comp & ~edges, structure=_EIGHT)
        if m <= 1:
            out.append(comp)
            continue
        sizes = ndimage.sum_labels(np.ones_like(parts), parts, index=np.arange(1, m + 1))
        big = [i + 1 for i, s in enumerate(sizes) if s >= min_pixels]
        if len(big) <= 1:
            out.append(comp)
            continue
        seeds = np.isin(parts, big)
        # every pixel of the component goes to the nearest pixel of a large part
        _, (iy, ix) = ndimage.distance_transform_edt(~seeds, return_indices=True)
        owner = parts[iy, ix]
        for b in big:
            out.append(comp & (owner == b))
    return out


def split_at_levels(
    mask: np.ndarray,
    heights: np.ndarray,
    *,
    min_pixels: int = MIN_PIXELS,
    share: float = LEVEL_SHARE,
    bin_width: float = PLANE_BIN,
    margin: float = LEVEL_MARGIN,
) -> list[np.ndarray]:
    """A stack's parts: each part's top is a horizontal face, a *level* of the proposal's
    heights (two adjacent `bin_width` bands holding at least ``share`` of its pixels and
    ``min_pixels``: a face's heights scatter over a band's edge; overlapping windows are one
    level); side faces spread over many bands and make none. Cut ``margin`` above every
    level but the highest: the pixels up to a cut belong to the part whose top is that level
    (a tower's bottom seen round the body on it), those above to the parts above. One level
    (or a part smaller than ``min_pixels``): ``[mask]``."""
    z = heights[mask]
    z = z[np.isfinite(z)]
    if z.size < 2 * min_pixels:
        return [mask]
    edges = np.arange(float(z.min()), float(z.max()) + 3 * bin_width, bin_width)
    counts, edges = np.histogram(z, bins=edges)
    window = counts[:-1] + counts[1:]  # window i: bands i and i + 1
    dense = window >= max(min_pixels, share * z.size)
    levels, run = [], []
    for i, d in enumerate(dense):
        if d:
            run.append(i)
        if run and (not d or i == len(dense) - 1):
            top = float(edges[run[-1] + 2])  # the run's upper edge: the face and its scatter
            levels.append(top)
            run = []
    if len(levels) <= 1:
        return [mask]
    parts = cut_at_heights(mask, heights, [lv + margin for lv in levels[:-1]])
    parts[-1] |= mask & ~np.isfinite(heights)  # no depth return: the top part's
    if any(int(p.sum()) < min_pixels for p in parts):
        return [mask]
    return parts


def cut_at_heights(
    mask: np.ndarray, heights: np.ndarray, cuts: Sequence[float]
) -> list[np.ndarray]:
    """The pixels of ``mask`` between consecutive ``cuts`` (ascending world heights, m), one
    mask per slice from below the first cut to above the last: a stack's parts, each up to
    the cut above its top (pixels without a height are in none)."""
    edges = [-np.inf, *cuts, np.inf]
    with np.errstate(invalid="ignore"):
        return [
            mask & (heights > lo) & (heights <= hi)
            for lo, hi in zip(edges, edges[1:], strict=False)
        ]


def split_several(
    mask: np.ndarray,
    depth: np.ndarray,
    heights: np.ndarray,
    *,
    jump: float = FINE_JUMP,
    min_pixels: int = MIN_PIXELS,
) -> tuple[list[np.ndarray], bool]:
    """(the parts of a proposal the classifier calls ``several`` (touching objects), whether
    they are its levels): split at ``jump`` steps of depth (side by side at different
    heights), else at its levels (`split_at_levels`, bottom up: one stacked on another,
    whose sides run on without a step). One part: the proposal itself. The detector and the
    classifier's training split alike (the detector also tries the levels of a proposal it
    calls ``unknown``)."""
    parts = split_at_jumps(mask, depth, jump=jump, min_pixels=min_pixels)
    if len(parts) > 1:
        return parts, False
    levels = split_at_levels(mask, heights, min_pixels=min_pixels)
    return levels, len(levels) > 1


def _by_class(
    comp: np.ndarray, best: np.ndarray, objects: Sequence[int], min_pixels: int, share: float
) -> list[np.ndarray]:
    """One object's region split by class where two or more classes each hold at least
    ``share`` of it (and ``min_pixels``): two touching objects of different classes at one
    height. Otherwise the region itself (a class flickering inside one object stays one)."""
    area = int(comp.sum())
    counts = {c: int((comp & (best == c)).sum()) for c in objects}
    big = [c for c, n in counts.items() if n >= max(min_pixels, share * area)]
    if len(big) <= 1:
        return [comp]
    seeds = np.zeros(comp.shape, int)
    for k, c in enumerate(big, start=1):
        seeds[comp & (best == c)] = k
    _, (iy, ix) = ndimage.distance_transform_edt(seeds == 0, return_indices=True)
    owner = seeds[iy, ix]
    return [comp & (owner == k) for k in range(1, len(big) + 1)]


def extract(
    probs: np.ndarray,
    depth: np.ndarray,
    names: Sequence[str],
    object_classes: Sequence[int],
    intrinsics: Sequence[float],
    X_WC,
    *,
    jump: float = DEPTH_JUMP,
    min_pixels: int = MIN_PIXELS,
    unknown_below: float = UNKNOWN_BELOW,
    share: float = CLASS_SHARE,
) -> list[ObjectDetection]:
    """The detections of one view (module docstring): ``probs`` (C x H x W) class
    probabilities, ``depth`` (H x W, metres, 0 = no return), ``names`` of the C classes,
    ``object_classes`` the indices that are objects (not background or table)."""
    depth = np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)
    best = probs.argmax(axis=0)
    edges = depth_jumps(depth, jump)
    objects = list(object_classes)
    foreground = np.isin(best, objects)
    out = []
    for region in split_at_jumps(foreground, depth, min_pixels=min_pixels, edges=edges):
        for inst in _by_class(region, best, objects, min_pixels, share):
            mean = probs[objects][:, inst].mean(axis=1)
            c = objects[int(mean.argmax())]
            score = float(mean.max())
            cls = names[c] if score >= unknown_below else UNKNOWN
            where = located(inst, depth, intrinsics, X_WC)
            if where is not None:
                out.append(ObjectDetection(cls, score, inst, **where))
    return out


def located(mask: np.ndarray, depth: np.ndarray, intrinsics, X_WC) -> dict | None:
    """Where a mask's object is: its world-frame points (``depth``: metres, 0 = no return),
    their median as the centroid, the mask's mean pixel and its median valid depth, as
    `ObjectDetection` fields; None when no pixel of the mask has a depth return. Without
    ``intrinsics`` or ``X_WC`` the view cannot be placed in the world: no points and a NaN
    centroid, the pixel and depth as ever."""
    valid = depth[mask]
    valid = valid[np.isfinite(valid) & (valid > 0)]
    if valid.size == 0:
        return None
    if intrinsics is None or X_WC is None:
        points, centroid = np.zeros((3, 0)), (float("nan"),) * 3
    else:
        points = backproject_mask(mask, depth, intrinsics, X_WC)
        centroid = tuple(float(x) for x in np.median(points, axis=1))
    vs, us = np.nonzero(mask)
    return {
        "centroid": centroid,
        "points": points,
        "u": float(us.mean()),
        "v": float(vs.mean()),
        "depth": float(np.median(valid)),
    }


def world_heights(depth: np.ndarray, intrinsics: Sequence[float], X_WC) -> np.ndarray:
    """World z (m) of every pixel (H x W; NaN where there is no depth return): the pixel
    back-projected through the intrinsics and the camera pose."""
    h, w = depth.shape
    d = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float64)
    fx, fy, cx, cy = intrinsics
    X = as_matrix(X_WC)
    # z_W = R[2] . p_C + t_z with p_C = ((u - cx) d / fx, (v - cy) d / fy, d)
    ru = X[2, 0] * (np.arange(w) - cx) / fx
    rv = X[2, 1] * (np.arange(h) - cy) / fy
    return d * (ru[None, :] + rv[:, None] + X[2, 2]) + X[2, 3]


def support_plane(
    heights: np.ndarray, *, share: float = PLANE_SHARE, bin_width: float = PLANE_BIN
) -> float | None:
    """The height (m) of the surface the objects stand on, from one view: the lowest
    ``bin_width`` band of the pixels' world heights holding at least ``share`` of them (the
    most populated band when none does), refined as the median height within 1.5 bins of it;
    None without a single depth return. The plane is horizontal (world z up, the camera pose
    from the arm's kinematics); only its height is estimated, so a mat or a tray floor that
    fills the view is found as readily as the table."""
    z = heights[np.isfinite(heights)]
    if z.size == 0:
        return None
    lo = float(z.min())
    edges = lo + bin_width * np.arange(int(min(z.max() - lo, 1.0) / bin_width) + 2)
    counts, _ = np.histogram(z, edges)
    enough = np.flatnonzero(counts >= max(10, share * z.size))
    b = int(enough[0]) if enough.size else int(counts.argmax())
    centre = edges[b] + 0.5 * bin_width
    near = z[np.abs(z - centre) <= 1.5 * bin_width]
    return float(np.median(near))


@dataclass(frozen=True, eq=False)
class Proposals:
    """The instance candidates of one view (`proposals`): their masks, the support plane's
    height and every pixel's height above it (NaN without a depth return)."""

    masks: list[np.ndarray]
    plane: float | None
    heights: np.ndarray


def proposals(
    depth: np.ndarray,
    intrinsics: Sequence[float],
    X_WC,
    *,
    above: float = ABOVE_PLANE,
    jump: float = DEPTH_JUMP,
    min_pixels: int = MIN_PIXELS,
    plane: float | None = None,
    exclude: np.ndarray | None = None,
) -> Proposals:
    """Instance candidates from geometry (module docstring): the components of the pixels
    more than ``above`` over the support plane, split where depth jumps by more than
    ``jump``, each at least ``min_pixels`` large. ``plane``: the support's known height (a
    workcell's tray floor), else estimated from the view (`support_plane`); ``exclude``:
    pixels of known fixtures (a tray's walls), never part of an object."""
    depth = np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)
    z = world_heights(depth, intrinsics, X_WC)
    if plane is None:
        plane = support_plane(z)
    if plane is None:
        return Proposals([], None, z)
    rel = z - plane
    with np.errstate(invalid="ignore"):
        fg = rel > above
    if exclude is not None:
        fg &= ~exclude
    return Proposals(split_at_jumps(fg, depth, jump=jump, min_pixels=min_pixels), plane, rel)
