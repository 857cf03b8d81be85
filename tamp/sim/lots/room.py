"""Where `Place` can put a held object down: the floor its views saw bare (no simulation).

A wrist camera that carries an object sees past it only in part: the LOTS arm's camera sits
6.5 cm beside the gripper's axis, and a held hammer fills most of its image, so a workspace's
middle can stay hidden in every view from above it (what a person put there meanwhile with
it). A spot is therefore chosen among the candidate spots (a grid over the workspace's floor,
inset by the object's reach) that a view *saw bare* (perception's ``floor`` pixels: world
height at the floor's, from depth and the arm's kinematics), farthest from everything it
must keep clear of: what the views showed on the floor (object pixels taken down to the
floor's plane), what perception remembers there but cannot see now, and every candidate no
view saw bare (something may lie there). `Room` gathers that evidence over the place's
views; when the best spot's clearance is below the object's reach, `next_look` says where a
view from the same height would show most of what is still unseen (the held object hangs
at the same place in every image, so the camera moves sideways, not round).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform

from tamp.grasp.pinhole import camera_to_pixel, pixel_to_camera

#: spacing of the candidate spots (m)
STEP = 0.02
#: the camera's sideways shifts tried for another view of the floor (m; 8 directions each)
SHIFTS = (0.07, 0.13)


@dataclass(frozen=True)
class Room:
    """What the place's views showed of one workspace's floor: the candidate spots ``grid``
    (N x 2, world x, y), which of them some view saw bare (``seen``, N bools), the floor
    plane's height ``floor`` and the points to keep clear of (``objects``, M x 2)."""

    grid: np.ndarray
    seen: np.ndarray
    floor: float
    objects: np.ndarray

    @property
    def unseen(self) -> np.ndarray:
        return self.grid[~self.seen]


def floor_grid(
    center: tuple[float, float], floor_size: tuple[float, float], margin: float, step: float = STEP
) -> np.ndarray:
    """Candidate spots every ``step`` over the floor (sides ``floor_size`` round ``center``),
    ``margin`` inside its edges (the centre alone when the margin leaves no room)."""
    cx, cy = center
    hx = max(floor_size[0] / 2 - margin, 0.0)
    hy = max(floor_size[1] / 2 - margin, 0.0)
    xs = cx + np.arange(-hx, hx + 1e-9, step)
    ys = cy + np.arange(-hy, hy + 1e-9, step)
    return np.array([[x, y] for x in xs for y in ys])


def empty_room(
    center: tuple[float, float],
    floor_size: tuple[float, float],
    floor: float,
    margin: float,
    step: float = STEP,
) -> Room:
    """A room nothing has been seen of yet."""
    grid = floor_grid(center, floor_size, margin, step)
    return Room(grid, np.zeros(len(grid), bool), floor, np.zeros((0, 2)))


def _pixels(points: np.ndarray, floor: float, X_WC: RigidTransform, intrinsics) -> tuple:
    """Pixel coordinates (u, v; rounded) of floor points (N x 2) in a camera at ``X_WC``,
    and which lie in front of it."""
    p_W = np.vstack([points.T, np.full(len(points), floor)])
    p_C = X_WC.inverse().multiply(p_W)
    front = p_C[2] > 1e-6
    z = np.where(front, p_C[2], 1.0)
    u, v = camera_to_pixel(np.vstack([p_C[:2], z]), intrinsics)
    return np.rint(u).astype(int), np.rint(v).astype(int), front


