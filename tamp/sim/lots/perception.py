"""Perception: what the wrist camera shows, as the LOTS controller and the grasp skill need it.

The paper detects objects with YOLO in the RGB image; here the camera's *label image*
stands in for the detector: every pixel carries the id of the body it shows (Drake's
`RgbdSensor`), and a fixed map from those ids to object classes plays the role of the
detector's class output. What the controller receives is only what a detector would give:
per class, the instances in view (pixel area, centroid, depth), never a plant pose.

Counting (Zhou et al. §III-B: the observed state is the count per class of the visible
workspace): an instance counts when at least ``min_pixels`` of its pixels lie farther than
``hand_depth`` (0.12 m) from the camera (nearer pixels are in the gripper). For a grasp, the target
(the instance of the requested class tracked so far, else the one nearest the image centre)
comes with a square crop of colour, depth and its mask around it: the grasp network's input.

Rendering is the budget (~15-20 ms per image kind at 320x180 on 2 cores): the sensor renders
only when an output port is evaluated, and `Perception` evaluates the image inputs only in
its periodic update and only when a new `ViewRequest` id arrives; the colour image only when
the request asks for it (grasping). ``frames`` in the state counts the renders.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, LeafSystem
from pydrake.systems.sensors import ImageDepth32F, ImageLabel16I, ImageRgba8U

from tamp.sim.lots.timing import Stopwatch


@dataclass(frozen=True)
class ViewRequest:
    """Ask for one view: id (0 = none), the workspace looked at, and what to find in it."""

    id: int = 0
    side: str = ""
    target: str | None = None  # class to find for a grasp (then the colour image is rendered)
    track: int | None = None  # instance tracked so far (its detector id)

    def __deepcopy__(self, memo: dict) -> ViewRequest:
        return self


@dataclass(frozen=True)
class Detection:
    """One instance in view: detector id (label), class, pixel area, centroid, median depth."""

    label: int
    cls: str
    pixels: int
    u: float
    v: float
    depth: float


@dataclass(frozen=True)
class TargetCrop:
    """The grasp network's input around the target: square crop (``origin`` = its top-left
    pixel in the full image) of colour, depth and the target's mask."""

    detection: Detection
    origin: tuple[int, int]
    rgb: np.ndarray
    depth: np.ndarray
    mask: np.ndarray


@dataclass(frozen=True)
class Observation:
    """The answer to view request ``id`` (rendered at sim ``time``)."""

    id: int = 0
    time: float = 0.0
    side: str = ""
    counts: dict[str, int] = field(default_factory=dict)
    detections: tuple[Detection, ...] = ()
    in_hand: tuple[str, ...] = ()  # classes seen closer than hand_depth (in the gripper)
    target: TargetCrop | None = None
    occupied: np.ndarray | None = None  # object pixels on the table (full image, bool)

    def __deepcopy__(self, memo: dict) -> Observation:
        return self  # immutable (arrays are read-only): Drake's state copies cost nothing


@dataclass(frozen=True)
class PerceptionState:
    """Last request served, its observation, and how many frames were rendered."""

    served: int = 0
    observation: Observation = field(default_factory=Observation)
    frames: int = 0
    render_kinds: int = 0  # image kinds evaluated in total (label, depth, colour)

    def __deepcopy__(self, memo: dict) -> PerceptionState:
        return self


def analyse(
    label: np.ndarray,
    depth: np.ndarray,
    classes: dict[int, str],
    *,
    min_pixels: int = 25,
    hand_depth: float = 0.12,
) -> tuple[dict[str, int], tuple[Detection, ...], tuple[str, ...], np.ndarray]:
    """(counts per class, detections, classes in the gripper, table-object mask) of one view."""
    valid = np.isfinite(depth) & (depth > 0)
    far = valid & (depth > hand_depth)
    near = valid & (depth <= hand_depth)
    detections = []
    in_hand = []
    occupied = np.zeros(label.shape, bool)
    for value in np.unique(label):
        cls = classes.get(int(value))
        if cls is None:
            continue
        pix = label == value
        on_table = pix & far
        n = int(on_table.sum())
        if int((pix & near).sum()) >= min_pixels:
            in_hand.append(cls)
        if n < min_pixels:
            continue
        occupied |= on_table
        vs, us = np.nonzero(on_table)
        detections.append(
            Detection(
                int(value),
                cls,
                n,
                float(us.mean()),
                float(vs.mean()),
                float(np.median(depth[on_table])),
            )
        )
    counts = dict(Counter(d.cls for d in detections))
    return counts, tuple(detections), tuple(sorted(in_hand)), occupied


