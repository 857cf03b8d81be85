"""Class-agnostic safety from depth: which depth points are foreign, how near they are, and how
fast and fine the monitor's frames must be (Zhou et al., T-ASE 2023, §IV-C, pre-collision
measures; speed and separation monitoring as in ISO/TS 15066 §5.5.4).

A depth point is *foreign* unless it is the table (a known plane), the gripper (the arm's own
collision boxes at its measured joint angles) or the held object (a box in the hand frame).
No label image, body index or plant pose of anything else is used: whatever else comes within
``hand_distance`` of the gripper or the held object stops the arm, whatever it is.

Rate and resolution from physics (`budget`, numbers for the cell's defaults):

- The gripper's stopping distance ``S_s``: the TCP at the skills' speed ``v_r`` (0.35 m/s)
  needs joint speeds ``J^+ v_r``; braking every joint at Franka's acceleration limits
  (``catalogue.ARM.max_acceleration``) in synchrony takes ``T_s = max_j |qdot_j| / a_j`` and
  covers ``v_r T_s / 2``. The worst TCP direction at the ready pose (along x, joints 2, 4
  and 6) gives ``T_s`` = 0.106 s and ``S_s`` = 18.5 mm.
- The hand's travel between frames: a hand at the person's speed ``v_h`` (1.2 m/s,
  ``catalogue.PERSON.speed``) can enter the band just after a frame; the separation closes at
  ``v_h + v_r`` for one frame period ``T`` plus the latency ``L`` from frame to hold.
- The measurement's uncertainty ``Z``: one depth pixel's footprint at the farthest range at
  which the gripper's band is watched (0.3 m): the nearest surface point can lie between
  samples.

A hand that stops anywhere in the band is never touched by the arm when
``(v_h + v_r)(T + L) + S_s + Z <= hand_distance``. With ``L`` = 0 in the simulation (the
frame is rendered and judged in the same update and the hold is the monitor's output at
once), ``T`` = 10 ms (100 Hz) and an 80 x 45 depth image (a quarter of the wrist camera's
320 x 180 per axis: 5.2 mm per pixel at 0.3 m) the sum is 15.5 + 18.5 + 5.2 = 39.2 mm of
the 50 mm band, leaving 7 ms for a real camera's latency. ISO/TS 15066's full protective
distance adds the hand's travel while the arm brakes, ``v_h T_s`` = 127 mm: no band of 5 cm
covers a hand that keeps coming at 1.2 m/s into a braking arm; the monitor guarantees that
the arm has stopped before it reaches a hand, not that a hand cannot reach a stopped arm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from pydrake.math import RigidTransform

from tamp.sim.core.camera import backproject, camera_config

#: points this close to the table's plane, the gripper's boxes or the held object's box are
#: taken as theirs (m): the depth render's precision plus the boxes' fit to the meshes
MARGIN = 0.005
#: the safety camera renders depth at 1/SCALE of the wrist camera's size per axis
SCALE = 4
#: background voxels (m): a point in a voxel of the static scene is not foreign
VOXEL = 0.01

Boxes = list[tuple[RigidTransform, np.ndarray]]  # (pose in world, half sizes)


def safety_camera_config(width: int, height: int, fov_y_deg: float, near: float, far: float):
    """The monitor's depth camera: the wrist camera's field of view at 1/`SCALE` of its size
    (only its depth port is ever evaluated, so only depth is rendered)."""
    return camera_config(
        name="safety_camera",
        width=width // SCALE,
        height=height // SCALE,
        fov_y_deg=fov_y_deg,
        near=near,
        far=far,
    )


def depth_points(
    depth: np.ndarray, intrinsics: tuple[float, float, float, float], X_WC: RigidTransform
) -> tuple[np.ndarray, int]:
    """World points (N x 3) of the pixels with a valid depth, and how many pixels are nearer
    than the camera's near plane (Drake renders those as 0: something is closer than any
    depth can be measured)."""
    too_close = int(np.count_nonzero(depth == 0))
    vs, us = np.nonzero(np.isfinite(depth) & (depth > 0))
    if us.size == 0:
        return np.zeros((0, 3)), too_close
    return backproject(us, vs, depth[vs, us], intrinsics, X_WC).T, too_close


def in_boxes(points: np.ndarray, boxes: Boxes, margin: float = 0.0) -> np.ndarray:
    """Which of ``points`` (N x 3, world) lie inside any box grown by ``margin``."""
    inside = np.zeros(len(points), bool)
    for X_WB, half in boxes:
        local = (points - X_WB.translation()) @ X_WB.rotation().matrix()
        inside |= np.all(np.abs(local) <= np.asarray(half) + margin, axis=1)
    return inside


def distance_to_boxes(points: np.ndarray, boxes: Boxes) -> float:
    """The smallest distance from ``points`` (N x 3, world) to the boxes (0 inside one)."""
    if len(points) == 0 or not boxes:
        return math.inf
    best = math.inf
    for X_WB, half in boxes:
        local = (points - X_WB.translation()) @ X_WB.rotation().matrix()
        d = np.linalg.norm(np.maximum(np.abs(local) - half, 0.0), axis=1)
        best = min(best, float(d.min()))
    return best


def voxel_keys(points: np.ndarray, size: float = VOXEL) -> np.ndarray:
    """One int64 key per point: its voxel of edge ``size`` (coordinates within +-10 km)."""
    ijk = np.floor(np.asarray(points) / size).astype(np.int64) + (1 << 20)
    return (ijk[:, 0] << 42) | (ijk[:, 1] << 21) | ijk[:, 2]


@dataclass(frozen=True)
class Scene:
    """What is known not to be foreign in one frame: the table's top (z, world), the gripper's
    boxes, the held object's boxes (empty when nothing is held) and the background's voxel
    keys (sorted; the static scene learnt while no person was in the cell)."""

    table_z: float
    gripper: Boxes
    held: Boxes = field(default_factory=list)
    background: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))


def foreign_points(points: np.ndarray, scene: Scene, margin: float = MARGIN) -> np.ndarray:
    """The points (M x 3) that are neither the table, the gripper, the held object nor the
    background."""
    if len(points) == 0:
        return points
    own = points[:, 2] <= scene.table_z + margin
    own |= in_boxes(points, scene.gripper, margin)
    own |= in_boxes(points, scene.held, margin)
    if len(scene.background):
        own |= np.isin(voxel_keys(points), scene.background, assume_unique=False)
    return points[~own]


def separation(points: np.ndarray, scene: Scene, too_close: int = 0) -> float:
    """The distance from the nearest foreign point to the gripper or the held object (inf:
    none); 0 when pixels are nearer than the near plane (nothing of the robot is)."""
    if too_close:
        return 0.0
    foreign = foreign_points(points, scene)
    return distance_to_boxes(foreign, [*scene.gripper, *scene.held])


def learn_background(background: np.ndarray, points: np.ndarray, scene: Scene) -> np.ndarray:
    """The background with the static points of a frame taken while no person is in the cell
    (table, gripper and held object excluded: they are subtracted by geometry)."""
    static = foreign_points(points, Scene(scene.table_z, scene.gripper, scene.held))
    return np.union1d(background, voxel_keys(static))


def learn_released(
    background: np.ndarray, points: np.ndarray, box: tuple[RigidTransform, np.ndarray]
) -> np.ndarray:
    """The background with the points inside the box of an object just let go (the robot put
    it there: it is not an intruder, though a person is present)."""
    inside = points[in_boxes(points, [box], MARGIN)]
    return np.union1d(background, voxel_keys(inside))


@dataclass(frozen=True)
class Budget:
    """The protective-separation budget of `budget` (m, s)."""

    stop_time: float  # T_s
    stop_distance: float  # S_s
    closing: float  # (v_h + v_r)(T + L)
    pixel: float  # Z
    band: float  # hand_distance

    @property
    def used(self) -> float:
        return self.closing + self.stop_distance + self.pixel


def stopping(qdot: np.ndarray, max_acceleration: np.ndarray, speed: float) -> tuple[float, float]:
    """(T_s, S_s): synchronous braking of joint speeds ``qdot`` at the joints' acceleration
    limits, and the distance the TCP moving at ``speed`` covers meanwhile (linear slow-down)."""
    t = float(np.max(np.abs(qdot) / np.asarray(max_acceleration)))
    return t, speed * t / 2


def worst_stop(q9: np.ndarray, speed: float) -> tuple[float, float]:
    """`stopping` for the TCP at ``speed`` along the worst of the six axis directions at the
    arm's positions ``q9`` (the arm's own model: `tamp.sim.lots.safety.GripperModel`)."""
    from pydrake.multibody.tree import JacobianWrtVariable

    from tamp.sim.lots.catalogue import ARM
    from tamp.sim.lots.safety import GripperModel

    g = GripperModel()
    g.set(q9)
    tcp = g.plant.GetFrameByName(ARM.tcp_frame)
    world = g.plant.world_frame()
    J = g.plant.CalcJacobianTranslationalVelocity(
        g.context, JacobianWrtVariable.kV, tcp, [0, 0, 0], world, world
    )[:, :7]
    pinv = np.linalg.pinv(J)
    return max(stopping(pinv @ (speed * d), ARM.max_acceleration, speed) for d in np.eye(3))


def budget(
    *,
    band: float = 0.05,
    hand_speed: float = 1.2,
    tcp_speed: float = 0.35,
    period: float = 0.01,
    latency: float = 0.0,
    fov_y_deg: float = 42.5,
    height: int = 45,
    watch_range: float = 0.3,
) -> tuple[Budget, float]:
    """The module docstring's budget at the ready pose, and the latency left (s)."""
    from tamp.sim.lots.catalogue import ARM, READY

    t_s, s_s = worst_stop(np.r_[READY, ARM.finger_max, ARM.finger_max], tcp_speed)
    pixel = watch_range * 2 * math.tan(math.radians(fov_y_deg) / 2) / height
    closing = (hand_speed + tcp_speed) * (period + latency)
    b = Budget(t_s, s_s, closing, pixel, band)
    return b, (band - b.used) / (hand_speed + tcp_speed)
