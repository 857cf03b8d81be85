"""What `Place` knows of the held object: its footprint from the grasp's views (no
simulation)."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform

from tamp.sim.core.messages import Detection, TargetCrop
from tamp.sim.lots.kinematics import down
from tamp.sim.lots.skills import top_view_points


def _crop(half_u: int, half_v: int, depth: float) -> TargetCrop:
    """A 180 x 180 crop whose target is a rectangle of (2 half_u + 1) x (2 half_v + 1) pixels
    centred in a 320 x 180 image (crop origin (70, 0)), all at ``depth``."""
    mask = np.zeros((180, 180), bool)
    mask[90 - half_v : 90 + half_v + 1, 90 - half_u : 90 + half_u + 1] = True
    det = Detection(1, "hammer", int(mask.sum()), 159.5, 89.5, depth)
    return TargetCrop(det, (70, 0), np.zeros((180, 180, 3), np.uint8), mask * depth, mask)


@pytest.mark.parametrize(("half_u", "half_v"), [(40, 5), (10, 10), (5, 60)])
def test_the_footprint_is_the_targets_extent_on_the_table(half_u, half_v):
    fx = fy = 231.0
    K = (fx, fy, 159.5, 89.5)
    X_WC = RigidTransform(down(0.0), [0.5, 0.25, 0.4])  # looking straight down, 0.4 m up
    pts = top_view_points(_crop(half_u, half_v, 0.4), K, X_WC)
    assert len(pts) == (2 * half_u + 1) * (2 * half_v + 1)
    r = np.hypot(pts[:, 0] - 0.5, pts[:, 1] - 0.25).max()
    corner = np.hypot((half_u + 0.5) / fx, (half_v + 0.5) / fy) * 0.4
    longest = max(half_u, half_v) / fx * 0.4
    assert longest * 0.99 < r <= corner * 1.01  # between the long side and the corner


def test_an_empty_mask_has_no_footprint():
    crop = _crop(3, 3, 0.4)
    empty = TargetCrop(crop.detection, crop.origin, crop.rgb, crop.depth, crop.mask & False)
    assert top_view_points(empty, (231.0, 231.0, 159.5, 89.5), RigidTransform()).shape == (0, 2)
