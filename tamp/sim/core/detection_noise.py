"""A seeded noisy detector: the errors a real detector makes, applied to a view's detections.

Perception errors are their own axis of robustness (Zhou et al., IEEE T-ASE 2023, §V report
their detector's misses under occlusion and at small size); `perturb` turns a view's
`ObjectDetection` list into what a worse detector would have reported, drawn from the run's
seed and the frame alone (`tamp.perturbation.stream`), so a seeded run sees the same errors
every time:

- **misses by area**: a detection of ``a`` pixels is dropped with probability
  ``miss_small * (1 - a / small_area)`` below ``small_area`` pixels;
- **misses by occlusion**: dropped with probability ``miss_occluded * occlusion``, where
  occlusion is the share of the mask's outline that borders the image edge or something
  nearer (`occlusion`; without a depth image the image edge alone);
- **class swaps**: with probability ``swap`` the class becomes another task class;
- **mask jitter**: the mask grows or shrinks by one pixel (binary dilation or erosion) with
  probability ``jitter``, and its pixel centroid, depth, points and centroid follow;
- **fresh identities**: with probability ``fresh`` the centroid and points (and the pixel
  centroid and depth, where the view is placed) jump ``fresh_jump`` metres in a random
  horizontal direction, beyond the tracker's first gate
  (`tamp.sim.core.tracks.GATE`); its second round (``REGATE``, 15 cm) matches most of them
  back to their track when no other detection claims it, so fresh track ids under this
  noise come mostly from false positives and from jumps another detection takes over;
- **false positives**: ``false_positives`` extra detections per view on average (Poisson),
  each a disc of 6-15 pixels' radius of a random task class at a random pixel, with the
  depth there.

Two named levels, `LEVELS`: ``low`` (a good detector on a bad day) and ``high`` (one that
fails often). Wiring it as a ``perturbation:`` kind of a scenario file belongs with the
workcells' use of the detector (their perception systems call `perturb`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from tamp.grasp.pinhole import camera_to_pixel, pixel_to_camera
from tamp.perturbation import stream
from tamp.sim.core.instances import ObjectDetection, as_matrix, backproject_mask, located

NOT_TASK = ("unknown", "hand")


@dataclass(frozen=True)
class NoiseLevel:
    """Probabilities and sizes of each error (module docstring)."""

    miss_small: float
    small_area: int
    miss_occluded: float
    swap: float
    jitter: float
    fresh: float
    fresh_jump: float
    false_positives: float


LEVELS: dict[str, NoiseLevel] = {
    "low": NoiseLevel(0.3, 60, 0.2, 0.03, 0.3, 0.03, 0.08, 0.1),
    "high": NoiseLevel(0.7, 120, 0.6, 0.12, 0.7, 0.1, 0.08, 0.5),
}


def occlusion(mask: np.ndarray, depth: np.ndarray | None, tolerance: float = 0.01) -> float:
    """Share of the mask's outline (the pixels just outside it) on the image edge or showing
    something more than ``tolerance`` nearer than the object's median depth."""
    h, w = mask.shape
    ring = ndimage.binary_dilation(mask) & ~mask
    edge = mask.copy()
    edge[1:-1, 1:-1] = False
    total = int(ring.sum()) + int(edge.sum())
    if total == 0:
        return 0.0
    hidden = int(edge.sum())
    if depth is not None:
        d = depth[mask]
        d = d[d > 0]
        if d.size:
            near = (depth > 0) & (depth < float(np.median(d)) - tolerance)
            hidden += int((ring & near).sum())
    return min(1.0, hidden / total)


def _moved(pixel: tuple[float, float, float], shift: np.ndarray, intrinsics, X_WC) -> tuple:
    """(u, v, depth) of the world point seen at ``pixel`` moved by ``shift`` (m)."""
    X = as_matrix(X_WC)
    p_W = X[:3, :3] @ pixel_to_camera(*pixel, intrinsics) + X[:3, 3] + shift
    p_C = X[:3, :3].T @ (p_W - X[:3, 3])
    if p_C[2] <= 0:
        return pixel
    u, v = camera_to_pixel(p_C, intrinsics)
    return float(u), float(v), float(p_C[2])


