"""The detector's classifier: one instance proposal's crop and size in, its class out (torch).

The second stage of the classic tabletop pipeline (proposals from geometry,
`tamp.sim.core.instances.proposals`; then a classifier per proposal, as in Rusu et al.,
RAS 56(11), 2008, §5-6, with a small CNN in place of their hand-made features). Zhou et al.
(IEEE T-ASE 2023, §IV-V) count the workcell's objects per class from the wrist camera; a
proposal already is one object (or a few touching ones), so the network only has to name it.

Input of one proposal (`crop_input`): a square window around its mask (1.25 times its larger
side), resampled to `CROP` x `CROP` pixels (nearest), with five channels: RGB centred, height
above the support plane in units of 5 cm (clipped to [-1, 5]) and the mask; plus `FEATURES`
metric features a robot measures from the proposal's points: the number of pixels (log), its
length and width on the table (the spread of its world points along their principal axes,
5th to 95th percentile), its height above the plane (95th percentile), its median depth and
the share of its pixels on the image border (a truncated object looks smaller).

Outputs (`output_names`): the object classes of the data set (the catalogue, ``unknown``,
``hand``), then ``several`` (the proposal holds two or more touching objects: the detector
splits it finer) and ``none`` (not an object: a piece of table, a shadowless mat edge).
A class is only given to a proposal of a size its training proposals had (`size_gate`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

#: the shipped weights (``tamp/models/weights``)
WEIGHTS_FILE = "detector_crops_rgbd.pt"
CROP = 32
IN_CHANNELS = 5
FEATURES = 6
HEIGHT_SCALE = 0.05
#: the window around a mask: this times its larger side (context for the classifier)
MARGIN = 1.25
SEVERAL = "several"
NONE = "none"
#: the size gate's slack over the sizes seen in training (`size_gate`)
SIZE_MARGIN = 1.1


def output_names(object_classes: Sequence[str]) -> list[str]:
    """The classifier's outputs: the object classes, then ``several`` and ``none``."""
    return [*object_classes, SEVERAL, NONE]


def _block(cin: int, cout: int) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, padding=1, bias=False),
        nn.BatchNorm2d(cout),
        nn.ReLU(inplace=True),
        nn.Conv2d(cout, cout, 3, padding=1, bias=False),
        nn.BatchNorm2d(cout),
        nn.ReLU(inplace=True),
        nn.MaxPool2d(2),
    )


class CropNet(nn.Module):
    """Logits (N, outputs) of crops (N, 5, 32, 32) and their metric features (N, 6): three
    convolution stages (32 -> 16 -> 8 -> 4 pixels), global average pooling, the features
    through one hidden layer, and a two-layer head on both."""

    def __init__(self, outputs: int, width: int = 16):
        super().__init__()
        c1, c2, c3 = width, 2 * width, 3 * width
        self.conv = nn.Sequential(_block(IN_CHANNELS, c1), _block(c1, c2), _block(c2, c3))
        self.feat = nn.Sequential(nn.Linear(FEATURES, 32), nn.ReLU(inplace=True))
        self.head = nn.Sequential(
            nn.Linear(c3 + 32, 96), nn.ReLU(inplace=True), nn.Dropout(0.1), nn.Linear(96, outputs)
        )

    def forward(self, x: torch.Tensor, f: torch.Tensor) -> torch.Tensor:
        g = self.conv(x).mean(dim=(2, 3))
        return self.head(torch.cat([g, self.feat(f)], dim=1))


def _extent(points: np.ndarray) -> tuple[float, float]:
    """(length, width) of world points (3 x N) on the table: 5th-95th percentile spread along
    the principal axes of their x, y."""
    if points.shape[1] < 3:
        return 0.0, 0.0
    xy = points[:2] - points[:2].mean(axis=1, keepdims=True)
    _, vecs = np.linalg.eigh(xy @ xy.T)
    proj = vecs.T @ xy
    lo, hi = np.percentile(proj, [5, 95], axis=1)
    spread = hi - lo
    return float(spread[1]), float(spread[0])


