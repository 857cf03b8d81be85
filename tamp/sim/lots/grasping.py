"""Grasp choice over several views (Zhou et al. §IV-B, Fig. 6), on top of `tamp.grasp.predict`.

Each view gives the network a square crop around the target; its grasps are mapped to the
world through the crop's intrinsics and the camera pose (the arm's own kinematics), and only
grasps whose centre lies on the target's mask are kept. The skill keeps the best grasp of
every view and, after the last (lowest) view, takes the best of all of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tamp.sim.core.models import MODELS_DIR
from tamp.sim.lots.perception import TargetCrop
from tamp.sim.lots.scenario import DEFAULT_WEIGHTS, GraspSettings

MAX_OPENING = 0.08  # the gripper's opening (2 x 0.04 m)


@dataclass(frozen=True)
class GraspCandidate:
    """A world-frame top grasp: centre on the object's top, closing yaw, opening, quality,
    and the camera height of the view it came from."""

    x: float
    y: float
    z: float
    yaw: float
    width: float
    quality: float
    view_height: float


class GraspPlanner:
    """Loads the chosen network once; turns a `TargetCrop` into world-frame candidates."""

    def __init__(self, settings: GraspSettings, intrinsics: tuple[float, float, float, float]):
        from tamp.grasp.predict import GraspPredictor

        weights = settings.weights or str(MODELS_DIR / DEFAULT_WEIGHTS[settings.network])
        self.weights = Path(weights)
        self.predictor = GraspPredictor.load(self.weights)
        self.intrinsics = intrinsics
        self.calls = 0
        #: (crop, all predicted grasps, kept candidates) of every call when ``record`` is set:
        #: what notebooks and tests show of the descending views (not simulation state)
        self.record = False
        self.history: list[tuple[TargetCrop, list, list[GraspCandidate]]] = []

    def candidates(
        self, crop: TargetCrop, X_WC: np.ndarray, view_height: float, n: int = 5
    ) -> list[GraspCandidate]:
        """The network's ``n`` best grasps on the target's mask, best first."""
        fx, fy, cx, cy = self.intrinsics
        u0, v0 = crop.origin
        grasps = self.predictor.predict(
            rgb=np.asarray(crop.rgb),
            depth=np.asarray(crop.depth, np.float32),
            intrinsics=(fx, fy, cx - u0, cy - v0),
            X_WC=X_WC,
            n=n,
        )
        self.calls += 1
        mask = dilate(np.asarray(crop.mask), 2)
        out = []
        for g in grasps:
            r, c = int(round(g.v)), int(round(g.u))
            if not (0 <= r < mask.shape[0] and 0 <= c < mask.shape[1] and mask[r, c]):
                continue
            if g.position is None or not all(math.isfinite(v) for v in g.position):
                continue
            x, y, z = g.position
            out.append(
                GraspCandidate(x, y, z, g.yaw, min(g.width_m, MAX_OPENING), g.quality, view_height)
            )
        if self.record:
            self.history.append((crop, grasps, out))
        return out


def dilate(mask: np.ndarray, r: int) -> np.ndarray:
    """Binary dilation by a (2r+1) square (numpy only)."""
    out = mask.copy()
    h, w = mask.shape
    for dr in range(-r, r + 1):
        for dc in range(-r, r + 1):
            src = mask[max(-dr, 0) : h - max(dr, 0), max(-dc, 0) : w - max(dc, 0)]
            out[max(dr, 0) : h - max(-dr, 0), max(dc, 0) : w - max(-dc, 0)] |= src
    return out
