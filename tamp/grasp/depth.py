"""Which depth pixels are measurements, how the network sees the others, and where a grasp
may stand.

A depth camera reports a pixel it could not measure as 0 or NaN (a hole: a shiny or dark
surface, a shadow of the projector, an edge), and a renderer as 0 (nearer than its near
plane) or infinity (farther than its far plane). A pixel is **valid** when its depth is a
finite number inside the sensor's range :class:`DepthRange` (default
:data:`DEFAULT_DEPTH_RANGE`, 0.05-5 m: every tabletop camera placement, from the LOTS
workcell's eye-in-hand views 0.15-0.34 m above the target to a Kinect 0.6-1 m above a
Cornell table, and it catches a depth image written in millimetres, whose 600 mm table
reads 600 m). Everything else is **invalid**: holes, values nearer or farther than the range,
and the few negative values a filtered image may carry.

Masked pixels are filled for the network from their valid neighbours (:func:`fill_invalid`:
each takes the depth of the nearest valid pixel). GG-CNN (Morrison et al., RSS 2018) and
GR-ConvNet (Kumra et al., IROS 2020) inpaint the holes (0) of Cornell and Jacquard depth with
OpenCV's Navier-Stokes method before the network, in their released preprocessing
(``DepthImage.inpaint``); the nearest-valid fill continues the surface that bounds the hole
in the same way (not a value from elsewhere in the image, as a median does) without OpenCV.
The fill only keeps the network's input well defined: a grasp whose centre, or most of whose
rectangle, lies on invalid depth is never returned (:func:`on_valid_depth`), since the camera
saw nothing there.

Bad input (:meth:`DepthCheck.problem`): an image with no valid pixel at all, or with negative
depth on more than :data:`NEGATIVE_TOLERANCE` of its pixels. Depth is the distance in front
of the camera along its optical axis; an image that is negative beyond a few noise pixels
follows another convention (OpenGL's camera looks down -z) or is not a depth image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tamp.errors import InputError
from tamp.grasp.rect import GraspRect

#: more negative pixels than this share of the image make it bad input (fewer: holes)
NEGATIVE_TOLERANCE = 0.01
#: a grasp stands on valid depth when its centre does and at least this share of its
#: rectangle does (`on_valid_depth`)
MIN_VALID_SHARE = 0.5
#: peaks of the quality map on invalid depth passed over before the answer is "no grasp"
#: (`tamp.grasp.maps.detect_grasps`): the network's best guesses lie where the camera saw
#: nothing
INVALID_PEAKS = 10


@dataclass(frozen=True)
class DepthRange:
    """The depth a sensor measures, in metres: valid depth lies in ``[near, far]``."""

    near: float
    far: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.near) and math.isfinite(self.far)):
            raise InputError(f"depth range {self.near}-{self.far} m must be finite")
        if not 0 < self.near < self.far:
            raise InputError(f"depth range needs 0 < MIN < MAX, got {self.near},{self.far}")

    @classmethod
    def parse(cls, text: str, field: str = "--depth-range") -> DepthRange:
        """``"MIN,MAX"`` in metres, e.g. ``"0.05,5"``."""
        parts = text.split(",")
        try:
            near, far = (float(p) for p in parts)
        except ValueError:
            raise InputError(f"expected MIN,MAX in metres, got {text!r}", field=field) from None
        try:
            return cls(near, far)
        except InputError as exc:
            raise InputError(exc.reason, field=field) from None

    def describe(self) -> str:
        return f"{self.near:g}-{self.far:g} m"


DEFAULT_DEPTH_RANGE = DepthRange(0.05, 5.0)


def valid_depth(depth: np.ndarray, depth_range: DepthRange = DEFAULT_DEPTH_RANGE) -> np.ndarray:
    """Boolean mask of the measured pixels: finite depth inside ``depth_range``."""
    d = np.asarray(depth)
    with np.errstate(invalid="ignore"):
        return np.isfinite(d) & (d >= depth_range.near) & (d <= depth_range.far)


@dataclass(frozen=True)
class DepthCheck:
    """What a depth image holds: its valid mask and why the other pixels are invalid."""

    valid: np.ndarray  # (h, w) bool
    depth_range: DepthRange
    holes: int  # 0 or not finite (NaN, infinity)
    negative: int
    near: int  # 0 < depth < near
    far: int  # depth > far (finite)
    #: median of the finite values beyond ``far`` (millimetres read as metres?), else None
    far_median: float | None = None

    @property
    def pixels(self) -> int:
        return int(self.valid.size)

    @property
    def valid_count(self) -> int:
        return int(np.count_nonzero(self.valid))

    @property
    def valid_share(self) -> float:
        return self.valid_count / self.pixels if self.pixels else 0.0

    def describe(self) -> str:
        """One line: the valid share and the count of each kind of invalid pixel."""
        kinds = [
            (self.holes, "holes (0 or NaN)"),
            (self.negative, "negative"),
            (self.near, f"nearer than {self.depth_range.near:g} m"),
            (self.far, f"farther than {self.depth_range.far:g} m"),
        ]
        rest = ", ".join(f"{n} {what}" for n, what in kinds if n)
        text = f"{self.valid_count} of {self.pixels} pixels in {self.depth_range.describe()}"
        return f"{text}, {rest}" if rest else text

    def problem(self) -> str | None:
        """Why this is not a usable depth image (bad input), or None."""
        if self.negative > NEGATIVE_TOLERANCE * self.pixels:
            return (
                f"{self.negative} of {self.pixels} pixels have negative depth: depth is the "
                "distance in front of the camera along its optical axis, in metres (an image "
                "of negative values follows another convention, such as OpenGL's camera "
                "looking down -z)"
            )
        if self.valid_count == 0:
            text = f"no valid depth: {self.describe()}"
            r, m = self.depth_range, self.far_median
            if m is not None and r.near <= m / 1000 <= r.far:
                text += f" (values near {m:.0f} look like millimetres: depth must be in metres)"
            return text
        return None

    def as_dict(self) -> dict:
        return {
            "pixels": self.pixels,
            "valid": self.valid_count,
            "holes": self.holes,
            "negative": self.negative,
            "near": self.near,
            "far": self.far,
            "range": [self.depth_range.near, self.depth_range.far],
        }


def check_depth(depth: np.ndarray, depth_range: DepthRange = DEFAULT_DEPTH_RANGE) -> DepthCheck:
    """The :class:`DepthCheck` of a depth image (metres)."""
    d = np.asarray(depth, dtype=np.float64)
    finite = np.isfinite(d)
    f = np.where(finite, d, 0.0)
    far = finite & (f > depth_range.far)
    return DepthCheck(
        valid=valid_depth(d, depth_range),
        depth_range=depth_range,
        holes=int(np.count_nonzero(~finite | (f == 0))),
        negative=int(np.count_nonzero(f < 0)),
        near=int(np.count_nonzero((f > 0) & (f < depth_range.near))),
        far=int(np.count_nonzero(far)),
        far_median=float(np.median(d[far])) if far.any() else None,
    )


def fill_invalid(depth: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """The depth with every invalid pixel set to the depth of its nearest valid pixel (see
    the module docstring); all zeros when no pixel is valid."""
    d = np.asarray(depth, dtype=np.float32)
    if valid.all():
        return d
    if not valid.any():
        return np.zeros_like(d)
    from scipy.ndimage import distance_transform_edt

    rows, cols = distance_transform_edt(~valid, return_distances=False, return_indices=True)
    return d[rows, cols].astype(np.float32)


def fill_invalid_depth(
    depth: np.ndarray, depth_range: DepthRange = DEFAULT_DEPTH_RANGE
) -> np.ndarray:
    """:func:`fill_invalid` over the pixels outside :func:`valid_depth`."""
    return fill_invalid(depth, valid_depth(depth, depth_range))


def valid_share(rect: GraspRect, valid: np.ndarray) -> float:
    """Share of the rectangle's pixels inside the image that are valid (1 px sampling);
    0 when none is inside."""
    along = np.arange(-rect.width / 2, rect.width / 2 + 0.5, 1.0)
    across = np.arange(-rect.height / 2, rect.height / 2 + 0.5, 1.0)
    a, b = np.meshgrid(along, across)
    d, n = rect.direction, rect.normal
    us = np.round(rect.x + a * d[0] + b * n[0]).astype(int).ravel()
    vs = np.round(rect.y + a * d[1] + b * n[1]).astype(int).ravel()
    h, w = valid.shape
    inside = (us >= 0) & (us < w) & (vs >= 0) & (vs < h)
    if not inside.any():
        return 0.0
    return float(np.mean(valid[vs[inside], us[inside]]))


def on_valid_depth(rect: GraspRect, valid: np.ndarray) -> bool:
    """Whether a grasp stands on measured depth: its centre pixel is valid and at least
    :data:`MIN_VALID_SHARE` of its rectangle is."""
    r, c = int(round(rect.y)), int(round(rect.x))
    h, w = valid.shape
    if not (0 <= r < h and 0 <= c < w and valid[r, c]):
        return False
    return valid_share(rect, valid) >= MIN_VALID_SHARE