def on_floor_plane(mask: np.ndarray, floor: float, X_WC: RigidTransform, intrinsics) -> np.ndarray:
    """The pixels of ``mask`` taken along their rays down to the floor's plane (K x 2; at
    most about 2,000 of them): where the objects they show stand, as seen from above."""
    vs, us = np.nonzero(mask)
    if len(us) == 0:
        return np.zeros((0, 2))
    R, p = X_WC.rotation().matrix(), X_WC.translation()
    rays = R @ pixel_to_camera(us, vs, np.ones(len(us)), intrinsics)
    down = rays[2] < -1e-6
    s = (floor - p[2]) / np.where(down, rays[2], -1.0)
    pts = (p[:2, None] + rays[:2] * s)[:, down].T
    return pts[:: max(1, len(pts) // 2000)]


def observed(
    room: Room,
    X_WC: RigidTransform,
    intrinsics,
    *,
    occupied: np.ndarray | None,
    floor: np.ndarray | None,
    avoid: Sequence[tuple[float, float]] = (),
) -> Room:
    """``room`` with one more view: the candidates this view saw bare join ``seen`` (all of
    them when the view has no ``floor`` mask: the view is taken to show the whole floor),
    its object pixels and the hidden objects' centres (``avoid``) join ``objects``."""
    if floor is None:
        seen = np.ones(len(room.grid), bool)
    else:
        u, v, front = _pixels(room.grid, room.floor, X_WC, intrinsics)
        h, w = floor.shape
        inside = front & (u >= 0) & (u < w) & (v >= 0) & (v < h)
        seen = np.zeros(len(room.grid), bool)
        seen[inside] = floor[v[inside], u[inside]]
    objects = [room.objects]
    if occupied is not None and occupied.any():
        objects.append(on_floor_plane(occupied, room.floor, X_WC, intrinsics))
    if len(avoid):
        objects.append(np.asarray(avoid, float).reshape(-1, 2))
    return Room(room.grid, room.seen | seen, room.floor, np.vstack(objects))


def free_spot(room: Room, center: tuple[float, float]) -> tuple[tuple[float, float], float]:
    """The spot to put the object's centre on and its clearance (m): the candidate seen bare
    farthest from every object point and every candidate not seen bare (``center`` with an
    infinite clearance when the whole floor was seen bare and nothing lies on it; the best
    candidate by the objects alone, with clearance 0, when no candidate was seen bare)."""
    clear = np.vstack([room.objects, room.unseen])
    if len(clear) == 0:
        return (float(center[0]), float(center[1])), float("inf")
    d = np.min(np.linalg.norm(room.grid[:, None, :] - clear[None, :, :], axis=2), axis=1)
    if room.seen.any():
        i = int(np.flatnonzero(room.seen)[np.argmax(d[room.seen])])
        return (float(room.grid[i, 0]), float(room.grid[i, 1])), float(d[i])
    if len(room.objects) == 0:
        return (float(center[0]), float(center[1])), 0.0
    d = np.min(np.linalg.norm(room.grid[:, None, :] - room.objects[None, :, :], axis=2), axis=1)
    i = int(np.argmax(d))
    return (float(room.grid[i, 0]), float(room.grid[i, 1])), 0.0


def at_best(room: Room) -> float:
    """The clearance (m) the best candidate could have if every unseen one were bare: how
    much another view can gain at most."""
    if len(room.objects) == 0:
        return float("inf")
    d = np.min(np.linalg.norm(room.grid[:, None, :] - room.objects[None, :, :], axis=2), axis=1)
    return float(d.max())


def next_look(
    room: Room,
    hidden: np.ndarray,
    X_WC: RigidTransform,
    intrinsics,
    shifts: Sequence[float] = SHIFTS,
) -> tuple[float, float] | None:
    """Where to put the camera (world x, y; same height and orientation as ``X_WC``) so that
    a view shows the most candidates no view has seen yet: each sideways shift of ``shifts``
    in 8 directions is scored by the unseen candidates that would fall in the image (of
    ``hidden``'s size) and outside its ``hidden`` pixels (the held object hangs there in
    every view); the smaller
    shift wins a tie. None when no shift shows any."""
    todo = room.unseen
    if len(todo) == 0:
        return None
    h, w = hidden.shape
    p = X_WC.translation()
    best, where = 0, None
    for d in shifts:
        for k in range(8):
            a = k * np.pi / 4
            c = p + [d * np.cos(a), d * np.sin(a), 0.0]
            u, v, front = _pixels(todo, room.floor, RigidTransform(X_WC.rotation(), c), intrinsics)
            shown = front & (u >= 0) & (u < w) & (v >= 0) & (v < h)
            shown[shown] = ~hidden[v[shown], u[shown]]
            n = int(shown.sum())
            if n > best:
                best, where = n, (float(c[0]), float(c[1]))
    return where