def choose_target(
    detections: tuple[Detection, ...], cls: str, track: int | None, center: tuple[float, float]
) -> Detection | None:
    """The tracked instance if still in view, else the instance of ``cls`` nearest ``center``."""
    cands = [d for d in detections if d.cls == cls]
    for d in cands:
        if d.label == track:
            return d
    if not cands:
        return None
    return min(cands, key=lambda d: (d.u - center[0]) ** 2 + (d.v - center[1]) ** 2)


def crop_square(size: int, shape: tuple[int, int], u: float, v: float) -> tuple[int, int]:
    """Top-left corner of a ``size`` square centred on (u, v), shifted to lie in the image."""
    h, w = shape
    u0 = int(round(u - size / 2))
    v0 = int(round(v - size / 2))
    return min(max(u0, 0), w - size), min(max(v0, 0), h - size)


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, copy=True)
    a.flags.writeable = False
    return a


class Perception(LeafSystem):
    """Answers `ViewRequest`s from the wrist camera's label, depth (and colour) images."""

    def __init__(
        self,
        classes: dict[int, str],
        *,
        width: int,
        height: int,
        period: float,
        min_pixels: int = 25,
        hand_depth: float = 0.12,
    ):
        super().__init__()
        self.set_name("perception")
        self._classes = dict(classes)
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
        self.label_port = self.DeclareAbstractInputPort(
            "label_image", AbstractValue.Make(ImageLabel16I(width, height))
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

    def _calc_observation(self, context, output) -> None:
        output.set_value(self.state(context).observation)

    def _update(self, context, state) -> EventStatus:
        s: PerceptionState = context.get_abstract_state(self._state).get_value()
        req: ViewRequest = self.request_port.Eval(context)
        if req.id == 0 or req.id == s.served:
            return EventStatus.DidNothing()
        t0 = time.perf_counter()
        with self.render:
            label = self.label_port.Eval(context).data[..., 0]
            depth = self.depth_port.Eval(context).data[..., 0]
        self.render_seconds.append(time.perf_counter() - t0)
        kinds = 2
        with self.analysis:
            counts, dets, in_hand, occupied = analyse(
                label,
                depth,
                self._classes,
                min_pixels=self._min_pixels,
                hand_depth=self._hand_depth,
            )
            det = None
            if req.target is not None:
                det = choose_target(dets, req.target, req.track, self._center)
        target = None
        if det is not None:
            t0 = time.perf_counter()
            with self.render:
                rgb = self.color_port.Eval(context).data[..., :3]
            self.render_seconds[-1] += time.perf_counter() - t0
            kinds += 1
            with self.analysis:
                u0, v0 = crop_square(self._crop, label.shape, det.u, det.v)
                sl = (slice(v0, v0 + self._crop), slice(u0, u0 + self._crop))
                target = TargetCrop(
                    det,
                    (u0, v0),
                    _frozen(rgb[sl]),
                    _frozen(np.nan_to_num(depth[sl], nan=0.0, posinf=0.0)),
                    _frozen((label[sl] == det.label) & (depth[sl] > self._hand_depth)),
                )
        obs = Observation(
            req.id, context.get_time(), req.side, counts, dets, in_hand, target, _frozen(occupied)
        )
        state.get_mutable_abstract_state(self._state).set_value(
            PerceptionState(req.id, obs, s.frames + 1, s.render_kinds + kinds)
        )
        return EventStatus.Succeeded()
