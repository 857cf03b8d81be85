"""Cornell and Jacquard dataset loaders, splits and augmentation (§V-A).

A dataset is a list of samples (RGB path, depth path, grasp path, object id) found under a
root folder; every file of every sample is checked when the dataset is opened, so a missing
file is reported before training starts. ``load(i, aug)`` reads one sample, applies one
similarity transform (rotation about the crop centre and zoom: the usual augmentation of
GG-CNN / GR-ConvNet) with bilinear resampling, crops to ``size`` x ``size`` and returns the
raw crops, the transformed rectangles and the target maps.

Crops: Jacquard images (objects centred) use the whole square image; Cornell images use a
300 px square around the mean of the ground-truth centres, as GG-CNN does.

Splits: ``image`` shuffles images; ``object`` keeps all images of an object on one side
(Jacquard: the object folder; Cornell: runs of consecutive files, which are images of the
same object, as in GG-CNN's object-wise protocol). Either takes a test fraction, or
``fold`` of ``folds`` for k-fold cross-validation (the paper's five folds on Cornell).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tamp.errors import InputError
from tamp.grasp import formats
from tamp.grasp.maps import draw_targets, fill_missing_depth, stack_input
from tamp.grasp.rect import GraspRect

DATASETS = ("cornell", "jacquard")
SPLITS = ("image", "object")


@dataclass(frozen=True, slots=True)
class SampleFiles:
    rgb: Path
    depth: Path
    grasps: Path
    object_id: str


@dataclass(frozen=True, slots=True)
class Augment:
    """Random rotation (degrees, uniform in ±rotation, or multiples of 90 when ``quarter``)
    and zoom (crop side scale in [zoom_min, 1]) applied to a training sample."""

    rotation: float = 180.0
    zoom_min: float = 0.8
    quarter: bool = False


@dataclass(slots=True)
class Sample:
    rgb: np.ndarray  # (size, size, 3) uint8
    depth: np.ndarray  # (size, size) float32 metres
    rects: list[GraspRect]
    x: np.ndarray  # (C, size, size) network input
    y: np.ndarray  # (4, size, size) targets


def _discover_jacquard(root: Path) -> list[SampleFiles]:
    out = []
    for g in sorted(root.rglob("*_grasps.txt")):
        prefix = str(g)[: -len("_grasps.txt")]
        out.append(
            SampleFiles(
                Path(prefix + "_RGB.png"),
                Path(prefix + "_perfect_depth.tiff"),
                g,
                g.parent.name if g.parent != root else Path(prefix).name.split("_", 1)[-1],
            )
        )
    return out


def _discover_cornell(root: Path) -> list[SampleFiles]:
    out = []
    for g in sorted(root.rglob("pcd*cpos.txt")):
        prefix = str(g)[: -len("cpos.txt")]
        tiff = Path(prefix + "d.tiff")
        depth = tiff if tiff.is_file() else Path(prefix + ".txt")
        number = re.sub(r"\D", "", Path(prefix).name)
        out.append(SampleFiles(Path(prefix + "r.png"), depth, g, number))
    return out


class GraspDataset:
    """Samples of one dataset in the Cornell or Jacquard format, rendered at ``size`` px."""

    def __init__(self, kind: str, root: str | Path, size: int = 224, mode: str = "rgbd"):
        if kind not in DATASETS:
            raise InputError(f"unknown dataset kind {kind!r}; expected one of {list(DATASETS)}")
        self.kind = kind
        self.root = Path(root)
        self.size = int(size)
        self.mode = mode
        if not self.root.is_dir():
            raise InputError("dataset folder not found", file=str(self.root))
        found = (
            _discover_jacquard(self.root) if kind == "jacquard" else _discover_cornell(self.root)
        )
        if not found:
            pattern = "*_grasps.txt" if kind == "jacquard" else "pcd*cpos.txt"
            raise InputError(f"no {kind} grasp file ({pattern}) under the folder", file=str(root))
        for s in found:
            for p in (s.rgb, s.depth):
                if not p.is_file():
                    raise InputError(f"file not found (needed by {s.grasps.name})", file=str(p))
        self.samples = found

    def __len__(self) -> int:
        return len(self.samples)

    def groups(self) -> list[str]:
        """Object id of every sample (for object-wise splits)."""
        if self.kind == "cornell":  # consecutive images show the same object
            return [str(i // 5) for i in range(len(self.samples))]
        return [s.object_id for s in self.samples]

    def read(self, i: int) -> tuple[np.ndarray, np.ndarray, list[GraspRect]]:
        """Raw RGB, depth (metres, holes filled) and rectangles of sample ``i``."""
        s = self.samples[i]
        if self.kind == "jacquard":
            rects = formats.read_jacquard_grasps(s.grasps)
            depth = formats.read_depth_tiff(s.depth)
        else:
            rects = formats.read_cornell_grasps(s.grasps)
            if s.depth.suffix == ".tiff":
                depth = formats.read_depth_tiff(s.depth)
            else:  # the point cloud indexes pixels of the RGB image
                depth = formats.read_cornell_pcd(s.depth, formats.image_shape(s.rgb))
        rgb = formats.read_rgb(s.rgb) if self.mode != "d" else None
        if rgb is not None and rgb.shape[:2] != depth.shape:
            raise InputError(
                f"RGB image is {rgb.shape[1]}x{rgb.shape[0]} but depth is "
                f"{depth.shape[1]}x{depth.shape[0]}",
                file=str(s.rgb),
            )
        return rgb, fill_missing_depth(depth), rects

    def crop_box(
        self, shape: tuple[int, int], rects: list[GraspRect]
    ) -> tuple[float, float, float]:
        """Centre (x, y) and side of the square crop before augmentation."""
        h, w = shape
        if self.kind == "jacquard":
            return (w - 1) / 2, (h - 1) / 2, float(min(h, w))
        cx = float(np.mean([r.x for r in rects]))
        cy = float(np.mean([r.y for r in rects]))
        side = float(min(300, h, w))
        cx = min(max(cx, side / 2), w - side / 2)
        cy = min(max(cy, side / 2), h - side / 2)
        return cx, cy, side

    def load(self, i: int, aug: Augment | None = None, rng: np.random.Generator | None = None):
        """Sample ``i`` cropped to ``size``, augmented when ``aug`` is given."""
        rgb, depth, rects = self.read(i)
        cx, cy, side = self.crop_box(depth.shape, rects)
        angle, zoom = 0.0, 1.0
        if aug is not None:
            rng = rng or np.random.default_rng()
            if aug.quarter:
                angle = math.pi / 2 * int(rng.integers(4))
            else:
                angle = math.radians(rng.uniform(-aug.rotation, aug.rotation))
            zoom = float(rng.uniform(aug.zoom_min, 1.0))
        matrix = similarity(cx, cy, side * zoom, self.size, angle)
        depth_c = warp(depth, matrix, self.size)
        rgb_c = warp(rgb, matrix, self.size) if rgb is not None else None
        out_rects = [r.transformed(matrix) for r in rects]
        x = stack_input(rgb_c, depth_c, self.mode)
        y = draw_targets(out_rects, self.size)
        rgb_out = (
            np.clip(rgb_c, 0, 255).astype(np.uint8)
            if rgb_c is not None
            else np.zeros((self.size, self.size, 3), np.uint8)
        )
        return Sample(rgb_out, depth_c, out_rects, x, y)


def similarity(cx: float, cy: float, side: float, size: int, angle: float) -> np.ndarray:
    """2x3 map from source pixels to output pixels: the ``side`` square at (cx, cy),
    turned by ``angle`` (counter-clockwise on screen) and scaled to ``size`` px."""
    s = size / side
    c, sn = math.cos(angle), math.sin(angle)
    # on screen (y down) a counter-clockwise turn is [[c, s], [-s, c]]
    a = s * np.array([[c, sn], [-sn, c]])
    centre_out = np.array([(size - 1) / 2, (size - 1) / 2])
    t = centre_out - a @ np.array([cx, cy])
    return np.hstack([a, t[:, None]])


def warp(img: np.ndarray, matrix: np.ndarray, size: int) -> np.ndarray:
    """Bilinear resampling of ``img`` (h, w[, c]) under the 2x3 source->output ``matrix``."""
    a, t = matrix[:, :2], matrix[:, 2]
    inv = np.linalg.inv(a)
    ys, xs = np.mgrid[0:size, 0:size].astype(np.float64)
    pts = np.stack([xs.ravel() - t[0], ys.ravel() - t[1]])
    sx, sy = inv @ pts
    h, w = img.shape[:2]
    sx = np.clip(sx, 0, w - 1)
    sy = np.clip(sy, 0, h - 1)
    x0 = np.floor(sx).astype(int)
    y0 = np.floor(sy).astype(int)
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    fx, fy = sx - x0, sy - y0
    src = img.astype(np.float32)
    if src.ndim == 3:
        fx, fy = fx[:, None], fy[:, None]
    out = (
        src[y0, x0] * (1 - fx) * (1 - fy)
        + src[y0, x1] * fx * (1 - fy)
        + src[y1, x0] * (1 - fx) * fy
        + src[y1, x1] * fx * fy
    )
    return out.reshape((size, size) + img.shape[2:]).astype(np.float32)


def make_split(
    groups: list[str],
    split: str = "image",
    test_fraction: float = 0.1,
    seed: int = 0,
    fold: int | None = None,
    folds: int = 5,
) -> tuple[list[int], list[int]]:
    """(train indices, test indices) for an image-wise or object-wise split."""
    if split not in SPLITS:
        raise InputError(f"unknown split {split!r}; expected one of {list(SPLITS)}")
    rng = np.random.default_rng(seed)
    n = len(groups)
    if split == "image":
        units = [[i] for i in rng.permutation(n)]
    else:
        by_group: dict[str, list[int]] = {}
        for i, g in enumerate(groups):
            by_group.setdefault(g, []).append(i)
        keys = sorted(by_group)
        units = [by_group[keys[k]] for k in rng.permutation(len(keys))]
    if len(units) < 2:
        raise InputError(f"a {split}-wise split needs at least 2 {split}s, got {len(units)}")
    if fold is not None:
        if not 0 <= fold < folds:
            raise InputError(f"fold must be in 0..{folds - 1}, got {fold}")
        test_units = [u for k, u in enumerate(units) if k % folds == fold]
        train_units = [u for k, u in enumerate(units) if k % folds != fold]
    else:
        if not 0 < test_fraction < 1:
            raise InputError(f"test fraction must be in (0, 1), got {test_fraction}")
        n_test = min(max(1, int(round(len(units) * test_fraction))), len(units) - 1)
        test_units, train_units = units[:n_test], units[n_test:]
    train = sorted(i for u in train_units for i in u)
    test = sorted(i for u in test_units for i in u)
    return train, test
