"""Grasps from one camera image, in pixels and in the world frame (what the robot calls).

``GraspPredictor.predict(rgb=..., depth=..., intrinsics=(fx, fy, cx, cy), X_WC=...)``
takes the central square of the image, resizes it to the network's input size, runs the
network, reads the best grasps at the peaks of the smoothed quality map (§IV-B: g = (x, y,
z, Φ, w, q)) and maps them back to the original pixels. With the intrinsics and the camera
pose X_WC (4x4, camera frame x right, y down, z forward, as Drake's RgbdSensor and the
RealSense use), each grasp also gets its world point (from the z-depth at the grasp
pixel), the closing direction's yaw in the world xy plane and the opening in metres.

Depth the camera did not measure (holes, values outside the predictor's `DepthRange`) is
filled from valid neighbours for the network and never carries a grasp (`tamp.grasp.depth`):
``GraspPredictor.detect`` returns the grasps on valid depth with the reason when there is
none, ``predict`` the grasps alone.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from tamp.grasp.datasets import similarity, warp
from tamp.grasp.depth import (
    DEFAULT_DEPTH_RANGE,
    DepthCheck,
    DepthRange,
    check_depth,
    fill_invalid,
    valid_depth,
)
from tamp.grasp.maps import detect_grasps, post_process, stack_input
from tamp.grasp.pinhole import pixel_to_camera
from tamp.grasp.rect import GraspRect, wrap_angle


@dataclass(frozen=True)
class PredictedGrasp:
    """One grasp: pixel centre, angle (rad, counter-clockwise on screen), opening, quality
    (the regressed quality map's peak, trained towards 1 at grasp centres: not a probability,
    it can read a little above 1); world position (m), closing yaw (rad) and opening (m) when
    a camera was given."""

    u: float
    v: float
    angle: float
    width_px: float
    quality: float
    position: tuple[float, float, float] | None = None
    yaw: float | None = None
    width_m: float | None = None

    @property
    def angle_deg(self) -> float:
        return math.degrees(self.angle)

    @property
    def yaw_deg(self) -> float | None:
        return None if self.yaw is None else math.degrees(self.yaw)

    def rect(self) -> GraspRect:
        return GraspRect(self.u, self.v, self.angle, self.width_px, self.width_px / 2)

    def as_dict(self) -> dict:
        return asdict(self)


def depth_at(
    depth: np.ndarray,
    u: float,
    v: float,
    radius: int = 2,
    depth_range: DepthRange = DEFAULT_DEPTH_RANGE,
) -> float:
    """Median of the valid depth values (`tamp.grasp.depth.valid_depth`) in a small window
    around (u, v); NaN when the window holds none (no depth is made up)."""
    r0, c0 = int(round(v)), int(round(u))
    win = depth[max(r0 - radius, 0) : r0 + radius + 1, max(c0 - radius, 0) : c0 + radius + 1]
    valid = win[valid_depth(win, depth_range)]
    return float(np.median(valid)) if valid.size else float("nan")


def to_world(
    rect: GraspRect,
    depth: np.ndarray,
    intrinsics,
    X_WC: np.ndarray,
    depth_range: DepthRange = DEFAULT_DEPTH_RANGE,
):
    """(world point, closing yaw, opening in metres) of a pixel grasp; NaN coordinates when
    there is no valid depth at its centre."""
    z = depth_at(depth, rect.x, rect.y, depth_range=depth_range)
    d = rect.direction * rect.width / 2
    a = pixel_to_camera(rect.x - d[0], rect.y - d[1], z, intrinsics)
    b = pixel_to_camera(rect.x + d[0], rect.y + d[1], z, intrinsics)
    c = pixel_to_camera(rect.x, rect.y, z, intrinsics)
    R, p = X_WC[:3, :3], X_WC[:3, 3]
    cw, aw, bw = R @ c + p, R @ a + p, R @ b + p
    yaw = wrap_angle(math.atan2(bw[1] - aw[1], bw[0] - aw[0]))
    return tuple(float(v) for v in cw), yaw, float(np.linalg.norm(bw - aw))


@dataclass(frozen=True)
class Prediction:
    """The grasps of one image, best first, with what its depth held (None without depth)
    and, when no grasp came back, why."""

    grasps: list[PredictedGrasp]
    depth: DepthCheck | None = None
    reason: str | None = None


class GraspPredictor:
    """A trained network plus the pre- and post-processing of ``eval``, and the depth range
    of the camera whose images it reads (`tamp.grasp.depth`)."""

    def __init__(
        self,
        model,
        meta: dict,
        device: str = "cpu",
        depth_range: DepthRange = DEFAULT_DEPTH_RANGE,
    ):
        if device == "cpu" and isinstance(model, torch.nn.Module):
            from tamp.grasp.evaluate import optimize_for_cpu

            model = optimize_for_cpu(model)
        self.model = model
        self.meta = meta
        self.device = device
        self.mode = meta["input"]
        self.size = int(meta["size"])
        self.depth_range = depth_range
        from tamp.grasp.evaluate import calibration_of

        self.width_calibration = calibration_of(meta)

    @classmethod
    def load(
        cls,
        path: str | Path,
        device: str = "cpu",
        depth_range: DepthRange = DEFAULT_DEPTH_RANGE,
    ) -> GraspPredictor:
        from tamp.grasp.train import load_model

        model, meta = load_model(path, device)
        return cls(model, meta, device, depth_range)

    def _check_inputs(self, rgb, depth) -> None:
        from tamp.errors import InputError

        if self.mode in ("d", "rgbd") and depth is None:
            raise InputError(f"this network takes {self.mode!r} input: a depth image is needed")
        if self.mode in ("rgb", "rgbd") and rgb is None:
            raise InputError(f"this network takes {self.mode!r} input: an RGB image is needed")
        if rgb is not None and depth is not None and rgb.shape[:2] != np.shape(depth):
            raise InputError(f"RGB {rgb.shape[:2]} and depth {np.shape(depth)} differ in size")

    def maps(self, rgb=None, depth=None, valid=None) -> tuple[np.ndarray, np.ndarray]:
        """(raw 4 x size x size output, 2x3 source->network pixel map) for one image; the
        depth's pixels outside ``valid`` (default: `valid_depth` in the predictor's range)
        are filled from their valid neighbours first (`tamp.grasp.depth.fill_invalid`)."""
        from tamp.grasp.evaluate import predict_maps

        self._check_inputs(rgb, depth)
        ref = depth if depth is not None else rgb
        h, w = ref.shape[:2]
        matrix = similarity((w - 1) / 2, (h - 1) / 2, float(min(h, w)), self.size, 0.0)
        d = None
        if depth is not None:
            if valid is None:
                valid = valid_depth(depth, self.depth_range)
            d = warp(fill_invalid(depth, valid), matrix, self.size)
        c = warp(np.asarray(rgb)[..., :3], matrix, self.size) if rgb is not None else None
        x = stack_input(c, d, self.mode)[None]
        return predict_maps(self.model, x, self.device)[0], matrix

    def detect(self, rgb=None, depth=None, intrinsics=None, X_WC=None, n: int = 1) -> Prediction:
        """The ``n`` best grasps on valid depth, best first (see the module docstring and
        `tamp.grasp.depth`); fewer or none, with the reason, where the depth is invalid."""
        self._check_inputs(rgb, depth)
        check = None
        if depth is not None:
            depth = np.asarray(depth, np.float32)
            check = check_depth(depth, self.depth_range)
            problem = check.problem()
            if problem:
                return Prediction([], check, problem)
        raw, matrix = self.maps(rgb, depth, None if check is None else check.valid)
        q, angle, width = post_process(raw, self.width_calibration)
        valid_net = None
        if check is not None and not check.valid.all():
            valid_net = warp(check.valid.astype(np.float32), matrix, self.size) >= 0.5
        back = np.linalg.inv(np.vstack([matrix, [0, 0, 1]]))[:2]
        out = []
        for rect_net, quality in detect_grasps(q, angle, width, n=n, valid=valid_net):
            r = rect_net.transformed(back)
            pos = yaw = width_m = None
            if intrinsics is not None and X_WC is not None and depth is not None:
                X = np.asarray(X_WC, float)
                pos, yaw, width_m = to_world(r, depth, intrinsics, X, self.depth_range)
                if not all(math.isfinite(v) for v in pos):
                    continue  # no valid depth around the centre in the original pixels
            out.append(PredictedGrasp(r.x, r.y, r.angle, r.width, quality, pos, yaw, width_m))
        reason = None
        if not out:
            reason = "the network's best grasps lie on invalid depth"
            if check is not None:
                reason += f": {check.describe()}"
        return Prediction(out, check, reason)

    def predict(self, rgb=None, depth=None, intrinsics=None, X_WC=None, n: int = 1):
        """The ``n`` best grasps on valid depth, best first: :meth:`detect` without the
        reason (an empty list where the depth holds no grasp)."""
        return self.detect(rgb, depth, intrinsics, X_WC, n).grasps


def predict_grasps(weights, rgb=None, depth=None, intrinsics=None, X_WC=None, n: int = 1):
    """One-call form of :meth:`GraspPredictor.predict` (loads the weights each time)."""
    return GraspPredictor.load(weights).predict(rgb, depth, intrinsics, X_WC, n)
