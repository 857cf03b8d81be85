"""Perception: what a robot's camera shows, as a detector would report it.

Every workcell with a camera uses it: the LOTS arm's wrist camera (the LOTS controller counts
per class, the grasp skill gets the target's crop) and the SMP-MRO youBot's mast camera (the
object pose estimator back-projects the detections). The cell injects what is its own: the map
from render labels to object classes (``classes``), the image size and period, the depth
below which pixels are in the gripper (``hand_depth``), the intrinsics (to place and track
what was seen), the workspaces' rectangles (``regions``), optionally a seeded noisy
detector (``noise``), and, with each `ViewRequest`, the name of the workspace looked at and
the camera's pose from its own kinematics. The messages are in `tamp.sim.core.messages`.

Detection. Zhou et al. (IEEE T-ASE 2023) detect objects with YOLO in the RGB image. The cell
chooses the source (``source``): the learned detector (`tamp.sim.core.detector`: colour and
depth in, no label input declared at all), or the camera's *label image* as a perfect
stand-in (`LabelOracle`, `detect`): every pixel carries the id of the body it shows (Drake's
`RgbdSensor`), and the fixed map from those ids to object classes plays the role of the
detector's class output. Either way each instance becomes an `ObjectDetection` (mask, class,
world points and centroid: `tamp.sim.core.instances.located`) cut to the pixels beyond the
gripper's region (`on_table`: the person's hand is no object), and nothing after this step
reads a label id. An ``unknown`` object (a shape the detector was not trained on) is
tracked, remembered and kept clear of, but never counted as a task class (`counted`). A
learned detector's view is read once more as a whole (`tamp.sim.core.view_parts`): an
object cut in two by an occluder is joined back into one, and an object the person's hand
touches (``CARRIED``) is tracked but neither counted nor remembered. With
``noise`` the view's detections first pass through the seeded noisy detector
(`tamp.sim.core.detection_noise.perturb`: misses, class swaps, mask jitter, fresh identities,
false positives), so robustness to perception errors is measured on its own axis.

Identity is perception's own (`tamp.sim.core.tracks`): each detection is associated with a
track of its class by 3-D distance within a gate; a `Detection`'s ``track`` is that track's
id. The grasp descent follows its target by track id (`choose_target`: the tracked instance
or none, never silently another one), occlusion memory keys on tracks, and the lift check
asks whether the target's track is still on the table. Without a camera pose (or intrinsics)
nothing can be placed in the world: detections then carry track 0 (no identity).

Counting (Zhou et al. §III-B: the observed state is the count per class of the visible
workspace): an instance counts when at least ``min_pixels`` of its pixels lie farther than
``hand_depth`` (0.12 m) from the camera and, when the cell gives the workspace's rectangle
(``regions``), its world centroid lies in it: a wide view also shows what lies beside the
workspace (an object that rolled off it, the other workspace's edge), which is seen (and
tracked) but neither counted nor remembered there. Nearer pixels are the gripper's region: when at
least ``min_pixels`` of them show something, an object is in hand (from depth alone), of the
class of the track the grasp picked (the request's ``track`` after a grasp, when that track
has left the table) or ``unknown``. For a grasp, the target comes with a square crop of
colour, depth and its mask around it: the grasp network's input.

Occlusion is not absence: an object the gripper holds can hang in front of a wrist camera
(the LOTS arm's sits 6.5 cm off the gripper's axis) and hide part of the workspace.
Perception therefore keeps, per workspace, what it last saw there (`Seen`: each instance's
track, class and world centroid). At a new view of that workspace, a remembered instance
that is not seen now is kept (counted, and reported as occluded) when its point is hidden:
out of the image, or covered by something nearer than it (the gripper, the held object), or
inside another detection's mask with the depth there still its own (merged into a
neighbour's detection: `merged_into_others`); one whose point lies in plain view is gone
(`recall`). A track taken into the gripper is
forgotten everywhere: it lies in no workspace.

One view is not a fact. A detection is counted and remembered only once its track has been
seen in `CONFIRM_VIEWS` views (tentative until then: a one-view false positive or class
swap never enters the count or the memory), and a remembered instance whose place a view
shows plainly without it is forgotten only after `FORGET_VIEWS` such views in a row (until
then it is still counted, reported with the occluded ones). The LOTS arm's `LookAt` takes
two views at its settled pose for this (`tamp.sim.lots.skills`).

Rendering is the budget (~15-20 ms per image kind at 320x180 on 2 cores): the sensor renders
only when an output port is evaluated, and `Perception` evaluates the image inputs only in
its periodic update and only when a new `ViewRequest` id arrives; the colour image only when
the request asks for it (grasping). ``frames`` in the state counts the renders.
"""

from __future__ import annotations

