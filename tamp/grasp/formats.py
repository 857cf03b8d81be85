"""Reading and writing the real Cornell and Jacquard file formats, with precise errors.

Jacquard [37]: per image ``<prefix>_RGB.png``, ``<prefix>_perfect_depth.tiff`` (float
metres) and ``<prefix>_grasps.txt`` with one rectangle per line ``x;y;theta;w;h``: centre in
pixels, angle in degrees measured with the image y-axis pointing down (so our
counter-clockwise ``angle`` is ``-theta``), opening ``w`` and jaw size ``h`` in pixels.

Cornell [36]: per image ``pcdNNNNr.png``, ``pcdNNNNcpos.txt`` (four lines ``x y`` per
rectangle, the first edge being the gripper opening; rectangles holding NaN are skipped as
in the dataset's own tools) and depth either ``pcdNNNNd.tiff`` or the point cloud
``pcdNNNN.txt`` (PCD v0.7 text: header, then ``x y z rgb index`` per point, millimetres;
the pixel is ``index`` in a 640-wide image and the depth is the point's distance).

Every reader raises :class:`tamp.errors.InputError` naming the file (and line) on a missing
or malformed file.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from tamp.errors import InputError
from tamp.grasp.rect import GraspRect

CORNELL_SHAPE = (480, 640)
_PCD_HEADER = {"VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT",
               "POINTS", "DATA"}  # fmt: skip


def _require(path: Path) -> None:
    if not path.is_file():
        raise InputError("file not found", file=str(path))


def _read_lines(path: Path) -> list[str]:
    _require(path)
    try:
        return path.read_text().splitlines()
    except UnicodeDecodeError:
        raise InputError("not a text file", file=str(path)) from None


# --------------------------------------------------------------------------- images


def read_rgb(path: str | Path) -> np.ndarray:
    """An RGB image as ``(h, w, 3) uint8``."""
    from PIL import Image, UnidentifiedImageError

    p = Path(path)
    _require(p)
    try:
        with Image.open(p) as im:
            return np.asarray(im.convert("RGB"), dtype=np.uint8).copy()
    except (UnidentifiedImageError, OSError) as exc:
        raise InputError(f"not a readable image ({exc})", file=str(p)) from None


def image_shape(path: str | Path) -> tuple[int, int]:
    """(height, width) of an image file, read from its header only."""
    from PIL import Image, UnidentifiedImageError

    p = Path(path)
    _require(p)
    try:
        with Image.open(p) as im:
            return im.size[1], im.size[0]
    except (UnidentifiedImageError, OSError) as exc:
        raise InputError(f"not a readable image ({exc})", file=str(p)) from None


def write_rgb(path: str | Path, rgb: np.ndarray) -> None:
    from PIL import Image

    Image.fromarray(np.asarray(rgb, dtype=np.uint8)[..., :3]).save(path)


def read_depth_tiff(path: str | Path) -> np.ndarray:
    """A depth image ``(h, w) float32`` in metres; non-finite values become 0 (missing)."""
    import tifffile

    p = Path(path)
    _require(p)
    try:
        depth = np.asarray(tifffile.imread(p), dtype=np.float32)
    except Exception as exc:  # tifffile raises several types for a corrupt file
        raise InputError(f"not a readable TIFF depth image ({exc})", file=str(p)) from None
    if depth.ndim == 3 and depth.shape[-1] == 1:
        depth = depth[..., 0]
    if depth.ndim != 2:
        raise InputError(f"depth image must be 2-D, got shape {depth.shape}", file=str(p))
    return np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)


def write_depth_tiff(path: str | Path, depth: np.ndarray) -> None:
    import tifffile

    tifffile.imwrite(path, np.asarray(depth, dtype=np.float32))


# --------------------------------------------------------------------------- Jacquard


def read_jacquard_grasps(path: str | Path) -> list[GraspRect]:
    """Rectangles of a Jacquard ``*_grasps.txt`` file (``x;y;theta;w;h`` per line)."""
    p = Path(path)
    rects = []
    for number, line in enumerate(_read_lines(p), start=1):
        text = line.strip()
        if not text:
            continue
        fields = text.split(";")
        if len(fields) != 5:
            raise InputError(
                f"line {number}: expected 5 fields 'x;y;theta;w;h', got {len(fields)}",
                file=str(p),
            )
        try:
            x, y, theta, w, h = (float(v) for v in fields)
        except ValueError:
            raise InputError(f"line {number}: not a number in {text!r}", file=str(p)) from None
        if not all(math.isfinite(v) for v in (x, y, theta, w, h)) or w <= 0 or h <= 0:
            raise InputError(
                f"line {number}: values must be finite with w, h > 0: {text!r}", file=str(p)
            )
        rects.append(GraspRect(x, y, -math.radians(theta), w, h))
    if not rects:
        raise InputError("no grasp rectangle in the file", file=str(p))
    return rects


def format_jacquard_grasps(rects: Sequence[GraspRect]) -> str:
    """The text of a Jacquard grasp file for ``rects``."""
    return "".join(
        f"{r.x:.2f};{r.y:.2f};{-math.degrees(r.angle):.2f};{r.width:.2f};{r.height:.2f}\n"
        for r in rects
    )


def write_jacquard(
    folder: str | Path, prefix: str, rgb: np.ndarray, depth: np.ndarray, rects: Sequence[GraspRect]
) -> Path:
    """Write one Jacquard sample ``folder/prefix_{RGB.png,perfect_depth.tiff,grasps.txt}``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_rgb(folder / f"{prefix}_RGB.png", rgb)
    write_depth_tiff(folder / f"{prefix}_perfect_depth.tiff", depth)
    (folder / f"{prefix}_grasps.txt").write_text(format_jacquard_grasps(rects))
    return folder / f"{prefix}_grasps.txt"


