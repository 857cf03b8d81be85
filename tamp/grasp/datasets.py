"""Cornell and Jacquard dataset loaders, splits and augmentation (§V-A).

A dataset is a list of samples (RGB path, depth path, grasp path, object id) found under a
root folder; every file of every sample is checked when the dataset is opened, so a missing
file is reported before training starts. ``load(i, aug)`` reads one sample, applies one
similarity transform (rotation about the crop centre and zoom: the usual augmentation of
GG-CNN / GR-ConvNet) with bilinear resampling, crops to ``size`` x ``size`` and returns the
raw crops, the transformed rectangles and the target maps.

Crops: Jacquard images (objects centred) use the whole square image; Cornell images use a
300 px square around the mean of the ground-truth centres, as GG-CNN does.

Objects (for object-wise splits, :mod:`tamp.grasp.splits`): Jacquard names the object by the
folder of its images. Cornell's file names (``pcdNNNNr.png``) carry the image number only, and
an object has a varying number of images (885 images of 244 objects), so the object of every
image number is read from the object list :data:`CORNELL_OBJECTS` in the dataset folder
(one ``NNNN OBJECT`` line per image, ``#`` comments); without it a Cornell set has no object
ids and only an image-wise split is possible.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tamp.errors import InputError
from tamp.grasp import formats
from tamp.grasp.depth import fill_invalid_depth
from tamp.grasp.maps import draw_targets, stack_input
from tamp.grasp.rect import GraspRect

DATASETS = ("cornell", "jacquard")
#: Cornell object list: image number and object id per line
CORNELL_OBJECTS = "objects.txt"


@dataclass(frozen=True, slots=True)
class SampleFiles:
    rgb: Path
    depth: Path
    grasps: Path
    object_id: str | None  # None: unknown (a Cornell set without its object list)


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
    scale: float = 1.0  # source-image pixels per output pixel
    focal: float | None = None  # camera focal length in source pixels, when the set has it


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


def read_cornell_objects(path: Path) -> dict[int, str]:
    """Image number -> object id from a Cornell object list (``NNNN OBJECT`` per line)."""
    out: dict[int, str] = {}
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        fields = text.split()
        if len(fields) < 2 or not fields[0].isdigit():
            raise InputError(
                f"line {number}: expected 'IMAGE_NUMBER OBJECT_ID', got {text[:60]!r}",
                file=str(path),
            )
        image = int(fields[0])
        if image in out:
            raise InputError(f"line {number}: image {image} listed twice", file=str(path))
        out[image] = fields[1]
    return out


def _discover_cornell(root: Path) -> list[SampleFiles]:
    objects_file = root / CORNELL_OBJECTS
    objects = read_cornell_objects(objects_file) if objects_file.is_file() else None
    out = []
    for g in sorted(root.rglob("pcd*cpos.txt")):
        prefix = str(g)[: -len("cpos.txt")]
        tiff = Path(prefix + "d.tiff")
        depth = tiff if tiff.is_file() else Path(prefix + ".txt")
        digits = re.sub(r"\D", "", Path(prefix).name)
        if not digits:
            raise InputError("no image number in the file name", file=str(g))
        obj = None
        if objects is not None:
            obj = objects.get(int(digits))
            if obj is None:
                raise InputError(
                    f"image {digits} ({g.name}) is not in the object list", file=str(objects_file)
                )
        out.append(SampleFiles(Path(prefix + "r.png"), depth, g, obj))
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

    def ids(self) -> list[str]:
        """Sample id of every sample: its grasp file's path under the root, without the
        suffix (what the split fingerprint hashes)."""
        suffix = "_grasps.txt" if self.kind == "jacquard" else "cpos.txt"
        return [s.grasps.relative_to(self.root).as_posix()[: -len(suffix)] for s in self.samples]

    def groups(self) -> list[str]:
        """Object id of every sample (for object-wise splits)."""
        if any(s.object_id is None for s in self.samples):
            raise InputError(
                "an object-wise split of a Cornell set needs the object of every image: "
                f"write {CORNELL_OBJECTS} (one 'IMAGE_NUMBER OBJECT_ID' line per image)",
                file=str(self.root / CORNELL_OBJECTS),
            )
        return [s.object_id for s in self.samples]

    def split(self, spec):
        """The :class:`~tamp.grasp.splits.Split` of this dataset under ``spec`` (a
        :class:`~tamp.grasp.splits.SplitSpec`); an image-wise split needs no object ids."""
        from tamp.grasp.splits import make_split

        return make_split(self.ids() if spec.kind == "image" else self.groups(), spec)

    def read(self, i: int) -> tuple[np.ndarray, np.ndarray, list[GraspRect]]:
        """Raw RGB, depth (metres, invalid pixels filled: `tamp.grasp.depth`) and rectangles of
        sample ``i``."""
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
        return rgb, fill_invalid_depth(depth), rects

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
        return Sample(rgb_out, depth_c, out_rects, x, y, side * zoom / self.size, self.focal(i))

    def focal(self, i: int) -> float | None:
        """Focal length (pixels) of sample ``i`` from the synthetic set's ``camera.json``."""
        s = self.samples[i]
        if self.kind != "jacquard":
            return None
        cam = Path(str(s.grasps)[: -len("_grasps.txt")] + "_camera.json")
        if not cam.is_file():
            return None
        try:
            return float(json.loads(cam.read_text())["K"][0][0])
        except (ValueError, KeyError, IndexError, TypeError):
            raise InputError("expected JSON with K (3x3)", file=str(cam)) from None


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
