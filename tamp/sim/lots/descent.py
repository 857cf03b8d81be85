"""The closed-loop descent's decisions (Zhou et al., IEEE T-ASE 2023, §IV-B, Fig. 6): fusing
grasp predictions over views, judging confidence, choosing where to look while uncertain,
and the hand's speed profile. Pure functions on small dataclasses (no Drake); the skill
controller (`tamp.sim.lots.skills`) calls them once per view and once per control tick.

**Fusion.** Each view contributes its best grasp on the target (`ViewGrasp`), stored
relative to the target's detected centre in that view (world frame, table plane), so that a
target that moves between views carries its grasps along. The last ``window`` views are fused
(`fuse`) over their largest agreeing cluster (grasps within `CLUSTER_RADIUS` and
`CLUSTER_ANGLE` of one of them: the network alternating between two good grasps, e.g. either
end of a handle, gives two modes, and the one more views support is fused); views without a
grasp on the target or outside the cluster count as views but add nothing; the estimate
is the quality-weighted mean of the grasp centres' offsets and of the closing angles
(doubled, as a parallel gripper is symmetric under a half turn); its spread is the weighted
RMS distance of the centres from the mean (m) and the circular standard deviation of the
closing angles (rad). The grasp executed is the window's member nearest the estimate (a real
prediction, with its own post-processing flags), moved with the target's centre to where
the latest view saw it.

**Confidence** (`confident`): at least ``min_views`` grasps in the window, spread within
``max_spread`` and ``max_angle_spread``, mean quality at least ``min_quality``. The paper
lets the arm "explore until it is confident enough" and fails the grasp when it reaches the
lowest point without one; it names the entropy of the predictions as the usual measure; the
spread of the fused grasp is ours, as the network's quality map is read only at its peaks.

**Exploration** (`explore_offset`): while uncertain the camera aims beside the target,
``shift`` away from the nearest other object in view (to reduce clutter in the crop), or,
with none near, at successive quarter turns round the target (new view directions).

**The final approach** (below the preset height, where the paper's hand "determines the
final predicted gripping posture and position based on the observations throughout the
trajectory" and grasps): the committed grasp is carried with the target's centre from the
view it was fused in to where the target is now (`carried`), so a target that slides or is
carried moves the goal (a fusion that turns into another grasp, `same_grasp`, is not
followed); the TCP is servoed to it (`approach_velocity` for the position, `turn_rate` for
the hand's yaw, the way round `wrist_turn` keeps in the wrist's range), and goes below the
gate height, under which the views no longer show the target, only once it is over the goal
and turned to its yaw (`approach_aim`). A view that shows the target cut by the image's edge
(`wholly_in_view`: the camera sits beside the TCP, so over the grasp a long target reaches
out of the image) is not read: the centre of its visible part is not the target's. Between
views and below the gate the target's centre is the latest view's carried on at the velocity
its recent views show (`predicted_centre`, `target_velocity`: a straight line through the
centres of the views that showed all of it, zero for a target that keeps still), for at most
`VELOCITY_HORIZON`, so below the gate the goal is frozen for a still target and goes on with
a sliding one. Closing the loop on the grasp while the hand comes down follows Morrison et
al.'s closed-loop grasping, the paper's multi-view reference [45].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from tamp.grasp.pinhole import camera_to_pixel
from tamp.grasp.rect import angle_difference, wrap_angle
from tamp.sim.lots.grasping import GraspCandidate

#: views agree (`fuse`) when their grasp centres (relative to the target) lie within this
#: distance and their closing angles within this angle of one view's: a long handle's grasps
#: at either end are two modes, fused apart, not one wide estimate
CLUSTER_RADIUS = 0.015
CLUSTER_ANGLE = math.radians(20.0)
#: other objects within this distance (m, table plane) of the target count as clutter that
#: the exploring camera moves away from
CLUTTER_RADIUS = 0.15
#: the final approach's TCP counts as below its gate (`approach_aim`) this far under it (m):
#: a hand held at the gate stays above it
GATE_TOLERANCE = 0.001
#: `target_velocity`: the views of this long (s) before the latest one, at least
#: `VELOCITY_VIEWS` of them, and the speed (m/s) under which the target counts as still
#: (the oracle's centres of a still body scatter about 1 mm from view to view: 3 views over
#: 0.4 s make about 3 mm/s of it)
VELOCITY_SPAN = 0.65
VELOCITY_VIEWS = 3
STILL_SPEED = 0.005
#: `predicted_centre` carries the latest view's centre on for at most this long (s): the
#: blind part of the approach takes about 0.85 s, and a velocity read wrong (a still
#: target's centre wandering as the camera moves) moves the goal for at most this long
VELOCITY_HORIZON = 1.5


@dataclass(frozen=True)
class ViewGrasp:
    """One view's best grasp on the target (None: the view had none) and the target's centre
    (world x, y) in that view."""

    grasp: GraspCandidate | None
    centre: tuple[float, float]

    @property
    def offset(self) -> tuple[float, float]:
        g = self.grasp
        return (g.x - self.centre[0], g.y - self.centre[1])


@dataclass(frozen=True)
class FusedGrasp:
    """The fused estimate over a window of views: the grasp to execute (the member nearest
    the mean, moved with the target), the mean offset from the target centre and closing
    angle, their spreads, the mean quality, and how many views had a grasp / none."""

    grasp: GraspCandidate
    offset: tuple[float, float]
    angle: float
    spread: float
    angle_spread: float
    quality: float
    views: int
    misses: int


@dataclass(frozen=True)
class Thresholds:
    """What `confident` requires (the scenario's ``grasp.descent`` fields)."""

    min_views: int
    max_spread: float  # m
    max_angle_spread: float  # rad
    min_quality: float

    @staticmethod
    def of(descent) -> Thresholds:
        """From a `tamp.sim.lots.scenario.DescentSettings` (angles there in degrees)."""
        return Thresholds(
            descent.min_views,
            descent.max_spread,
            math.radians(descent.max_angle_spread),
            descent.min_quality,
        )


def fuse(
    window: Sequence[ViewGrasp],
    centre: tuple[float, float],
    radius: float | None = None,
    angle: float | None = None,
) -> FusedGrasp | None:
    """Fuse the views of ``window`` (module docstring) over their largest agreeing cluster
    (``radius``, ``angle``: default `CLUSTER_RADIUS`, `CLUSTER_ANGLE`); the executed grasp
    is placed on the target's present ``centre``. None when no view of the window has a
    grasp."""
    radius = CLUSTER_RADIUS if radius is None else radius
    angle = CLUSTER_ANGLE if angle is None else angle
    grasps = [v for v in window if v.grasp is not None]
    if not grasps:
        return None

    def near(a: ViewGrasp, b: ViewGrasp) -> bool:
        close = math.dist(a.offset, b.offset) <= radius
        return close and angle_difference(a.grasp.yaw, b.grasp.yaw) <= angle

    def support(v: ViewGrasp) -> tuple:
        group = [u for u in grasps if near(v, u)]
        # most views, then the most quality; the offset breaks ties by content, not order
        return (len(group), sum(u.grasp.quality for u in group), v.offset)

    seed = max(grasps, key=support)
    members = [u for u in grasps if near(seed, u)]
    w = np.array([max(v.grasp.quality, 1e-3) for v in members])
    off = np.array([v.offset for v in members])
    mean = (w[:, None] * off).sum(axis=0) / w.sum()
    two = np.array([2.0 * v.grasp.yaw for v in members])
    c, s = float((w * np.cos(two)).sum() / w.sum()), float((w * np.sin(two)).sum() / w.sum())
    r = min(math.hypot(c, s), 1.0)
    angle = wrap_angle(math.atan2(s, c) / 2.0)
    angle_spread = math.sqrt(-2.0 * math.log(r)) / 2.0 if r > 1e-12 else math.pi / 2
    spread = float(math.sqrt((w * ((off - mean) ** 2).sum(axis=1)).sum() / w.sum()))
    quality = float((w * [v.grasp.quality for v in members]).sum() / w.sum())

    def distance(v: ViewGrasp) -> float:
        dx, dy = np.subtract(v.offset, mean)
        return math.hypot(dx, dy) / 0.01 + angle_difference(v.grasp.yaw, angle) / 0.2

    best = min(members, key=distance)
    dx, dy = best.offset
    grasp = replace(best.grasp, x=centre[0] + dx, y=centre[1] + dy)
    return FusedGrasp(
        grasp,
        (float(mean[0]), float(mean[1])),
        angle,
        spread,
        float(angle_spread),
        quality,
        len(members),
        len(window) - len(members),
    )


def confident(fused: FusedGrasp | None, th: Thresholds) -> bool:
    """Whether the fused grasp is good enough to commit to (module docstring)."""
    return (
        fused is not None
        and fused.views >= th.min_views
        and fused.spread <= th.max_spread
        and fused.angle_spread <= th.max_angle_spread
        and fused.quality >= th.min_quality
    )


def explore_offset(
    target: tuple[float, float],
    others: Sequence[tuple[float, float]],
    k: int,
    shift: float,
) -> tuple[float, float]:
    """Where the exploring camera aims relative to the target (x, y offset, m): ``shift`` away
    from the nearest of ``others`` within `CLUTTER_RADIUS`, else a quarter turn further round
    the target at each exploring view ``k`` (0, 1, ...)."""
    if shift <= 0.0:
        return (0.0, 0.0)
    near = [o for o in others if 1e-6 < math.dist(o, target) < CLUTTER_RADIUS]
    if near:
        o = min(near, key=lambda p: math.dist(p, target))
        d = np.subtract(target, o)
        d = d / np.linalg.norm(d)
        return (float(shift * d[0]), float(shift * d[1]))
    a = math.pi / 4 + k * math.pi / 2
    return (shift * math.cos(a), shift * math.sin(a))


def approach_velocity(
    p: np.ndarray,
    goal: np.ndarray,
    v: np.ndarray,
    speed: float,
    accel: float,
    dt: float,
    lateral: float | None = None,
) -> np.ndarray:
    """The next TCP velocity (m/s) from ``p`` towards ``goal``: vertically at most ``speed``,
    horizontally at most ``lateral`` (default ``speed``: the exploring hand descends slowly
    but still moves sideways to its new viewpoint), each slow enough to stop at the goal
    within ``accel`` (the braking curve sqrt(2 a d)) and changed by at most ``accel * dt``
    from the present velocity ``v`` (a continuous move, no stops)."""
    p, goal, v = (np.asarray(a, float) for a in (p, goal, v))
    out = np.zeros(3)
    for axes, top in ((slice(0, 2), speed if lateral is None else lateral), (slice(2, 3), speed)):
        out[axes] = _toward(p[axes], goal[axes], v[axes], top, accel, dt)
    return out


def _toward(p, goal, v, speed: float, accel: float, dt: float) -> np.ndarray:
    d = goal - p
    dist = float(np.linalg.norm(d))
    if dist < 1e-9:
        want = np.zeros_like(d)
    else:
        # the braking curve, less one step's worth so the velocity reaches zero at the goal
        mag = min(speed, max(math.sqrt(2.0 * accel * dist) - accel * dt, 0.0), dist / dt)
        want = d / dist * mag
    dv = want - v
    n = float(np.linalg.norm(dv))
    if n > accel * dt:
        dv = dv * (accel * dt / n)
    return v + dv


def carried(
    grasp: GraspCandidate, then: tuple[float, float], now: tuple[float, float]
) -> GraspCandidate:
    """``grasp``, fused when the target's centre was at ``then``, moved with the target to
    its centre ``now`` (world x, y): what the hand goes to when the target has slid."""
    return replace(grasp, x=grasp.x + (now[0] - then[0]), y=grasp.y + (now[1] - then[1]))


def turn_rate(error: float, w: float, speed: float, accel: float, dt: float) -> float:
    """The hand's next yaw rate (rad/s) to turn by ``error`` (rad, signed: the caller chooses
    the way round, `wrist_turn`): at most ``speed``, slow enough to stop there within
    ``accel`` and changed by at most ``accel * dt`` from the present rate ``w``
    (`approach_velocity` for one angle)."""
    return float(_toward(np.zeros(1), np.array([error]), np.array([w]), speed, accel, dt)[0])


def wrist_turn(yaw: float, goal: float, centred: float) -> float:
    """The signed turn (rad) from the hand's ``yaw`` to ``goal`` the way that never passes
    the yaw opposite ``centred`` (the yaw at which the wrist's last joint is mid-range,
    `tamp.sim.lots.kinematics.ArmKinematics.wrist_centred_yaw`): the wrist turns within its
    range, not the short way round into its limit."""
    return math.remainder(goal - centred, 2 * math.pi) - math.remainder(yaw - centred, 2 * math.pi)


def same_grasp(a: FusedGrasp, b: FusedGrasp) -> bool:
    """Whether two fused grasps are one grasp on the target: offsets from its centre within
    `CLUSTER_RADIUS` and closing angles within `CLUSTER_ANGLE` (`fuse`'s agreement). A
    square block has two grasps a quarter turn apart; the closed approach keeps to the one
    it started with."""
    close = math.dist(a.offset, b.offset) <= CLUSTER_RADIUS
    return close and angle_difference(a.grasp.yaw, b.grasp.yaw) <= CLUSTER_ANGLE


def approach_aim(
    p: np.ndarray,
    goal: np.ndarray,
    yaw_error: float,
    gate: float,
    reach: float,
    turn: float,
    seen: bool = True,
) -> np.ndarray:
    """Where the final approach's TCP heads from ``p``: the ``goal`` once the hand is within
    ``reach`` (m, horizontally) of it and ``turn`` (rad) of its yaw (``yaw_error``) with the
    latest view showing the target (``seen``), or already below the ``gate`` height; until
    then the goal held at the gate (the hand moves over the grasp and turns while the camera
    still sees the target, then goes straight down)."""
    p, goal = np.asarray(p, float), np.asarray(goal, float)
    near = float(np.linalg.norm(goal[:2] - p[:2])) <= reach
    over = seen and near and abs(yaw_error) <= turn
    if over or p[2] < gate - GATE_TOLERANCE or goal[2] >= gate:
        return goal
    return np.array([goal[0], goal[1], gate])


def target_velocity(
    seen: Sequence[tuple[float, float, float]],
    span: float = VELOCITY_SPAN,
    views: int = VELOCITY_VIEWS,
    still: float = STILL_SPEED,
) -> tuple[float, float]:
    """The target's velocity on the table (m/s, world x and y) from its centres ``seen``
    ((time, x, y) of the views that showed it, oldest first): the least-squares line through
    those within ``span`` seconds of the latest; (0, 0) with fewer than ``views`` of them or
    a speed under ``still``."""
    recent = [p for p in seen if p[0] >= seen[-1][0] - span] if seen else []
    if len(recent) < views:
        return (0.0, 0.0)
    a = np.asarray(recent, float)
    t = a[:, 0] - a[:, 0].mean()
    den = float((t * t).sum())
    if den <= 1e-12:
        return (0.0, 0.0)
    vx, vy = (float((t * (a[:, k] - a[:, k].mean())).sum() / den) for k in (1, 2))
    return (vx, vy) if math.hypot(vx, vy) >= still else (0.0, 0.0)


def wholly_in_view(
    points_C: np.ndarray,
    intrinsics: tuple[float, float, float, float],
    width: int,
    height: int,
    margin: float = 2.0,
) -> bool:
    """Whether every point of ``points_C`` (3 x N, camera frame: the target's outline as the
    attempt's widest view showed it, where the target is now) falls in front of the camera
    and at least ``margin`` pixels inside the ``width`` x ``height`` image."""
    p = np.asarray(points_C, float).reshape(3, -1)
    if not p.shape[1]:
        return True
    if np.any(p[2] <= 0.0):
        return False
    u, v = camera_to_pixel(p, intrinsics)
    lo = margin - 0.5
    return bool(
        np.all(u >= lo)
        and np.all(u <= width - 0.5 - margin)
        and np.all(v >= lo)
        and np.all(v <= height - 0.5 - margin)
    )


def predicted_centre(
    seen: Sequence[tuple[float, float, float, bool]],
    t: float,
    horizon: float = VELOCITY_HORIZON,
) -> tuple[float, float]:
    """The target's centre (world x, y) at time ``t`` from its views ``seen`` ((time, x, y,
    whole), oldest first; ``whole``: the view showed all of it, `wholly_in_view`): the
    latest view's centre, carried on at the `target_velocity` of the whole views for at most
    ``horizon`` seconds, and only when the latest view is whole: a cut view's centre is its
    visible part's, and a velocity through cut views is the camera's moving cut, not the
    target's motion."""
    t0, x, y, _ = seen[-1]
    vx, vy = seen_velocity(seen)
    dt = min(max(t - t0, 0.0), horizon)
    return (x + vx * dt, y + vy * dt)


def seen_velocity(seen: Sequence[tuple[float, float, float, bool]]) -> tuple[float, float]:
    """The velocity `predicted_centre` carries the latest centre on at: the
    `target_velocity` of the whole views of ``seen`` when the latest is whole, else none."""
    if not seen or not seen[-1][3]:
        return (0.0, 0.0)
    return target_velocity([(u, a, b) for u, a, b, w in seen if w])
