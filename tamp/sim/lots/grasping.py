"""Grasp choice over several views (Zhou et al. §IV-B, Fig. 6), on top of `tamp.grasp.predict`.

Each view gives the network a square crop around the target; its grasps are mapped to the
world through the crop's intrinsics and the camera pose (the arm's own kinematics), and only
grasps whose centre lies on the target's mask are kept. The skill keeps the best grasp of
every view and, after the last (lowest) view, takes the best of all of them.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tamp.grasp.predict import to_world
from tamp.grasp.rect import GraspRect
from tamp.sim.core.models import models_dir
from tamp.sim.lots.perception import TargetCrop
from tamp.sim.lots.scenario import DEFAULT_WEIGHTS, GraspSettings
from tamp.sim.lots.timing import Stopwatch

MAX_OPENING = 0.08  # the gripper's opening (2 x 0.04 m)
#: torch intra-op threads for the network inside the workcell. The simulation runs in the
#: same process and the machine has 2 shared cores: with 2 threads, OpenMP's second thread
#: spin-waits for a core, and one HRG-Net call on a 180 px crop took 6-9 s of wall time
#: and 1.0-1.4 s of CPU (load average 14) against 0.5-0.7 s and 63-75 ms with 1 thread.
INFERENCE_THREADS = 1
#: the object's top must stand this high above the table where the fingers close: the pads
#: stop 2 mm above the table, so a 6 mm saw blade gives them nothing to squeeze
MIN_TOP = 0.008


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

        weights = settings.weights or str(models_dir() / DEFAULT_WEIGHTS[settings.network])
        self.weights = Path(weights)
        self.predictor = GraspPredictor.load(self.weights)
        self.intrinsics = intrinsics
        self.calls = 0
        #: time spent in the network (pre-processing, inference, peak reading)
        self.network = Stopwatch()
        #: (crop, all predicted grasps, kept candidates) of every call when ``record`` is set:
        #: what notebooks and tests show of the descending views (not simulation state)
        self.record = False
        self.history: list[tuple[TargetCrop, list, list[GraspCandidate]]] = []
        #: move each grasp's centre along its closing line onto the target (see `snap_to_mask`)
        self.snap = True

    def candidates(
        self, crop: TargetCrop, X_WC: np.ndarray, view_height: float, n: int = 5
    ) -> list[GraspCandidate]:
        """The network's ``n`` best grasps on the target's mask, best first."""
        fx, fy, cx, cy = self.intrinsics
        u0, v0 = crop.origin
        with self.network, torch_threads(INFERENCE_THREADS):
            grasps = self.predictor.predict(
                rgb=np.asarray(crop.rgb),
                depth=np.asarray(crop.depth, np.float32),
                intrinsics=(fx, fy, cx - u0, cy - v0),
                X_WC=X_WC,
                n=n,
            )
        self.calls += 1
        mask = dilate(np.asarray(crop.mask), 1)
        depth = np.where(crop.mask, crop.depth, 0.0).astype(np.float32)  # the target's top
        out = []
        for g in grasps:
            rect = snap_to_mask(g.rect(), mask) if self.snap else on_mask(g.rect(), mask)
            if rect is None:
                continue
            (x, y, z), yaw, width = to_world(rect, depth, (fx, fy, cx - u0, cy - v0), X_WC)
            if not all(math.isfinite(v) for v in (x, y, z)) or z < MIN_TOP:
                continue  # no depth, or too thin there for the pads (a saw's blade)
            out.append(
                GraspCandidate(x, y, z, yaw, min(width, MAX_OPENING), g.quality, view_height)
            )
        if self.record:
            self.history.append((crop, grasps, out))
        return out


@contextmanager
def torch_threads(n: int):
    """Run the block with ``n`` torch intra-op threads, then restore the previous number."""
    import torch

    before = torch.get_num_threads()
    if before != n:
        torch.set_num_threads(n)
    try:
        yield
    finally:
        if before != n:
            torch.set_num_threads(before)


def on_mask(rect: GraspRect, mask: np.ndarray) -> GraspRect | None:
    """``rect`` if its centre lies on the mask, else None (the strict reading)."""
    r, c = int(round(rect.y)), int(round(rect.x))
    ok = 0 <= r < mask.shape[0] and 0 <= c < mask.shape[1] and mask[r, c]
    return rect if ok else None


def snap_to_mask(rect: GraspRect, mask: np.ndarray, reach: float = 0.75) -> GraspRect | None:
    """The grasp moved along its closing line to the middle of the target run nearest its
    centre, or None when the line (``reach`` x the opening each side) misses the target.

    On the workcell's views the shipped weights put the quality peak beside thin objects with
    the right closing angle (the jaws straddle the object, the centre lies on the table); the
    closing line then crosses the object, and this keeps the network's angle and quality
    while centring the fingers on what they must close on. Without it, most views give no
    grasp on the target (docs/lots_workcell.md has the figures).
    """
    d = rect.direction
    half = max(rect.width, 12.0) * reach
    ts = np.arange(-half, half + 0.5, 0.5)
    us = np.round(rect.x + ts * d[0]).astype(int)
    vs = np.round(rect.y + ts * d[1]).astype(int)
    inside = (us >= 0) & (us < mask.shape[1]) & (vs >= 0) & (vs < mask.shape[0])
    hit = np.zeros(ts.shape, bool)
    hit[inside] = mask[vs[inside], us[inside]]
    if not hit.any():
        return None
    # contiguous runs of hits; take the one nearest t = 0
    idx = np.flatnonzero(hit)
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
    best = min(
        runs, key=lambda r: min(abs(ts[r[0]]), abs(ts[r[-1]])) if ts[r[0]] * ts[r[-1]] > 0 else 0
    )
    t = (ts[best[0]] + ts[best[-1]]) / 2
    return GraspRect(rect.x + t * d[0], rect.y + t * d[1], rect.angle, rect.width, rect.height)


def dilate(mask: np.ndarray, r: int) -> np.ndarray:
    """Binary dilation by a (2r+1) square (numpy only)."""
    out = mask.copy()
    h, w = mask.shape
    for dr in range(-r, r + 1):
        for dc in range(-r, r + 1):
            src = mask[max(-dr, 0) : h - max(dr, 0), max(-dc, 0) : w - max(dc, 0)]
            out[max(dr, 0) : h - max(-dr, 0), max(dc, 0) : w - max(-dc, 0)] |= src
    return out