def crop_input(
    rgb: np.ndarray,
    heights: np.ndarray,
    depth: np.ndarray,
    mask: np.ndarray,
    points: np.ndarray,
    *,
    margin: float = MARGIN,
    shift: tuple[float, float] = (0.0, 0.0),
) -> tuple[np.ndarray, np.ndarray]:
    """(crop (5, 32, 32) float32, features (6,) float32) of one proposal (module docstring):
    ``rgb`` (H, W, 3+) uint8, ``heights`` above the support plane (H, W, m, NaN = no return),
    ``depth`` (H, W, m), ``mask`` (H, W) bool, ``points`` its world points (3 x N).
    ``margin`` and ``shift`` (the window's centre moved by these shares of its side, rows
    then columns) vary the window for training."""
    h, w = mask.shape
    vs, us = np.nonzero(mask)
    v0, v1, u0, u1 = vs.min(), vs.max() + 1, us.min(), us.max() + 1
    side = margin * max(v1 - v0, u1 - u0) + 2.0
    grid = (np.arange(CROP) + 0.5) * side / CROP - side / 2
    rows = np.floor(0.5 * (v0 + v1) + shift[0] * side + grid).astype(int)
    cols = np.floor(0.5 * (u0 + u1) + shift[1] * side + grid).astype(int)
    inside = ((rows >= 0) & (rows < h))[:, None] & ((cols >= 0) & (cols < w))[None, :]
    r, c = np.clip(rows, 0, h - 1), np.clip(cols, 0, w - 1)
    x = np.empty((IN_CHANNELS, CROP, CROP), np.float32)
    x[:3] = np.moveaxis(rgb[r[:, None], c[None, :], :3].astype(np.float32) / 255.0 - 0.5, -1, 0)
    hgt = heights[r[:, None], c[None, :]]
    x[3] = np.clip(np.nan_to_num(hgt, nan=0.0) / HEIGHT_SCALE, -1.0, 5.0)
    x[4] = mask[r[:, None], c[None, :]]
    x[:, ~inside] = 0.0
    n = len(vs)
    length, width = _extent(points)
    hm = heights[mask]
    hm = hm[np.isfinite(hm)]
    d = depth[mask]
    d = d[np.isfinite(d) & (d > 0)]
    border = (vs == 0) | (vs == h - 1) | (us == 0) | (us == w - 1)
    f = np.array(
        [
            np.log(n) / 5.0,
            10.0 * length,
            10.0 * width,
            10.0 * (float(np.percentile(hm, 95)) if hm.size else 0.0),
            5.0 * (float(np.median(d)) if d.size else 0.0),
            10.0 * float(border.mean()),
        ],
        np.float32,
    )
    return x, f


def size_gate(features: np.ndarray, sizes: dict | None, margin: float = SIZE_MARGIN) -> bool:
    """Whether a proposal of ``features`` (`crop_input`) fits a class's ``sizes`` (its
    training proposals' span, ``{"low": [l, w, h], "high": [l, w, h]}`` in metres): no side
    more than ``margin`` times the largest seen, and, when it is wholly inside the image, none
    under the smallest seen divided by ``margin``. A robot knows its catalogue's sizes: a
    plate twice a saw's width is no saw, however saw-like its crop looks."""
    if not sizes:
        return True
    size = np.asarray(features[1:4], float) / 10.0
    if (size > margin * np.asarray(sizes["high"])).any():
        return False
    inside = features[5] == 0
    return not (inside and (size < np.asarray(sizes["low"]) / margin).any())


@torch.no_grad()
def classify(model: CropNet, crops: np.ndarray, features: np.ndarray) -> np.ndarray:
    """Output probabilities (N, outputs) of a batch of crops and features."""
    if len(crops) == 0:
        return np.zeros((0, model.head[-1].out_features), np.float32)
    logits = model(torch.from_numpy(crops), torch.from_numpy(features))
    return F.softmax(logits, dim=1).numpy()


def save(path: str | Path, model: CropNet, meta: dict) -> None:
    """A weights file (the grasp networks' format: ``{"meta", "state_dict"}``, loadable with
    ``weights_only=True``); ``meta`` holds the outputs, the width, the threshold and split."""
    from tamp.grasp.train import write_weights

    write_weights(Path(path), meta, model.state_dict())


def load(path: str | Path) -> tuple[CropNet, dict]:
    """(the classifier in eval mode, its meta) of a weights file; `InputError` naming the
    file when it is not a crop classifier's weights."""
    from tamp.errors import InputError
    from tamp.grasp.train import read_weights

    blob = read_weights(path, "cpu")
    meta = blob["meta"]
    try:
        model = CropNet(len(meta["outputs"]), int(meta["width"]))
        model.load_state_dict(blob["state_dict"])
    except (KeyError, TypeError, RuntimeError) as exc:
        raise InputError(
            f"not crop-classifier weights ({type(exc).__name__}: {str(exc)[:200]})",
            file=str(path),
        ) from None
    return model.eval(), meta
