"""Fixture datasets written by the tests themselves, in the exact Cornell/Jacquard formats.

Each image shows one bar (a box-like object) on a plane: depth 0.6 m for the plane and
0.57 m on the bar, a coloured bar on a grey background; the ground-truth grasp is across
the bar at its centre. Nothing here is downloaded.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from tamp.grasp import formats
from tamp.grasp.rect import GraspRect


def bar_image(size: int, cx: float, cy: float, angle: float, length: float, thick: float):
    """(rgb, depth, rect) of a bar along ``angle`` (ccw on screen), grasp across it."""
    ys, xs = np.mgrid[0:size, 0:size].astype(float)
    d = np.array([math.cos(angle), -math.sin(angle)])
    along = (xs - cx) * d[0] + (ys - cy) * d[1]
    across = -(xs - cx) * d[1] + (ys - cy) * d[0]
    mask = (np.abs(along) <= length / 2) & (np.abs(across) <= thick / 2)
    depth = np.where(mask, 0.57, 0.6).astype(np.float32)
    rgb = np.full((size, size, 3), 120, np.uint8)
    rgb[mask] = (200, 40, 40)
    rect = GraspRect(cx, cy, angle + math.pi / 2, thick * 1.5, min(thick, length / 3))
    return rgb, depth, rect


def write_jacquard_set(root: Path, objects: int = 4, views: int = 2, size: int = 64, seed=0):
    rng = np.random.default_rng(seed)
    for o in range(objects):
        for v in range(views):
            c = rng.uniform(size * 0.35, size * 0.65, 2)
            rgb, depth, rect = bar_image(size, c[0], c[1], rng.uniform(-3, 3), size * 0.5, 8)
            formats.write_jacquard(root / f"obj{o}", f"{v}_obj{o}", rgb, depth, [rect])
    return root


def write_cornell_set(root: Path, images: int = 6, size=(48, 64), seed=0, pcd=True):
    rng = np.random.default_rng(seed)
    root.mkdir(parents=True, exist_ok=True)
    h, w = size
    for i in range(images):
        c = rng.uniform(20, 28, 2)
        rgb, depth, rect = bar_image(max(h, w), c[0], c[1], rng.uniform(-3, 3), 24, 8)
        rgb, depth = rgb[:h, :w], depth[:h, :w]
        prefix = root / f"pcd{100 + i:04d}"
        formats.write_rgb(f"{prefix}r.png", rgb)
        if pcd:
            formats.write_cornell_pcd(f"{prefix}.txt", depth)
        else:
            formats.write_depth_tiff(f"{prefix}d.tiff", depth)
        Path(f"{prefix}cpos.txt").write_text(formats.format_cornell_grasps([rect]))
    return root