def perturb(
    detections: Sequence[ObjectDetection],
    *,
    seed: int,
    frame: int,
    level: str | NoiseLevel,
    classes: Sequence[str],
    depth: np.ndarray | None = None,
    intrinsics: Sequence[float] | None = None,
    X_WC=None,
) -> list[ObjectDetection]:
    """What a noisier detector reports for this view (module docstring). ``classes``: the
    task classes a swap or a false positive may take; ``depth``, ``intrinsics`` and
    ``X_WC`` let jittered masks and false positives have points (without them, jittered
    masks keep their points and no false positive is made)."""
    lv = LEVELS[level] if isinstance(level, str) else level
    rng = stream(seed, "detector", "", frame)
    task = [c for c in classes if c not in NOT_TASK]
    out: list[ObjectDetection] = []
    for d in detections:
        u = rng.random(6)  # always six draws per detection: the stream stays aligned
        area = d.pixels
        if area < lv.small_area and u[0] < lv.miss_small * (1 - area / lv.small_area):
            continue
        if u[1] < lv.miss_occluded * occlusion(d.mask, depth):
            continue
        cls = d.cls
        if u[2] < lv.swap and cls not in NOT_TASK and len(task) > 1:
            others = [c for c in task if c != cls]
            cls = others[int(u[3] * len(others)) % len(others)]
        mask, points, pixel = d.mask, d.points, (d.u, d.v, d.depth)
        if u[4] < lv.jitter:
            grow = rng.random() < 0.5
            new = ndimage.binary_dilation(mask) if grow else ndimage.binary_erosion(mask)
            if new.sum() > 0:
                mask = new
                where = None if depth is None else located(mask, depth, intrinsics, X_WC)
                if where is not None:  # the mask's pixel, depth (and points) follow it
                    pixel = (where["u"], where["v"], where["depth"])
                    if where["points"].shape[1]:
                        points = where["points"]
        centroid = np.median(points, axis=1) if points.shape[1] else np.array(d.centroid)
        if u[5] < lv.fresh:
            a = rng.uniform(-math.pi, math.pi)
            shift = lv.fresh_jump * np.array([math.cos(a), math.sin(a), 0.0])
            points = points + shift[:, None]
            centroid = centroid + shift
            if intrinsics is not None and X_WC is not None:  # the pixel moves with it
                pixel = _moved(pixel, shift, intrinsics, X_WC)
        out.append(
            dataclasses.replace(
                d,
                cls=cls,
                mask=mask,
                points=points,
                centroid=tuple(float(x) for x in centroid),
                u=pixel[0],
                v=pixel[1],
                depth=pixel[2],
            )
        )
    if depth is not None and intrinsics is not None and X_WC is not None and task:
        h, w = depth.shape
        for _ in range(int(rng.poisson(lv.false_positives))):
            r = rng.uniform(6, 15) * w / 320
            cu, cv = rng.uniform(0, w), rng.uniform(0, h)
            vv, uu = np.mgrid[0:h, 0:w]
            mask = ((uu - cu) ** 2 + (vv - cv) ** 2 <= r * r) & (depth > 0)
            cls = task[int(rng.integers(len(task)))]
            if mask.sum() == 0:
                continue
            points = backproject_mask(mask, depth, intrinsics, X_WC)
            out.append(
                ObjectDetection(
                    cls,
                    float(rng.uniform(0.5, 0.9)),
                    mask,
                    tuple(float(x) for x in np.median(points, axis=1)),
                    points,
                    float(cu),
                    float(cv),
                    float(np.median(depth[mask])),
                )
            )
    return out
