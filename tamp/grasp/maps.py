"""Ground-truth maps from rectangles, image normalisation, and grasps from output maps.

Targets follow GG-CNN [49] as used by the paper (§IV-B): inside the middle third of each
rectangle (along the opening, full jaw size) Q = 1, the angle maps hold cos 2Φ and sin 2Φ,
and W holds the opening in pixels divided by :data:`WIDTH_SCALE`. (GG-CNN divides by 150,
the top of the paper's W range [0, 150] px; with 128 px images whose openings are 10-60 px
that leaves the width targets near 0.1 and the width loss ten times weaker than the
quality loss, and after a CPU-sized budget every network underestimated widths by half.
Dividing by 40 px puts the width targets in the same range as Q, cos and sin.)
A grasp is read at the peak of Q after Gaussian smoothing (σ = 2 px for Q and the angle) and
its rectangle takes jaw size = opening / 2. The width is the Q-weighted Gaussian mean of W
(σ = 2 px): W is only defined inside grasp regions (0 elsewhere), and a plain blur of W mixed
that 0 into narrow regions (the exact target maps of a 9 px opening read 14 % too narrow).
A trained network's W still reads wide at its own Q peak (about +19 % on the shipped weights:
it is low at a region's edges and overshoots in the middle, where Q peaks), so a weights file
carries a width calibration factor, fitted on its training or validation images
(:func:`tamp.grasp.evaluate.fit_width_calibration`), which :func:`post_process` applies.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from tamp.grasp.depth import INVALID_PEAKS, on_valid_depth
from tamp.grasp.rect import GraspRect

WIDTH_SCALE = 40.0


def draw_targets(rects: Sequence[GraspRect], size: int) -> np.ndarray:
    """(4, size, size) float32: Q, cos 2Φ, sin 2Φ, W / WIDTH_SCALE for ``rects``."""
    out = np.zeros((4, size, size), dtype=np.float32)
    ys, xs = np.mgrid[0:size, 0:size].astype(np.float32)
    for r in rects:
        corners = r.corners()
        x0, y0 = np.floor(corners.min(axis=0)).astype(int)
        x1, y1 = np.ceil(corners.max(axis=0)).astype(int)
        x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1 + 1, size), min(y1 + 1, size)
        if x0 >= x1 or y0 >= y1:
            continue
        px, py = xs[y0:y1, x0:x1] - r.x, ys[y0:y1, x0:x1] - r.y
        d, n = r.direction, r.normal
        along = np.abs(px * d[0] + py * d[1])
        across = np.abs(px * n[0] + py * n[1])
        mask = (along <= max(r.width / 6, 0.5)) & (across <= max(r.height / 2, 0.5))
        region = (slice(y0, y1), slice(x0, x1))
        out[0][region][mask] = 1.0
        out[1][region][mask] = math.cos(2 * r.angle)
        out[2][region][mask] = math.sin(2 * r.angle)
        out[3][region][mask] = r.width / WIDTH_SCALE
    return out


def normalise_depth(depth: np.ndarray) -> np.ndarray:
    """Depth minus its mean, clipped to [-1, 1] (GG-CNN's normalisation)."""
    return np.clip(depth - depth.mean(), -1.0, 1.0).astype(np.float32)


def normalise_rgb(rgb: np.ndarray) -> np.ndarray:
    """(3, h, w) float32 in [-1, 1]-ish: scaled to [0, 1] minus the image mean."""
    x = np.asarray(rgb, dtype=np.float32).transpose(2, 0, 1) / 255.0
    return x - x.mean()


def stack_input(rgb: np.ndarray | None, depth: np.ndarray | None, mode: str) -> np.ndarray:
    """Network input (C, h, w) for mode 'd', 'rgb' or 'rgbd' from raw crops."""
    parts = []
    if mode in ("d", "rgbd"):
        if depth is None:
            raise ValueError(f"input mode {mode!r} needs a depth image")
        parts.append(normalise_depth(depth)[None])
    if mode in ("rgb", "rgbd"):
        if rgb is None:
            raise ValueError(f"input mode {mode!r} needs an RGB image")
        parts.insert(0, normalise_rgb(rgb))
    return np.concatenate(parts, axis=0)


def gaussian_kernel(sigma: float) -> np.ndarray:
    radius = max(1, int(math.ceil(3 * sigma)))
    x = np.arange(-radius, radius + 1, dtype=np.float32)
    k = np.exp(-0.5 * (x / sigma) ** 2)
    return k / k.sum()


def smooth(img: np.ndarray, sigma: float) -> np.ndarray:
    """Separable Gaussian blur with edge padding (no SciPy needed)."""
    k = gaussian_kernel(sigma)
    r = len(k) // 2
    pad = np.pad(img, r, mode="edge")
    tmp = sum(k[i] * pad[:, i : i + img.shape[1]] for i in range(len(k)))
    return sum(k[i] * tmp[i : i + img.shape[0], :] for i in range(len(k)))


def post_process(
    maps: np.ndarray, width_calibration: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(quality, angle, width px) images from the raw (4, h, w) network output, smoothed;
    widths are multiplied by the weights' ``width_calibration`` (see the module docstring)."""
    q = smooth(maps[0], 2.0)
    angle = 0.5 * np.arctan2(smooth(maps[2], 2.0), smooth(maps[1], 2.0))
    weight = np.clip(maps[0], 0.0, None)
    num, den = smooth(weight * maps[3], 2.0), smooth(weight, 2.0)
    mean_w = np.where(den > 1e-6, num / np.maximum(den, 1e-6), maps[3])
    return q, angle, mean_w * (WIDTH_SCALE * width_calibration)


def detect_grasps(
    q: np.ndarray,
    angle: np.ndarray,
    width: np.ndarray,
    n: int = 1,
    min_distance: int = 5,
    valid: np.ndarray | None = None,
    max_invalid: int = INVALID_PEAKS,
) -> list[tuple[GraspRect, float]]:
    """Up to ``n`` grasps at the highest local maxima of Q, best first, with their quality.

    Local maxima are at least ``min_distance`` pixels apart (greedy suppression). With
    ``valid`` (bool, where the input's depth was measured: `tamp.grasp.depth`), a peak whose
    grasp is not `on_valid_depth` is passed over, and after ``max_invalid`` such peaks the
    search stops: fewer than ``n`` grasps (maybe none) come back.
    """
    order = np.argsort(q, axis=None)[::-1]
    picked: list[tuple[int, int]] = []
    out = []
    passed = 0
    for flat in order:
        y, x = divmod(int(flat), q.shape[1])
        if any(abs(y - py) < min_distance and abs(x - px) < min_distance for py, px in picked):
            continue
        picked.append((y, x))
        w = max(float(width[y, x]), 1.0)
        rect = GraspRect(float(x), float(y), float(angle[y, x]), w, w / 2)
        if valid is not None and not on_valid_depth(rect, valid):
            passed += 1
            if passed >= max_invalid:
                break
            continue
        out.append((rect, float(q[y, x])))
        if len(out) >= n:
            break
    return out
