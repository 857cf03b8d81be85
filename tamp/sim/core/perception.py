"""Perception: what a robot's camera shows, as a detector would report it.

Every workcell with a camera uses it: the LOTS arm's wrist camera (the LOTS controller counts
per class, the grasp skill gets the target's crop) and the SMP-MRO youBot's mast camera (the
object pose estimator back-projects the detections). The cell injects what is its own: the map
from render labels to object classes (``classes``), the image size and period, the depth
below which pixels are in the gripper (``hand_depth``), the intrinsics (to remember what was
seen), and, with each `ViewRequest`, the name of the workspace looked at and the camera's pose
from its own kinematics. The messages are in `tamp.sim.core.messages`.

Zhou et al. (IEEE T-ASE 2023) detect objects with YOLO in the RGB image; here the camera's
*label image* stands in for the detector: every pixel carries the id of the body it shows
(Drake's `RgbdSensor`), and the fixed map from those ids to object classes plays the role of
the detector's class output. What a consumer receives is only what a detector would give:
per class, the instances in view (pixel area, centroid, depth), never a plant pose.

Counting (Zhou et al. §III-B: the observed state is the count per class of the visible
workspace): an instance counts when at least ``min_pixels`` of its pixels lie farther than
``hand_depth`` (0.12 m) from the camera (nearer pixels are in the gripper). For a grasp, the
target (the instance of the requested class tracked so far, else the one nearest the image
centre) comes with a square crop of colour, depth and its mask around it: the grasp network's
input.

Occlusion is not absence: an object the gripper holds can hang in front of a wrist camera
(the LOTS arm's sits 6.5 cm off the gripper's axis) and hide part of the workspace.
Perception therefore keeps, per workspace, what it last saw there (`Seen`: each instance's
class and the world point of its centroid, back-projected through its depth, the intrinsics
and the camera pose given with the request). At a new view of that workspace, a remembered
instance that is not seen now is kept (counted, and reported as occluded) when its point is
hidden: out of the image, or covered by something nearer than it (the gripper, the held
object); one whose point lies in plain view is gone (`recall`). An instance seen in the
gripper is forgotten everywhere: it lies in no workspace.

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
from pydrake.math import RigidTransform
from pydrake.systems.framework import EventStatus, LeafSystem
from pydrake.systems.sensors import ImageDepth32F, ImageLabel16I, ImageRgba8U

from tamp.grasp.pinhole import camera_to_pixel
from tamp.sim.core.camera import backproject
from tamp.sim.core.messages import Detection, Observation, Seen, TargetCrop, ViewRequest
from tamp.sim.core.timing import Stopwatch

#: a remembered point counts as covered where the image shows something this much nearer (m)
OCCLUSION_TOLERANCE = 0.02
#: half-size of the patch around a remembered point's pixel that is checked for cover (m)
OCCLUSION_WINDOW = 0.015


@dataclass(frozen=True)
class PerceptionState:
    """Last request served, its observation, how many frames were rendered, and what was
    last seen in each workspace (never mutated: every update builds a new mapping)."""

    served: int = 0
    observation: Observation = field(default_factory=Observation)
    frames: int = 0
    render_kinds: int = 0  # image kinds evaluated in total (label, depth, colour)
    memory: dict[str, tuple[Seen, ...]] = field(default_factory=dict)

    def __deepcopy__(self, memo: dict) -> PerceptionState:
        return self


@dataclass(frozen=True)
class ViewAnalysis:
    """What `analyse` finds in one view: per-class counts and detections of the objects on
    the table (beyond ``hand_depth``), the detector ids and classes of the objects in the
    gripper (`gripper_labels`), and the mask of table-object pixels."""

    counts: dict[str, int]
    detections: tuple[Detection, ...]
    held: frozenset[int]
    in_hand: tuple[str, ...]
    occupied: np.ndarray
    hand_cover: float = 0.0  # share of the image the held objects cover


def analyse(
    label: np.ndarray,
    depth: np.ndarray,
    classes: dict[int, str],
    *,
    min_pixels: int = 25,
    hand_depth: float = 0.12,
) -> ViewAnalysis:
    """What one view's label and depth images show (see `ViewAnalysis`)."""
    valid = np.isfinite(depth) & (depth > 0)
    far = valid & (depth > hand_depth)
    held = gripper_labels(label, depth, classes, min_pixels=min_pixels, hand_depth=hand_depth)
    detections = []
    occupied = np.zeros(label.shape, bool)
    for value in np.unique(label):
        cls = classes.get(int(value))
        if cls is None:
            continue
        on_table = (label == value) & far
        n = int(on_table.sum())
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
    in_hand = tuple(sorted(classes[v] for v in held))
    near = valid & ~far
    cover = float(np.mean(near & np.isin(label, list(held)))) if held else 0.0
    return ViewAnalysis(counts, tuple(detections), held, in_hand, occupied, cover)