import dataclasses
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import EventStatus, LeafSystem
from pydrake.systems.sensors import ImageDepth32F, ImageLabel16I, ImageRgba8U

from tamp.grasp.pinhole import camera_to_pixel, pixel_to_camera
from tamp.sim.core.detection_noise import LEVELS, perturb
from tamp.sim.core.instances import ObjectDetection, located, world_heights
from tamp.sim.core.messages import Detection, Observation, Seen, TargetCrop, ViewRequest
from tamp.sim.core.stack_reading import StackModel, read_stack, remembered_in_columns
from tamp.sim.core.threads import torch_threads
from tamp.sim.core.timing import Stopwatch
from tamp.sim.core.tracks import Tracks, regate_for, update
from tamp.sim.core.view_parts import joined_fragments, touched_by_hand

#: a remembered point counts as covered where the image shows something this much nearer (m)
OCCLUSION_TOLERANCE = 0.02
#: half-size of the patch around a remembered point's pixel that is checked for cover (m)
OCCLUSION_WINDOW = 0.015
#: how far beyond a fixture's rim (m) pixels are still taken for the rim (depth noise, edges)
RIM_MARGIN = 0.004
#: a pixel shows the bare floor when its world height is within this of the floor's (m):
#: below the lowest object's top (a lying screw's is 8 mm up), above the renderer's depth
#: error and a mat's 2 mm
FLOOR_BAND = 0.005
#: a remembered object inside another's detection is still there when the view's depth at
#: its point is within this of the point's (m): its top is what the camera sees there; one
#: taken away leaves the surface below at least 1.2 cm farther (the thinnest object, the
#: wrench, is 12 mm high) (`merged_into_others`)
SURFACE_TOLERANCE = 0.008
#: the class reported in hand when the object there is not the grasp's tracked target
UNKNOWN = "unknown"
#: a remembered instance's footprint keeps one point per square this size (m)
FOOTPRINT_CELL = 0.005
#: a track is counted and remembered once it was seen in this many views (a look takes two):
#: what one view alone shows (a detector's false positive, a class swap) is held tentative
CONFIRM_VIEWS = 2
#: a remembered instance is forgotten after this many views in a row showed its place
#: plainly without it: one view's miss is not an absence
FORGET_VIEWS = 2


@dataclass(frozen=True)
class DetectorNoise:
    """The seeded noisy detector applied to every view (`tamp.sim.core.detection_noise`):
    its level (``low`` or ``high``) and the run's seed."""

    level: str
    seed: int

    def __post_init__(self) -> None:
        if self.level not in LEVELS:
            raise ValueError(f"unknown detector noise level {self.level!r} ({sorted(LEVELS)})")


@dataclass(frozen=True)
class Region:
    """A workspace's rectangle on the table (world x, y; m): a view of that workspace counts
    and remembers only the instances whose world centroid lies in it. What the cell knows of
    its fixtures there, for the learned detector: ``floor``, the height objects rest on
    when it is not the view's own lowest surface (a tray's floor; None: the detector finds
    the support in the view), and ``rim``, the (inner, outer) sides of a square wall round
    the rectangle's centre (a tray's walls), whose pixels are never an object's; ``above``,
    how far over the support a pixel must be to be an object's (None: the detector's default,
    `tamp.sim.core.instances.ABOVE_PLANE`; the SMP-MRO mast camera's far floor needs more)."""

    center: tuple[float, float]
    size: tuple[float, float]
    floor: float | None = None
    rim: tuple[float, float] | None = None
    above: float | None = None

    @property
    def base(self) -> float:
        """The height objects rest on here: the fixture's floor, else the table top (the
        cells' world z = 0)."""
        return 0.0 if self.floor is None else self.floor

    def contains(self, p) -> bool:
        return bool(
            abs(p[0] - self.center[0]) <= self.size[0] / 2
            and abs(p[1] - self.center[1]) <= self.size[1] / 2
        )

    def fixtures(self, depth: np.ndarray, intrinsics, X_WC) -> dict[str, Any]:
        """The learned detector's keyword arguments for a view of this region (`floor` as
        ``plane``, the pixels whose world point lies on the `rim` as ``exclude``, `above`):
        empty when the region has none of them."""
        out: dict[str, Any] = {}
        if self.floor is not None:
            out["plane"] = self.floor
        if self.above is not None:
            out["above"] = self.above
        if self.rim is not None:
            h, w = depth.shape
            vs, us = np.mgrid[0:h, 0:w]
            d = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan)
            p = X_WC.multiply(pixel_to_camera(us.ravel(), vs.ravel(), d.ravel(), intrinsics))
            r = np.maximum(np.abs(p[0] - self.center[0]), np.abs(p[1] - self.center[1]))
            inner, outer = self.rim
            with np.errstate(invalid="ignore"):
                out["exclude"] = (
                    (r >= inner / 2 - RIM_MARGIN) & (r <= outer / 2 + RIM_MARGIN)
                ).reshape(h, w)
        return out


