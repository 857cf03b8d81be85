"""The object detector: colour + depth + camera pose in, objects out (torch).

Zhou et al. (IEEE T-ASE 2023, §IV-V) detect the workcell's objects with a network on the
wrist camera's RGB-D images. `Detector` is ours: the segmentation network of
`tamp.sim.core.segnet` (trained on Drake renders by ``tamp detect train``) followed by
instance extraction (`tamp.sim.core.instances.extract`). Its inputs are only what a real
camera and arm give: the colour and depth images, the intrinsics and the camera pose from the
arm's kinematics. Its output per view is a list of `ObjectDetection` (class or ``unknown``,
score, mask, pixel centroid, 3-D centroid and world-frame points).

Resolution: the network runs at the resolution it was trained at (the weights record it:
160 x 90, half the LOTS wrist camera's 320 x 180, which keeps one frame near 20 ms of one
CPU core). A larger image whose size is an integer multiple of it is subsampled for the
network and the instance extraction; the masks are scaled back up (nearest), and points,
centroids and depths are taken from the image's own depth at its own resolution.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch

from tamp.sim.core.instances import (
    DEPTH_JUMP,
    MIN_PIXELS,
    UNKNOWN_BELOW,
    ObjectDetection,
    extract,
    located,
)
from tamp.sim.core.segdata import STUFF
from tamp.sim.core.segnet import SegNet, load, prepare


class Detector:
    """A trained segmentation network and the rules that make objects of its output."""

    def __init__(
        self,
        model: SegNet,
        meta: dict,
        *,
        min_pixels: int = MIN_PIXELS,
        jump: float = DEPTH_JUMP,
        unknown_below: float = UNKNOWN_BELOW,
        device: str = "cpu",
    ):
        self.model = model.to(device).eval()
        self.meta = meta
        self.classes: tuple[str, ...] = tuple(meta["classes"])
        self.size: tuple[int, int] = tuple(meta.get("size", (160, 90)))  # (width, height)
        self.objects = [i for i, n in enumerate(self.classes) if n not in STUFF]
        self.min_pixels = min_pixels
        self.jump = jump
        self.unknown_below = unknown_below
        self.device = device

    @classmethod
    def load(cls, path: str | Path | None = None, **kwargs) -> Detector:
        """The detector of a weights file (default: the shipped weights)."""
        if path is None:
            from tamp.sim.core.models import models_dir
            from tamp.sim.core.segnet import WEIGHTS_FILE

            path = models_dir() / "weights" / WEIGHTS_FILE
        model, meta = load(path, kwargs.get("device", "cpu"))
        return cls(model, meta, **kwargs)

    def _factor(self, shape: tuple[int, int]) -> int:
        h, w = shape
        W, H = self.size
        k = w // W
        if k >= 1 and w == k * W and h == k * H:
            return k
        return 1

    @torch.no_grad()
    def _network(self, rgb: np.ndarray, depth: np.ndarray, k: int) -> np.ndarray:
        """Class probabilities (C x H/k x W/k) of the image subsampled by ``k``."""
        x = prepare(rgb[::k, ::k], depth[::k, ::k])
        logits = self.model(torch.from_numpy(x)[None].to(self.device))[0]
        return torch.softmax(logits, dim=0).cpu().numpy()

    def probabilities(self, rgb: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """Class probabilities (C x H x W) at the image's resolution."""
        k = self._factor(depth.shape)
        probs = self._network(rgb, depth, k)
        if k > 1:
            probs = probs.repeat(k, axis=1).repeat(k, axis=2)
        return probs

    def detect(
        self, rgb: np.ndarray, depth: np.ndarray, intrinsics: Sequence[float], X_WC
    ) -> list[ObjectDetection]:
        """The objects in one view: ``rgb`` (H x W x 3 or 4, uint8), ``depth`` (H x W,
        metres), ``intrinsics`` (fx, fy, cx, cy) of this image, ``X_WC`` the camera pose
        (4 x 4 or a Drake ``RigidTransform``) from the arm's kinematics.

        An image ``k`` times the network's size is segmented and split into instances at the
        network's size (on the subsampled depth); each mask is then scaled up ``k`` times and
        its points and centroid are taken from the full-size depth."""
        k = self._factor(depth.shape)
        probs = self._network(rgb, depth, k)
        fx, fy, cx, cy = intrinsics
        found = extract(
            probs,
            depth[::k, ::k],
            self.classes,
            self.objects,
            (fx / k, fy / k, cx / k, cy / k),
            X_WC,
            jump=self.jump,
            min_pixels=self.min_pixels,
            unknown_below=self.unknown_below,
        )
        if k == 1:
            return found
        h, w = depth.shape
        depth = np.where(np.isfinite(depth), depth, 0.0)
        out = []
        for d in found:
            mask = d.mask.repeat(k, axis=0).repeat(k, axis=1)[:h, :w]
            where = located(mask, depth, intrinsics, X_WC)
            if where is not None:
                out.append(dataclasses.replace(d, mask=mask, **where))
        return out