def gripper_labels(
    label: np.ndarray,
    depth: np.ndarray,
    classes: dict[int, str],
    *,
    min_pixels: int = 25,
    hand_depth: float = 0.12,
) -> frozenset[int]:
    """Detector ids of the objects in the gripper: ``min_pixels`` or more of their pixels
    nearer than ``hand_depth``."""
    near = np.isfinite(depth) & (depth > 0) & (depth <= hand_depth)
    values, n = np.unique(label[near], return_counts=True)
    return frozenset(
        int(v) for v, k in zip(values, n, strict=True) if k >= min_pixels and int(v) in classes
    )


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
    p_C = X_WC.inverse().multiply(np.asarray(point, float))
    z = p_C[2]
    if z <= 0:
        return True
    u, v = camera_to_pixel(p_C, intrinsics)
    h, w = depth.shape
    r = max(0, int(round(window * intrinsics[0] / z)))
    ui, vi = int(round(u)), int(round(v))
    if not (r <= ui < w - r and r <= vi < h - r):  # the patch is not all in the image
        return True
    patch = depth[vi - r : vi + r + 1, ui - r : ui + r + 1]
    return bool(np.any(patch < z - tolerance))  # NaN compares False: no cover


def recall(
    memory: tuple[Seen, ...],
    detections: tuple[Detection, ...],
    held: frozenset[int],
    depth: np.ndarray,
    X_WC: RigidTransform,
    intrinsics: tuple[float, float, float, float],
    *,
    tolerance: float = OCCLUSION_TOLERANCE,
    window: float = OCCLUSION_WINDOW,
) -> tuple[tuple[Seen, ...], tuple[Seen, ...]]:
    """(what to remember of the workspace in view now, the remembered instances kept as
    occluded) after one view of it.

    ``memory``: what was last seen in this workspace; ``detections`` and ``depth``: this
    view; ``held``: detector ids seen in the gripper. Every detection is remembered where it
    is seen now. A remembered instance not detected now is kept, as occluded, when its point
    is `hidden`; it is gone when its point is in plain view or when it is in the gripper.
    Instances are matched by detector id (the label image's instance id, as the grasp's
    tracking uses it).
    """
    now = tuple(
        Seen(d.label, d.cls, tuple(backproject(d.u, d.v, d.depth, intrinsics, X_WC).tolist()))
        for d in detections
    )
    seen = {d.label for d in detections}
    occluded = tuple(
        m
        for m in memory
        if m.label not in seen
        and m.label not in held
        and hidden(m.position, depth, X_WC, intrinsics, tolerance=tolerance, window=window)
    )
    return now + occluded, occluded


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
    """Answers `ViewRequest`s from a camera's label, depth (and colour) images (module
    docstring: what the cell injects through the arguments)."""

    def __init__(
        self,
        classes: dict[int, str],
        *,
        width: int,
        height: int,
        period: float,
        min_pixels: int = 25,
        hand_depth: float = 0.12,
        intrinsics: tuple[float, float, float, float] | None = None,
    ):
        super().__init__()
        self.set_name("perception")
        self._classes = dict(classes)
        #: (fx, fy, cx, cy) of the depth image; None: remember nothing (no back-projection)
        self._intrinsics = intrinsics
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
            view = analyse(
                label,
                depth,
                self._classes,
                min_pixels=self._min_pixels,
                hand_depth=self._hand_depth,
            )
            counts, dets = view.counts, view.detections
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
        memory, occluded = s.memory, ()
        if req.camera_pose is not None and self._intrinsics is not None and req.side:
            with self.analysis:
                memory, occluded = self._remember(s.memory, req, depth, dets, view.held)
                counts = dict(Counter(d.cls for d in dets) + Counter(m.cls for m in occluded))
        obs = Observation(
            req.id,
            context.get_time(),
            req.side,
            counts,
            dets,
            view.in_hand,
            target,
            _frozen(view.occupied),
            occluded,
            view.hand_cover,
        )
        state.get_mutable_abstract_state(self._state).set_value(
            PerceptionState(req.id, obs, s.frames + 1, s.render_kinds + kinds, memory)
        )
        return EventStatus.Succeeded()

    def _remember(
        self,
        memory: dict[str, tuple[Seen, ...]],
        req: ViewRequest,
        depth: np.ndarray,
        dets: tuple[Detection, ...],
        held: frozenset[int],
    ) -> tuple[dict[str, tuple[Seen, ...]], tuple[Seen, ...]]:
        """The new memory of every workspace after a view of ``req.side`` (its detections
        ``dets``, ``held``: detector ids in the gripper), and the occluded instances of that
        view. An instance is in one place: one seen here or in the gripper is forgotten in the
        other workspaces."""
        here, occluded = recall(
            memory.get(req.side, ()), dets, held, depth, req.camera_pose, self._intrinsics
        )
        moved = held | {d.label for d in dets}
        new = {
            side: tuple(m for m in seen if m.label not in moved)
            for side, seen in memory.items()
            if side != req.side
        }
        new[req.side] = here
        return new, occluded