@dataclass(frozen=True)
class PerceptionState:
    """Last request served, its observation, how many frames were rendered, what was last
    seen in each workspace, the tracker, and the track in the gripper (never mutated: every
    update builds new values)."""

    served: int = 0
    observation: Observation = field(default_factory=Observation)
    frames: int = 0
    render_kinds: int = 0  # image kinds evaluated in total (label, depth, colour)
    memory: dict[str, tuple[Seen, ...]] = field(default_factory=dict)
    tracks: Tracks = field(default_factory=Tracks)
    held: Seen | None = None  # the tracked object in the gripper (None: none, or unknown)

    def __deepcopy__(self, memo: dict) -> PerceptionState:
        return self


@dataclass(frozen=True)
class LabelOracle:
    """Drake's label image read as a perfect detector (the stand-in of the module
    docstring): ``classes`` maps each object body's render label to its class."""

    classes: dict[int, str]


class ImageDetector(Protocol):
    """What a learned detector gives `Perception` (`tamp.sim.core.detector.Detector`): the
    objects of one colour + depth view placed with the intrinsics and the camera pose
    (``known``: the workspace's fixtures, `Region.fixtures`)."""

    classes: tuple[str, ...]

    def detect(
        self, rgb: np.ndarray, depth: np.ndarray, intrinsics: Sequence[float], X_WC, **known
    ) -> list[ObjectDetection]: ...


#: what a learned detector reports that is no object on the table (never tracked or counted)
NOT_OBJECTS = ("hand",)
#: the mark (`ObjectDetection.extra`) of an object a person's hand touches: tracked, neither
#: counted nor remembered in a workspace (`tamp.sim.core.view_parts.touched_by_hand`)
CARRIED = "carried"


def on_table(
    found: list[ObjectDetection],
    depth: np.ndarray,
    intrinsics: Sequence[float] | None,
    X_WC,
    *,
    min_pixels: int = 25,
    hand_depth: float = 0.12,
) -> list[ObjectDetection]:
    """A learned detector's objects as perception counts them, by the label oracle's rules
    (`detect`): the person's hand dropped (`NOT_OBJECTS`: never an object, whatever decides
    safety) and what it touches marked `CARRIED` (`tamp.sim.core.view_parts`), each mask
    cut to its pixels farther than ``hand_depth`` (the gripper's region is the in-hand
    check's) and kept when at least ``min_pixels``; placed in the world when ``intrinsics``
    and ``X_WC`` are given."""
    hands = [d.mask for d in found if d.cls in NOT_OBJECTS]
    touched = touched_by_hand(found, hands, depth)
    depth = np.where(np.isfinite(depth), depth, 0.0)
    far = depth > hand_depth
    placed = intrinsics is not None and X_WC is not None
    out = []
    for d, carried in zip(found, touched, strict=True):
        if d.cls in NOT_OBJECTS:
            continue
        if carried:
            d = dataclasses.replace(d, extra={**d.extra, CARRIED: True})
        mask = d.mask & far
        if int(mask.sum()) < min_pixels:
            continue
        if placed and not (d.mask & ~far).any():  # placed by the detector, nothing cut
            out.append(d)
            continue
        where = located(mask, depth, intrinsics if placed else None, X_WC)
        if where is not None:
            out.append(dataclasses.replace(d, mask=mask, **where))
    return out


def detect(
    label: np.ndarray,
    depth: np.ndarray,
    classes: dict[int, str],
    *,
    min_pixels: int = 25,
    hand_depth: float = 0.12,
    intrinsics: Sequence[float] | None = None,
    X_WC=None,
) -> list[ObjectDetection]:
    """The instances on the table in one view, as a detector reports them: per object body
    of the label image (``classes``: its render labels' classes), its pixels farther than
    ``hand_depth``, when at least ``min_pixels``; placed in the world (points, centroid)
    when ``intrinsics`` and the camera pose ``X_WC`` are given (else no points and a NaN
    centroid). The only function that reads the label image (module docstring)."""
    depth = np.where(np.isfinite(depth), depth, 0.0)
    far = depth > hand_depth
    placed = intrinsics is not None and X_WC is not None
    out = []
    for value in np.unique(label):
        cls = classes.get(int(value))
        if cls is None:
            continue
        mask = (label == value) & far
        n = int(mask.sum())
        if n < min_pixels:
            continue
        where = located(mask, depth, intrinsics if placed else None, X_WC)
        if where is not None:  # always: a mask's pixels lie beyond hand_depth
            out.append(ObjectDetection(cls, 1.0, mask, **where))
    return out


