"""What a robot's camera saw, view by view, kept for the recording: the depth image as a
world-frame point cloud, where the camera was (its frustum) and, for a grasp's views, the
candidates the grasp planner drew from that view.

`ViewLog` sits beside `tamp.sim.core.perception.Perception` on the same ports (the depth
image perception reads, the skills' `ViewRequest`, perception's `Observation`) and at the
same period, so it reads each view's depth in the tick perception renders it: Drake's cache
hands it the same image, no second render (profiled on a pick: the log's 1,135 updates spent
5 ms in `Eval`, perception's renders 1.08 s). The camera pose is the request's (the robot's own
kinematics, what it believes), not the plant's. It is added only when a run is drawn in
Meshcat (`tamp.sim.core.recording.draw_views` turns the log into the recording's overlays);
nothing on a decision path reads it.

The geometry here (`view_points`, `frustum_segments`, `grasp_segments`, `visible_spans`) is
plain numpy, so that it can be tested without Drake's renderer.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import EventStatus, LeafSystem

from tamp.grasp.pinhole import pixel_to_camera
from tamp.sim.core.messages import Observation, TargetCrop
from tamp.sim.core.perception import ViewTap

#: every ``STRIDE``-th pixel in each direction goes into a view's cloud (320x180 -> 54x30)
STRIDE = 6
#: depth beyond this (m) is not drawn: the floor far below the table, the room
MAX_DEPTH = 1.5
#: the frustum is drawn out to this distance along the optical axis (m)
FRUSTUM_DEPTH = 0.3
#: the last view of a run stays on screen this long (s)
LAST_VIEW_SPAN = 0.5


@dataclass(frozen=True)
class ViewRecord:
    """One view: request ``id``, sim ``time`` it was rendered, the workspace looked at, the
    camera pose ``X_WC`` (4x4, the robot's kinematics), its depth as world points (N x 3)
    and, once perception answered, the grasp target's crop (None: not a grasp's view)."""

    id: int
    time: float
    side: str
    X_WC: np.ndarray
    points: np.ndarray
    target: TargetCrop | None = None

    def __deepcopy__(self, memo: dict) -> ViewRecord:
        return self


@dataclass(frozen=True)
class ViewLogState:
    """The records so far (never mutated: each update builds a new tuple), so Drake's copies
    of the state cost nothing however long the run."""

    records: tuple[ViewRecord, ...] = ()

    def __deepcopy__(self, memo: dict) -> ViewLogState:
        return self


def view_points(
    depth: np.ndarray,
    intrinsics: tuple[float, float, float, float],
    X_WC: RigidTransform,
    *,
    stride: int = STRIDE,
    max_depth: float = MAX_DEPTH,
) -> np.ndarray:
    """World points (N x 3, float32) of every ``stride``-th pixel of ``depth`` that holds a
    depth in (0, ``max_depth``]: the pinhole back-projection moved by ``X_WC``."""
    d = np.asarray(depth, float)[::stride, ::stride]
    vs, us = np.nonzero(np.isfinite(d) & (d > 0) & (d <= max_depth))
    if us.size == 0:
        return np.zeros((0, 3), np.float32)
    p_C = pixel_to_camera(us * stride, vs * stride, d[vs, us], intrinsics)
    return X_WC.multiply(p_C).T.astype(np.float32)


def frustum_segments(
    X_WC: np.ndarray,
    intrinsics: tuple[float, float, float, float],
    size: tuple[int, int],
    depth: float = FRUSTUM_DEPTH,
) -> tuple[np.ndarray, np.ndarray]:
    """(start, end), each 3 x 8: the four edges from the camera's centre to the image
    corners at ``depth`` along the optical axis and the four sides of that far rectangle."""
    width, height = size
    corners = [(0, 0), (width, 0), (width, height), (0, height)]
    us = np.array([c[0] for c in corners], float)
    vs = np.array([c[1] for c in corners], float)
    far_C = pixel_to_camera(us, vs, np.full(4, depth), intrinsics)
    X = np.asarray(X_WC, float)
    far = X[:3, :3] @ far_C + X[:3, 3:4]
    origin = np.repeat(X[:3, 3:4], 4, axis=1)
    start = np.hstack([origin, far])
    end = np.hstack([far, np.roll(far, -1, axis=1)])
    return start, end


def grasp_segments(grasps: Sequence) -> tuple[np.ndarray, np.ndarray]:
    """(start, end), each 3 x N: each world-frame top grasp (``x, y, z, yaw, width``, as
    `tamp.sim.lots.grasping.GraspCandidate`) as its closing line, the jaws' two ends."""
    if not grasps:
        return np.zeros((3, 0)), np.zeros((3, 0))
    c = np.array([[g.x, g.y, g.z] for g in grasps], float).T
    half = np.array([g.width / 2 for g in grasps], float)
    yaw = np.array([g.yaw for g in grasps], float)
    d = np.vstack([np.cos(yaw) * half, np.sin(yaw) * half, np.zeros_like(half)])
    return c - d, c + d


def visible_spans(times: Sequence[float], end: float) -> list[tuple[float, float]]:
    """When each view is on screen: from its own time to the next view's (the last one for
    `LAST_VIEW_SPAN`, at most until ``end``)."""
    ts = list(times)
    spans = []
    for k, t in enumerate(ts):
        stop = ts[k + 1] if k + 1 < len(ts) else min(t + LAST_VIEW_SPAN, max(end, t))
        spans.append((t, max(stop, t)))
    return spans


class ViewLog(LeafSystem):
    """Keeps a `ViewRecord` of every view perception serves (module docstring)."""

    def __init__(
        self,
        *,
        width: int,
        height: int,
        period: float,
        intrinsics: tuple[float, float, float, float],
        stride: int = STRIDE,
    ):
        super().__init__()
        self.set_name("view_log")
        self.size = (width, height)
        self.intrinsics = intrinsics
        self._stride = stride
        self.view = ViewTap.declare(self, width, height)
        self.depth_port = self.view.depth
        self.request_port = self.view.request
        self.observation_port = self.view.observation
        self._state = self.DeclareAbstractState(AbstractValue.Make(ViewLogState()))
        # the same period and offset as Perception's update: both read the depth in one tick
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)

    def records(self, context) -> tuple[ViewRecord, ...]:
        """The views logged so far, oldest first."""
        return context.get_abstract_state(self._state).get_value().records

    def _update(self, context, state) -> EventStatus:
        records: tuple[ViewRecord, ...] = self.records(context)
        obs: Observation = self.observation_port.Eval(context)
        new = records
        if records and obs.id == records[-1].id and obs.target is not records[-1].target:
            new = (*records[:-1], replace(records[-1], target=obs.target))
        logged = records[-1].id if records else 0
        req = self.view.serving(context)
        if req is not None and req.id != logged and req.camera_pose is not None:
            depth = self.depth_port.Eval(context).data[..., 0]
            pts = view_points(depth, self.intrinsics, req.camera_pose, stride=self._stride)
            X = req.camera_pose.GetAsMatrix4()
            new = (*new, ViewRecord(req.id, context.get_time(), req.side, X, pts))
        if new is records:
            return EventStatus.DidNothing()
        state.get_mutable_abstract_state(self._state).set_value(ViewLogState(new))
        return EventStatus.Succeeded()
