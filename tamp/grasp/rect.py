"""Oriented grasp rectangles in image pixels, their IoU and the rectangle metric (§V-A).

Convention (the one of the Cornell and Jacquard datasets as read by GG-CNN [49] and
GR-ConvNet [57]): a rectangle has a centre ``(x, y)`` in pixels (x = column, y = row), an
angle ``angle`` in radians in ``[-pi/2, pi/2)`` measured counter-clockwise on screen from the
image x-axis (the image y-axis points down, so the closing direction in pixel coordinates
is ``(cos angle, -sin angle)``), an opening ``width`` along that direction (the gripper
opening, ``w`` in Jacquard and the paper's W map) and a jaw size ``height`` across it.
An antipodal grasp is symmetric under a half turn, hence angles live modulo pi.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

#: A predicted grasp is correct when IoU > IOU_THRESHOLD with some ground truth ...
IOU_THRESHOLD = 0.25
#: ... and the angle difference (modulo pi) is at most ANGLE_THRESHOLD radians.
ANGLE_THRESHOLD = math.radians(30.0)


def wrap_angle(angle: float) -> float:
    """Fold an angle to ``[-pi/2, pi/2)`` (antipodal symmetry)."""
    return (angle + math.pi / 2) % math.pi - math.pi / 2


def angle_difference(a: float, b: float) -> float:
    """Smallest difference between two grasp angles modulo pi, in ``[0, pi/2]``."""
    d = abs(a - b) % math.pi
    return min(d, math.pi - d)


@dataclass(frozen=True, slots=True)
class GraspRect:
    """One oriented grasp rectangle in pixels (see the module docstring for the axes)."""

    x: float
    y: float
    angle: float
    width: float
    height: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "angle", wrap_angle(float(self.angle)))

    @property
    def direction(self) -> np.ndarray:
        """Unit closing direction in pixel coordinates (x right, y down)."""
        return np.array([math.cos(self.angle), -math.sin(self.angle)])

    @property
    def normal(self) -> np.ndarray:
        """Unit direction along the jaws (the closing direction turned by 90 degrees)."""
        return np.array([math.sin(self.angle), math.cos(self.angle)])

    def corners(self) -> np.ndarray:
        """4x2 array of (x, y) corners; edge 0-1 is the opening, edge 1-2 the jaw (Cornell)."""
        c = np.array([self.x, self.y])
        d = self.direction * self.width / 2
        n = self.normal * self.height / 2
        return np.stack([c - d - n, c + d - n, c + d + n, c - d + n])

    @staticmethod
    def from_corners(points: Sequence[Sequence[float]]) -> GraspRect:
        """Rectangle from four (x, y) corners in the Cornell order (edge 0-1 = opening)."""
        p = np.asarray(points, dtype=float)
        if p.shape != (4, 2):
            raise ValueError(f"expected 4 corners of (x, y), got shape {p.shape}")
        c = p.mean(axis=0)
        dx, dy = p[1] - p[0]
        angle = math.atan2(-dy, dx)
        width = float(np.hypot(dx, dy))
        height = float(np.hypot(*(p[2] - p[1])))
        return GraspRect(float(c[0]), float(c[1]), angle, width, height)

    def scaled(self, factor: float) -> GraspRect:
        """The same rectangle in an image resized by ``factor`` about the origin."""
        return GraspRect(
            self.x * factor, self.y * factor, self.angle, self.width * factor, self.height * factor
        )

    def transformed(self, matrix: np.ndarray) -> GraspRect:
        """Rectangle after a similarity transform ``p' = A p + t`` (2x3 ``matrix``)."""
        m = np.asarray(matrix, dtype=float)
        corners = self.corners() @ m[:, :2].T + m[:, 2]
        return GraspRect.from_corners(corners)

    def area(self) -> float:
        return self.width * self.height

    def iou(self, other: GraspRect) -> float:
        """Intersection over union of the two rectangles (exact convex clipping)."""
        inter = polygon_area(clip_convex(self.corners(), other.corners()))
        union = self.area() + other.area() - inter
        return inter / union if union > 0 else 0.0

    def matches(self, truth: GraspRect) -> bool:
        """The rectangle metric: IoU > 0.25 and angle difference <= 30 degrees."""
        if angle_difference(self.angle, truth.angle) > ANGLE_THRESHOLD + 1e-9:
            return False
        return self.iou(truth) > IOU_THRESHOLD


def polygon_area(poly: np.ndarray) -> float:
    """Area of a simple polygon (shoelace formula); 0 for fewer than three vertices."""
    if len(poly) < 3:
        return 0.0
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _orientation(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def clip_convex(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """Sutherland-Hodgman: the part of polygon ``subject`` inside convex polygon ``clip``."""
    sign = 1.0 if _orientation(clip) >= 0 else -1.0
    output = [tuple(p) for p in subject]
    n = len(clip)
    for i in range(n):
        a, b = clip[i], clip[(i + 1) % n]
        edge = b - a

        def inside(p: tuple[float, float], a=a, edge=edge) -> bool:
            return sign * (edge[0] * (p[1] - a[1]) - edge[1] * (p[0] - a[0])) >= -1e-12

        def cross_point(p, q, a=a, edge=edge):
            p, q = np.asarray(p), np.asarray(q)
            d = q - p
            denom = edge[0] * d[1] - edge[1] * d[0]
            t = (edge[1] * (p[0] - a[0]) - edge[0] * (p[1] - a[1])) / denom
            return tuple(p + t * d)

        inputs, output = output, []
        if not inputs:
            break
        prev = inputs[-1]
        for cur in inputs:
            if inside(cur):
                if not inside(prev):
                    output.append(cross_point(prev, cur))
                output.append(cur)
            elif inside(prev):
                output.append(cross_point(prev, cur))
            prev = cur
    return np.array(output, dtype=float).reshape(-1, 2)


def max_iou(pred: GraspRect, truths: Iterable[GraspRect]) -> float:
    """Best IoU of ``pred`` against any ground-truth rectangle (0 when there is none)."""
    return max((pred.iou(t) for t in truths), default=0.0)


def is_correct(preds: Sequence[GraspRect], truths: Sequence[GraspRect]) -> bool:
    """True when the first predicted grasp (the quality peak) matches some ground truth."""
    if not preds:
        return False
    return any(preds[0].matches(t) for t in truths)