# --------------------------------------------------------------------------- Cornell


def read_cornell_grasps(path: str | Path) -> list[GraspRect]:
    """Rectangles of a Cornell ``pcd*cpos.txt`` file: four ``x y`` lines per rectangle."""
    p = Path(path)
    lines = [(n, ln.strip()) for n, ln in enumerate(_read_lines(p), start=1) if ln.strip()]
    if len(lines) % 4:
        raise InputError(
            f"line {lines[-1][0]}: {len(lines)} corner lines is not a multiple of 4", file=str(p)
        )
    rects = []
    for i in range(0, len(lines), 4):
        corners = []
        for number, text in lines[i : i + 4]:
            fields = text.split()
            if len(fields) != 2:
                raise InputError(
                    f"line {number}: expected 'x y', got {len(fields)} fields", file=str(p)
                )
            try:
                corners.append([float(fields[0]), float(fields[1])])
            except ValueError:
                raise InputError(f"line {number}: not a number in {text!r}", file=str(p)) from None
        arr = np.array(corners)
        if np.isnan(arr).any():
            continue  # the dataset marks a few rectangles as invalid with NaN
        rect = GraspRect.from_corners(arr)
        if rect.width <= 0 or rect.height <= 0:
            raise InputError(f"line {lines[i][0]}: degenerate rectangle", file=str(p))
        rects.append(rect)
    if not rects:
        raise InputError("no valid grasp rectangle in the file", file=str(p))
    return rects


def format_cornell_grasps(rects: Sequence[GraspRect]) -> str:
    return "".join(f"{x:.3f} {y:.3f}\n" for r in rects for x, y in r.corners())


def read_cornell_pcd(path: str | Path, shape: tuple[int, int] = CORNELL_SHAPE) -> np.ndarray:
    """Depth (metres) from a Cornell point-cloud text file; pixels with no point are 0."""
    p = Path(path)
    lines = _read_lines(p)
    img = np.zeros(shape, dtype=np.float32)
    seen_data = False
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = text.split()
        if not seen_data:
            if fields[0].upper() in _PCD_HEADER:
                seen_data = fields[0].upper() == "DATA"
                continue
            raise InputError(f"line {number}: unknown PCD header entry {fields[0]!r}", file=str(p))
        if len(fields) != 5:
            raise InputError(
                f"line {number}: expected 5 fields 'x y z rgb index', got {len(fields)}",
                file=str(p),
            )
        try:
            x, y, z = float(fields[0]), float(fields[1]), float(fields[2])
            index = int(float(fields[4]))
        except ValueError:
            raise InputError(f"line {number}: not a number in {text!r}", file=str(p)) from None
        if not 0 <= index < shape[0] * shape[1]:
            raise InputError(f"line {number}: pixel index {index} outside the image", file=str(p))
        img[index // shape[1], index % shape[1]] = math.sqrt(x * x + y * y + z * z) / 1000.0
    if not seen_data:
        raise InputError("no 'DATA ascii' header line: not a PCD file", file=str(p))
    return img


def write_cornell_pcd(path: str | Path, depth: np.ndarray) -> None:
    """Write a depth image (metres) as a Cornell-style PCD text file (points on the z axis)."""
    h, w = depth.shape
    rows, cols = np.nonzero(depth > 0)
    out = [
        "# .PCD v.7 - Point Cloud Data file format",
        "FIELDS x y z rgb index",
        "SIZE 4 4 4 4 4",
        "TYPE F F F F U",
        "COUNT 1 1 1 1 1",
        f"WIDTH {len(rows)}",
        "HEIGHT 1",
        f"POINTS {len(rows)}",
        "DATA ascii",
    ]
    for r, c in zip(rows, cols, strict=True):
        out.append(f"0 0 {depth[r, c] * 1000.0:.4f} 0 {r * w + c}")
    Path(path).write_text("\n".join(out) + "\n")