def footprint(points: np.ndarray) -> tuple[tuple[float, float], ...]:
    """Where a detection lies on the table, thinned for memory: the centres of the
    `FOOTPRINT_CELL` squares its world points (3 x N) fall in, in (x, y) order. Runs on
    every detection of every view: the squares are one integer key each (a row-major
    index), whose 1-D unique is 20x faster than a unique over rows."""
    if points.size == 0:
        return ()
    c = np.floor(points[:2] / FOOTPRINT_CELL).astype(np.int64)
    x0, y0 = c[0].min(), c[1].min()
    rows = int(c[1].max() - y0) + 1
    keys = np.unique((c[0] - x0) * rows + (c[1] - y0))
    xs = ((keys // rows + x0 + 0.5) * FOOTPRINT_CELL).tolist()
    ys = ((keys % rows + y0 + 0.5) * FOOTPRINT_CELL).tolist()
    return tuple(zip(xs, ys, strict=True))


def counted(classes) -> dict[str, int]:
    """The observed state's counts (Zhou et al. §III-B) of a view's classes: per task class;
    an `UNKNOWN` object is seen (tracked, remembered, kept clear of) but never counted."""
    return dict(Counter(c for c in classes if c != UNKNOWN))


def gripper_region(depth: np.ndarray, hand_depth: float = 0.12) -> np.ndarray:
    """The pixels showing something nearer than ``hand_depth``: what the gripper holds
    (the fingers themselves are outside the wrist camera's view)."""
    return np.isfinite(depth) & (depth > 0) & (depth <= hand_depth)


def projected(
    point: tuple[float, float, float] | np.ndarray,
    X_WC: RigidTransform,
    intrinsics: tuple[float, float, float, float],
) -> tuple[int, int, float] | None:
    """World ``point`` in the view of a camera at ``X_WC``: its pixel (column, row, rounded)
    and its depth along the optical axis; None when it is behind the camera."""
    p_C = X_WC.inverse().multiply(np.asarray(point, float))
    if p_C[2] <= 0:
        return None
    u, v = camera_to_pixel(p_C, intrinsics)
    return int(round(u)), int(round(v)), float(p_C[2])


def hidden(
    point: tuple[float, float, float] | np.ndarray,
    depth: np.ndarray,
    X_WC: RigidTransform,
    intrinsics: tuple[float, float, float, float],
    *,
    tolerance: float = OCCLUSION_TOLERANCE,
    window: float = OCCLUSION_WINDOW,
) -> bool:
    """Whether the camera at ``X_WC`` cannot tell if anything is at world ``point``: the
    patch ``window`` around its projection is not all in the image (or the point is behind
    the camera), or a pixel of that patch shows something more than ``tolerance`` nearer
    than the point (the gripper or the object it holds, a hand). Depth 0 (nearer than the
    clipping plane) is near too."""
    where = projected(point, X_WC, intrinsics)
    if where is None:
        return True
    ui, vi, z = where
    h, w = depth.shape
    r = max(0, int(round(window * intrinsics[0] / z)))
    if not (r <= ui < w - r and r <= vi < h - r):  # the patch is not all in the image
        return True
    patch = depth[vi - r : vi + r + 1, ui - r : ui + r + 1]
    return bool(np.any(patch < z - tolerance))  # NaN compares False: no cover


def covering(
    point: tuple[float, float, float] | np.ndarray,
    masks: Sequence[np.ndarray],
    X_WC: RigidTransform,
    intrinsics: tuple[float, float, float, float],
) -> tuple[int, ...]:
    """The indices of the ``masks`` (one per detection of a view from ``X_WC``) that cover
    world ``point``'s pixel (none when it is behind the camera or out of the image)."""
    where = projected(point, X_WC, intrinsics)
    return () if where is None else _under(where[0], where[1], masks)


def _under(ui: int, vi: int, masks: Sequence[np.ndarray]) -> tuple[int, ...]:
    """The indices of the ``masks`` holding pixel (``ui``, ``vi``) (none out of the image)."""
    if not masks:
        return ()
    h, w = masks[0].shape
    if not (0 <= ui < w and 0 <= vi < h):
        return ()
    return tuple(k for k, m in enumerate(masks) if m[vi, ui])


def recall(
    memory: tuple[Seen, ...],
    now: tuple[Seen, ...],
    held: frozenset[int],
    depth: np.ndarray,
    X_WC: RigidTransform,
    intrinsics: tuple[float, float, float, float],
    *,
    merged: frozenset[int] = frozenset(),
    tolerance: float = OCCLUSION_TOLERANCE,
    window: float = OCCLUSION_WINDOW,
    forget: int = FORGET_VIEWS,
) -> tuple[tuple[Seen, ...], tuple[Seen, ...]]:
    """(what to remember of the workspace in view now, the remembered instances kept as
    occluded) after one view of it.

    ``memory``: what was last seen in this workspace; ``now``: this view's detections (their
    tracks, classes and world centroids); ``depth``: this view; ``held``: the tracks in the
    gripper; ``merged``: remembered tracks seen inside another detection's mask
    (`merged_into_others`). Every detection is remembered where it is seen now. A
    remembered track not detected now is kept, as occluded, when its point is `hidden` or
    it is ``merged`` (in view, but inside a neighbour's detection: not gone); when its
    point is in plain view it is kept one view less than ``forget`` in a row (its
    ``misses`` counted up), then gone; in the gripper it is gone at once.
    """
    seen = {d.track for d in now}
    occluded = []
    for m in memory:
        if m.track in seen or m.track in held:
            continue
        if m.track in merged or hidden(
            m.position, depth, X_WC, intrinsics, tolerance=tolerance, window=window
        ):
            occluded.append(m)
        elif m.misses + 1 < forget:  # not where it was: once may be the detector's miss
            occluded.append(dataclasses.replace(m, misses=m.misses + 1))
    return now + tuple(occluded), tuple(occluded)


def merged_into_others(
    memory: Sequence[Seen],
    ids: Sequence[int],
    masks: Sequence[np.ndarray],
    depth: np.ndarray,
    X_WC: RigidTransform,
    intrinsics: tuple[float, float, float, float],
    tolerance: float = SURFACE_TOLERANCE,
) -> frozenset[int]:
    """The remembered tracks not detected in this view (``ids``: the track of each
    detection, ``masks`` its mask) whose point lies under another detection's mask with the
    surface still there: the view's depth at its pixel within ``tolerance`` of the point's.
    Such an object is seen, inside a neighbour's detection (the learned detector merges a
    screw lying against the hammer, or names a whole tower as one), not gone; one taken
    away leaves the surface below it (the table, the part under it in a stack) farther."""
    out = set()
    h, w = depth.shape
    for m in memory:
        where = None if m.track in ids else projected(m.position, X_WC, intrinsics)
        if where is None:
            continue
        ui, vi, z = where
        if not any(ids[k] != m.track for k in _under(ui, vi, masks)):
            continue
        patch = depth[max(vi - 1, 0) : min(vi + 2, h), max(ui - 1, 0) : min(ui + 2, w)]
        patch = patch[np.isfinite(patch) & (patch > 0)]
        if patch.size and abs(float(np.median(patch)) - z) <= tolerance:
            out.add(m.track)
    return frozenset(out)


def choose_target(
    detections: tuple[Detection, ...], cls: str, track: int | None, center: tuple[float, float]
) -> Detection | None:
    """The target of a grasp view: with a ``track``, that track's detection or None when it
    is not in view (the target is lost: never another instance in its place); without one,
    the instance of ``cls`` nearest ``center``."""
    if track is not None:
        return next((d for d in detections if d.track == track), None)
    cands = [d for d in detections if d.cls == cls]
    if not cands:
        return None
    return min(cands, key=lambda d: (d.u - center[0]) ** 2 + (d.v - center[1]) ** 2)


def crop_square(size: int, shape: tuple[int, int], u: float, v: float) -> tuple[int, int]:
    """Top-left corner of a ``size`` square centred on (u, v), shifted to lie in the image."""
    h, w = shape
    u0 = int(round(u - size / 2))
    v0 = int(round(v - size / 2))
    return min(max(u0, 0), w - size), min(max(v0, 0), h - size)


@dataclass(frozen=True)
class ViewTap:
    """The inputs of a system that works in the ticks perception renders in (the depth
    safety camera, the recording's view log): a depth image, the skills' `ViewRequest` and
    perception's `Observation`. Declared in that system's ``__init__`` (`declare`); a
    periodic update of it on perception's grid sees, through `serving`, the request
    perception answers in the same tick."""

    depth: Any
    request: Any
    observation: Any

    @staticmethod
    def declare(system: LeafSystem, width: int, height: int) -> ViewTap:
        """Declare the three input ports on ``system`` (depth image ``width`` x ``height``)."""
        return ViewTap(
            system.DeclareAbstractInputPort(
                "depth_image", AbstractValue.Make(ImageDepth32F(width, height))
            ),
            system.DeclareAbstractInputPort("view_request", AbstractValue.Make(ViewRequest())),
            system.DeclareAbstractInputPort("observation", AbstractValue.Make(Observation())),
        )

    def serving(self, context) -> ViewRequest | None:
        """The request perception serves at this tick: asked for and not answered yet
        (perception's update answers it now, from the same context); None when there is
        none or the request input is not connected."""
        if not self.request.HasValue(context):
            return None
        req: ViewRequest = self.request.Eval(context)
        obs: Observation = self.observation.Eval(context)
        return req if req.id != 0 and req.id != obs.id else None


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, copy=True)
    a.flags.writeable = False
    return a


class Perception(LeafSystem):
    """Answers `ViewRequest`s from a camera's images (module docstring: what the cell
    injects through the arguments). ``source``: the `LabelOracle` (label and depth images,
    colour for grasps) or a learned `ImageDetector` (colour and depth only: no label input
    is declared); ``task_classes``: the classes a noisy detector may swap to (default: the
    oracle's classes); ``spans``: each class's length on the table (its footprint's
    diagonal), which bounds how far apart the tracker may take two views of one object to
    be (`tamp.sim.core.tracks.regate_for`; a class without one: `REGATE`) and how long two
    fragments of one object may be together (`tamp.sim.core.view_parts.joined_fragments`;
    a class without one is never joined); ``stack``: the
    stack the cell builds, whose columns a learned detector's views of its workspace are
    read by height (`tamp.sim.core.stack_reading`)."""

    def __init__(
        self,
        source: LabelOracle | ImageDetector,
        *,
        width: int,
        height: int,
        period: float,
        min_pixels: int = 25,
        hand_depth: float = 0.12,
        intrinsics: tuple[float, float, float, float] | None = None,
        noise: DetectorNoise | None = None,
        regions: dict[str, Region] | None = None,
        task_classes: Sequence[str] | None = None,
        spans: Mapping[str, float] | None = None,
        stack: StackModel | None = None,
    ):
        super().__init__()
        self.set_name("perception")
        self._source = source
        self._oracle = isinstance(source, LabelOracle)
        if task_classes is None:
            if not isinstance(source, LabelOracle):
                raise ValueError("a learned detector needs the cell's task_classes")
            task_classes = source.classes.values()
        if not self._oracle and intrinsics is None:
            raise ValueError("a learned detector needs the camera's intrinsics")
        #: the classes a noisy detector's swap or false positive may take
        self._task_classes = tuple(sorted(set(task_classes)))
        #: (fx, fy, cx, cy) of the depth image; None: place, track and remember nothing
        self._intrinsics = intrinsics
        self._noise = noise
        #: each workspace's rectangle on the table: what a view of it counts and remembers
        self._regions = dict(regions or {})
        #: the tracker's second-stage gate per class
        self._regate = {c: regate_for(x) for c, x in (spans or {}).items()}
        #: each class's length on the table: fragments within it may be one object
        self._spans = dict(spans or {})
        #: the stack the cell builds, read by its heights in a learned detector's views
        self._stack = stack
        self._min_pixels = min_pixels
        self._hand_depth = hand_depth
        self._center = ((width - 1) / 2, (height - 1) / 2)
        #: wall seconds of every render (measurement only; not simulation state)
        self.render_seconds: list[float] = []
        #: time spent rendering (image ports evaluated) and analysing views (the rest)
        self.render = Stopwatch()
        self.analysis = Stopwatch()
        self._crop = min(width, height)
        self.color_port = self.DeclareAbstractInputPort(
            "color_image", AbstractValue.Make(ImageRgba8U(width, height))
        )
        self.depth_port = self.DeclareAbstractInputPort(
            "depth_image", AbstractValue.Make(ImageDepth32F(width, height))
        )
        #: only the oracle reads a label image; a learned detector has no such input
        self.label_port = (
            self.DeclareAbstractInputPort(
                "label_image", AbstractValue.Make(ImageLabel16I(width, height))
            )
            if self._oracle
            else None
        )
        self.request_port = self.DeclareAbstractInputPort(
            "view_request", AbstractValue.Make(ViewRequest())
        )
        self._state = self.DeclareAbstractState(AbstractValue.Make(PerceptionState()))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        self.observation_port = self.DeclareAbstractOutputPort(
            "observation",
            lambda: AbstractValue.Make(Observation()),
            self._calc_observation,
            prerequisites_of_calc={self.abstract_state_ticket(self._state)},
        )

    def state(self, context) -> PerceptionState:
        return context.get_abstract_state(self._state).get_value()

    @property
    def noise(self) -> DetectorNoise | None:
        """The seeded noisy detector every view passes through (None: exact)."""
        return self._noise

    def _calc_observation(self, context, output) -> None:
        output.set_value(self.state(context).observation)

    def _update(self, context, state) -> EventStatus:
        s: PerceptionState = context.get_abstract_state(self._state).get_value()
        req: ViewRequest = self.request_port.Eval(context)
        if req.id == 0 or req.id == s.served:
            return EventStatus.DidNothing()
        t0 = time.perf_counter()
        rgb = None
        with self.render:
            if self.label_port is not None:
                image = self.label_port.Eval(context).data[..., 0]
            else:  # a learned detector reads colour in every view
                image = rgb = self.color_port.Eval(context).data[..., :3]
            depth = self.depth_port.Eval(context).data[..., 0]
        self.render_seconds.append(time.perf_counter() - t0)
        kinds = 2
        placed = req.camera_pose is not None and self._intrinsics is not None
        X_WC = req.camera_pose if placed else None
        with self.analysis:
            raw = self._detect(image, depth, req, X_WC)
            near = gripper_region(depth, self._hand_depth)
            holding = int(near.sum()) >= self._min_pixels
            tracks, ids = s.tracks, (0,) * len(raw)
            if placed:
                keep = {m.track for seen in s.memory.values() for m in seen}
                keep |= {req.track} if req.track is not None else set()
                observed = [(d.cls, d.centroid) for d in raw]
                clouds = [d.points for d in raw]
                t = context.get_time()
                # the lift's view (a track, no target): only the target's own surface counts
                firm = {req.track} if req.target is None and req.track is not None else set()
                masks = [d.mask for d in raw]
                under = {
                    k.id: covering(k.position, masks, X_WC, self._intrinsics)
                    for k in s.tracks.tracks
                }
                tracks, ids = update(
                    s.tracks,
                    observed,
                    t,
                    keep=keep,
                    points=clouds,
                    firm=firm,
                    under=under,
                    regate=self._regate,
                )
            dets = tuple(
                Detection(i, d.cls, d.pixels, d.u, d.v, d.depth)
                for i, d in zip(ids, raw, strict=True)
            )
            held = self._held(s, req, tracks, ids, holding)
            gone = frozenset({held.track}) if held is not None else frozenset()
            tracks = tracks.without(gone)
            in_hand = (held.cls,) if held is not None else (UNKNOWN,) if holding else ()
            occupied = np.zeros(depth.shape, bool)
            for d in raw:
                occupied |= d.mask
            # what lies in the workspace looked at (beside it: seen, not counted there)
            region = self._regions.get(req.side) if placed else None
            inside = [
                (region is None or region.contains(d.centroid)) and CARRIED not in d.extra
                for d in raw
            ]
            carried = frozenset(i for i, d in zip(ids, raw, strict=True) if CARRIED in d.extra)
            counts = counted(d.cls for d, ok in zip(dets, inside, strict=True) if ok)
            det = None
            if req.target is not None:
                det = choose_target(dets, req.target, req.track, self._center)
        target = None
        if det is not None:
            if rgb is None:
                t0 = time.perf_counter()
                with self.render:
                    rgb = self.color_port.Eval(context).data[..., :3]
                self.render_seconds[-1] += time.perf_counter() - t0
            kinds += 1
            with self.analysis:
                mask = raw[dets.index(det)].mask & (depth > self._hand_depth)
                u0, v0 = crop_square(self._crop, depth.shape, det.u, det.v)
                sl = (slice(v0, v0 + self._crop), slice(u0, u0 + self._crop))
                target = TargetCrop(
                    det,
                    (u0, v0),
                    _frozen(rgb[sl]),
                    _frozen(np.nan_to_num(depth[sl], nan=0.0, posinf=0.0)),
                    _frozen(mask[sl]),
                )
        floor = None
        if placed and region is not None and req.target is None:  # not a grasp's view
            with self.analysis:
                z = world_heights(depth, self._intrinsics, X_WC)
                with np.errstate(invalid="ignore"):
                    floor = (np.abs(z - region.base) < FLOOR_BAND) & ~near & ~occupied
                    # anything standing up from the floor is kept clear of, detected or
                    # not (class-agnostic, like safety): an object no detection covers
                    # (missed, or merged into another's) is no room for a place
                    occupied = occupied | ((z >= region.base + FLOOR_BAND) & ~near)
        memory, occluded = s.memory, ()
        if placed and req.side:
            with self.analysis:
                # what this view shows of the workspace, of tracks seen often enough to count
                sure = {k.id for k in tracks.tracks if k.hits >= CONFIRM_VIEWS}
                now = tuple(
                    Seen(i, d.cls, tuple(float(x) for x in d.centroid), footprint(d.points))
                    for i, d, ok in zip(ids, raw, inside, strict=True)
                    if ok and i in sure
                )
                merged = merged_into_others(
                    s.memory.get(req.side, ()),
                    ids,
                    masks,
                    depth,
                    X_WC,
                    self._intrinsics,
                )
                memory, occluded = self._remember(s.memory, req, depth, now, gone | carried, merged)
                if self._stack is not None and req.side == self._stack.side:
                    levels = [
                        (d.cls, d.centroid)
                        for d, ok in zip(raw, inside, strict=True)
                        if ok and "level" in d.extra
                    ]
                    same = remembered_in_columns(occluded, levels)
                    if same:  # a read level, remembered aside: one part, not two
                        occluded = tuple(m for m in occluded if m.track not in same)
                        memory = {
                            **memory,
                            req.side: tuple(m for m in memory[req.side] if m.track not in same),
                        }
                counts = counted(m.cls for m in (*now, *occluded))
        obs = Observation(
            req.id,
            context.get_time(),
            req.side,
            counts,
            dets,
            in_hand,
            target,
            _frozen(occupied),
            occluded,
            float(near.mean()) if holding else 0.0,
            None if floor is None else _frozen(floor),
            _frozen(near),
        )
        state.get_mutable_abstract_state(self._state).set_value(
            PerceptionState(req.id, obs, s.frames + 1, s.render_kinds + kinds, memory, tracks, held)
        )
        return EventStatus.Succeeded()

    def _detect(self, image, depth, req: ViewRequest, X_WC) -> list[ObjectDetection]:
        """This view's detections: the label image's instances (`detect`; ``image`` is the
        label image) or the learned detector's objects on the table (`on_table`; ``image``
        is the colour image), through the noisy detector when the cell asks for one (drawn
        from the run's seed and the view's request id: a seeded run sees the same errors
        every time)."""
        intrinsics = self._intrinsics if X_WC is not None else None
        kw = dict(min_pixels=self._min_pixels, hand_depth=self._hand_depth)
        if isinstance(self._source, LabelOracle):
            raw = detect(image, depth, self._source.classes, intrinsics=intrinsics, X_WC=X_WC, **kw)
        else:
            # unplaced (no camera pose): detected in the camera's frame, then not placed
            pose = req.camera_pose if req.camera_pose is not None else RigidTransform()
            region = self._regions.get(req.side)
            known = region.fixtures(depth, self._intrinsics, pose) if region else {}
            with torch_threads():  # one thread: campaigns run a simulation per core
                found = self._source.detect(image, depth, self._intrinsics, pose, **known)
            raw = on_table(found, depth, intrinsics, X_WC, **kw)
            if intrinsics is not None and self._spans:  # one object cut in two by an occluder
                raw = joined_fragments(raw, depth, self._spans, intrinsics, X_WC)
            stack = self._stack
            if stack is not None and intrinsics is not None and req.side == stack.side:
                where = self._regions.get(stack.side)
                raw = read_stack(
                    raw,
                    stack,
                    depth,
                    intrinsics,
                    X_WC,
                    base=where.base if where else 0.0,
                    inside=where.contains if where else None,
                    min_pixels=self._min_pixels,
                )
        if self._noise is None:
            return raw
        return perturb(
            raw,
            seed=self._noise.seed,
            frame=req.id,
            level=self._noise.level,
            classes=self._task_classes,
            depth=np.where(np.isfinite(depth), depth, 0.0),
            intrinsics=intrinsics,
            X_WC=X_WC,
        )

    @staticmethod
    def _held(
        s: PerceptionState, req: ViewRequest, tracks: Tracks, ids: tuple[int, ...], holding: bool
    ) -> Seen | None:
        """The tracked object in the gripper after this view: none when the gripper's region
        is empty; the one held before while it stays full; else the track the grasp picked
        (a request without a target but with a ``track``: the lift's view) when its points
        left the table (no detection of this view is associated with it). An object in
        the gripper that is none of these is in hand as ``unknown`` (returns None)."""
        if not holding:
            return None
        if s.held is not None:
            return s.held
        if req.target is not None or req.track is None or req.track in ids:
            return None
        t = tracks.get(req.track)
        return None if t is None else Seen(t.id, t.cls, t.position)

    def _remember(
        self,
        memory: dict[str, tuple[Seen, ...]],
        req: ViewRequest,
        depth: np.ndarray,
        now: tuple[Seen, ...],
        held: frozenset[int],
        merged: frozenset[int] = frozenset(),
    ) -> tuple[dict[str, tuple[Seen, ...]], tuple[Seen, ...]]:
        """The new memory of every workspace after a view of ``req.side`` (its detections
        ``now``, ``held``: tracks taken into the gripper, ``merged``: remembered tracks
        inside a neighbour's detection), and the occluded instances of that view. A track is
        in one place: one seen here or in the gripper is forgotten in the other workspaces."""
        here, occluded = recall(
            memory.get(req.side, ()),
            now,
            held,
            depth,
            req.camera_pose,
            self._intrinsics,
            merged=merged,
        )
        moved = held | {m.track for m in now}
        new = {
            side: tuple(m for m in seen if m.track not in moved)
            for side, seen in memory.items()
            if side != req.side
        }
        new[req.side] = here
        return new, occluded
