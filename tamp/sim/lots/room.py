"""Where `Place` can put a held object down: the floor its views saw bare (no simulation).

A wrist camera that carries an object sees past it only in part: the LOTS arm's camera sits
6.5 cm beside the gripper's axis, and a held hammer fills most of its image, so a workspace's
middle can stay hidden in every view from above it (what a person put there meanwhile with
it). `Room` keeps, on a raster of the workspace's floor (`RES`), which cells some view saw
bare (perception's ``floor`` pixels: world height at the floor's, from depth and the arm's
kinematics) and which hold something (object pixels taken down to the floor's plane, and
perception's remembered objects hidden now). A cell is *free* when seen bare and not
blocked; every other cell must be kept clear of.

`place` puts the held object's footprint (its top-view points round its centre, in the
hand's frame, measured from the grasp's views) at every candidate centre (`STEP` apart)
and hand yaw given, keeps those whose footprint lies inside the floor's edges (`EDGE`),
prefers, in a tray, those a margin (`WALL_MARGIN`) off its walls, and of them takes the one
farthest from every cell that is not free (a Euclidean distance transform of the raster:
the clearance of every footprint point is one look-up). With
``unseen_bare`` every unseen cell counts as bare: what another view could gain at most;
`next_look` says where a view from the same height would show most of the unseen floor
(the held object hangs at the same place in every image, so the camera moves sideways,
not round).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform
from scipy import ndimage

from tamp.grasp.pinhole import camera_to_pixel, pixel_to_camera
from tamp.sim.core.messages import Seen

#: the floor raster's cell (m)
RES = 0.005
#: spacing of the candidate centres (m)
STEP = 0.02
#: a footprint's points keep this far inside the floor's edges (m)
EDGE = 0.01
#: the room a footprint wants first from walls round the floor (a tray's), beyond `EDGE`
#: (m); past it, only the clearance from objects counts: a screw put as far from the hammer
#: as it could go, 2 cm from the tray's wall, went over the wall
WALL_MARGIN = 0.03
#: a remembered object that is hidden now blocks this radius round its centre (m)
HIDDEN_RADIUS = 0.03
#: ... and this far round each point of the footprint it was last seen with (m): about half
#: its thinning cell's diagonal (`tamp.sim.core.perception.FOOTPRINT_CELL`, 5 mm)
FOOTPRINT_MARGIN = 0.005
#: the camera's sideways shifts tried for another view of the floor (m; 8 directions each)
SHIFTS = (0.07, 0.13)


@dataclass(frozen=True)
class Room:
    """What the place's views showed of one workspace's floor (sides ``size`` round
    ``center``, at height ``floor``), cell by cell (`RES`): ``seen`` bare by some view,
    ``blocked`` by something seen or remembered there."""

    center: tuple[float, float]
    size: tuple[float, float]
    floor: float
    seen: np.ndarray
    blocked: np.ndarray

    @property
    def cells(self) -> np.ndarray:
        """World x, y of every cell's centre (ny x nx x 2)."""
        ny, nx = self.seen.shape
        xs = self.center[0] - self.size[0] / 2 + RES * (np.arange(nx) + 0.5)
        ys = self.center[1] - self.size[1] / 2 + RES * (np.arange(ny) + 0.5)
        return np.stack(np.meshgrid(xs, ys), axis=-1)

    def index(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(row, column, inside) of world points (... x 2) on the raster."""
        ny, nx = self.seen.shape
        j = np.floor((xy[..., 0] - self.center[0] + self.size[0] / 2) / RES).astype(int)
        i = np.floor((xy[..., 1] - self.center[1] + self.size[1] / 2) / RES).astype(int)
        inside = (i >= 0) & (i < ny) & (j >= 0) & (j < nx)
        return np.clip(i, 0, ny - 1), np.clip(j, 0, nx - 1), inside


def empty_room(center: tuple[float, float], size: tuple[float, float], floor: float) -> Room:
    """A room of a floor (sides ``size`` round ``center``) nothing has been seen of yet."""
    n = (max(int(round(size[1] / RES)), 1), max(int(round(size[0] / RES)), 1))
    return Room(tuple(center), tuple(size), floor, np.zeros(n, bool), np.zeros(n, bool))


def _pixels(points: np.ndarray, floor: float, X_WC: RigidTransform, intrinsics) -> tuple:
    """Pixel coordinates (u, v; rounded) of floor points (N x 2) in a camera at ``X_WC``,
    and which lie in front of it."""
    p_W = np.vstack([points.T, np.full(len(points), floor)])
    p_C = X_WC.inverse().multiply(p_W)
    front = p_C[2] > 1e-6
    z = np.where(front, p_C[2], 1.0)
    u, v = camera_to_pixel(np.vstack([p_C[:2], z]), intrinsics)
    return np.rint(u).astype(int), np.rint(v).astype(int), front


def _in_image(points: np.ndarray, floor: float, X_WC, intrinsics, mask: np.ndarray) -> tuple:
    """Which floor points fall in the image of ``mask``'s size, and ``mask`` there."""
    u, v, front = _pixels(points, floor, X_WC, intrinsics)
    h, w = mask.shape
    inside = front & (u >= 0) & (u < w) & (v >= 0) & (v < h)
    value = np.zeros(len(points), bool)
    value[inside] = mask[v[inside], u[inside]]
    return inside, value


def on_floor_plane(mask: np.ndarray, floor: float, X_WC: RigidTransform, intrinsics) -> np.ndarray:
    """The pixels of ``mask`` taken along their rays down to the floor's plane (K x 2): where
    the objects they show stand, as seen from above."""
    vs, us = np.nonzero(mask)
    if len(us) == 0:
        return np.zeros((0, 2))
    R, p = X_WC.rotation().matrix(), X_WC.translation()
    rays = R @ pixel_to_camera(us, vs, np.ones(len(us)), intrinsics)
    down = rays[2] < -1e-6
    s = (floor - p[2]) / np.where(down, rays[2], -1.0)
    return (p[:2, None] + rays[:2] * s)[:, down].T


def observed(
    room: Room,
    X_WC: RigidTransform,
    intrinsics,
    *,
    occupied: np.ndarray | None,
    floor: np.ndarray | None,
    avoid: Sequence[Seen] = (),
) -> Room:
    """``room`` with one more view: the cells this view saw bare join ``seen`` (all of them
    when the view has no ``floor`` mask: it is taken to show the whole floor); the cells its
    object pixels fall on, and, for each remembered object hidden now (``avoid``), those
    within `HIDDEN_RADIUS` of its centre and within `FOOTPRINT_MARGIN` of where it was seen
    lying (its footprint: a long one reaches far past a disc round its centre), join
    ``blocked``."""
    cells = room.cells.reshape(-1, 2)
    if floor is None:
        seen = np.ones(room.seen.shape, bool)
    else:
        _, bare = _in_image(cells, room.floor, X_WC, intrinsics, floor)
        seen = bare.reshape(room.seen.shape)
    blocked = room.blocked.copy()
    if occupied is not None and occupied.any():
        i, j, inside = room.index(on_floor_plane(occupied, room.floor, X_WC, intrinsics))
        blocked[i[inside], j[inside]] = True
    for m in avoid:
        x, y = m.position[:2]
        near = np.hypot(cells[:, 0] - x, cells[:, 1] - y) <= HIDDEN_RADIUS
        for fx, fy in m.footprint:
            near |= np.hypot(cells[:, 0] - fx, cells[:, 1] - fy) <= FOOTPRINT_MARGIN
        blocked |= near.reshape(blocked.shape)
    return Room(room.center, room.size, room.floor, room.seen | seen, blocked)


def clearance(room: Room, *, unseen_bare: bool = False) -> np.ndarray:
    """Every cell's distance (m) to the nearest cell that is not free (ny x nx; negative on
    such a cell, infinite when every cell is free); ``unseen_bare``: unseen cells count as
    free. The floor's edges are not in it: `place` keeps a footprint inside them apart."""
    free = ~room.blocked & (room.seen | unseen_bare)
    if free.all():
        return np.full(free.shape, np.inf)
    return ndimage.distance_transform_edt(free) * RES - RES / 2


@dataclass(frozen=True)
class Placement:
    """Where to put the held object: its centre (x, y), the hand's yaw and the footprint's
    clearance there (m; infinite when nothing limits it, negative when it overlaps)."""

    x: float
    y: float
    yaw: float
    clearance: float


def _rotated(shape: np.ndarray, yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return shape @ np.array([[c, s], [-s, c]])


def place(
    room: Room,
    shape: np.ndarray,
    yaws: Sequence[float],
    *,
    unseen_bare: bool = False,
    walls: bool = False,
) -> Placement:
    """The centre (every `STEP` over the floor) and hand yaw of ``yaws`` whose footprint
    (``shape``: K x 2 points round the object's centre in the hand's frame) lies inside the
    floor, at least `EDGE` from its edges; of those (``walls``: the floor's edges are walls,
    a tray's) the ones `WALL_MARGIN` farther inside (or as near it as any), then the largest
    clearance (the least of its points' `clearance`: farthest from everything to keep clear
    of); among equals the one farthest inside the edges, and the first yaw. When no
    footprint fits inside, the one whose clearance or edge distance is least bad.
    ``unseen_bare``: `clearance`'s."""
    D = clearance(room, unseen_bare=unseen_bare)
    k = max(int(round(STEP / RES)), 1)
    centres = room.cells[k // 2 :: k, k // 2 :: k].reshape(-1, 2)
    if len(centres) == 0:
        centres = np.array([room.center])
    half = np.asarray(room.size, float) / 2
    best, best_key = None, None
    for yaw in yaws:
        pts = centres[:, None, :] + _rotated(np.asarray(shape, float), yaw)[None, :, :]
        i, j, _ = room.index(pts)
        edge = (half - np.abs(pts - np.asarray(room.center))).min(axis=2).min(axis=1)
        clear = np.where(edge >= 0, D[i, j].min(axis=1), -RES)
        fits = edge >= EDGE
        # inside the edges first, then off the walls, then the clearance, then the
        # distance to the edges
        off_walls = np.where(fits, np.minimum(edge - EDGE, WALL_MARGIN if walls else 0.0), 0.0)
        key = np.stack(
            [fits, off_walls, np.where(fits, clear, np.minimum(clear, edge)), edge], axis=1
        )
        b = int(np.lexsort(-key.T[::-1])[0])  # the largest key; the first among equals
        if best_key is None or tuple(key[b]) > best_key:
            best_key = tuple(key[b])
            best = Placement(
                float(centres[b, 0]), float(centres[b, 1]), float(yaw), float(clear[b])
            )
    assert best is not None
    return best


def next_look(
    room: Room,
    hidden: np.ndarray,
    X_WC: RigidTransform,
    intrinsics,
    shifts: Sequence[float] = SHIFTS,
) -> tuple[float, float] | None:
    """Where to put the camera (world x, y; same height and orientation as ``X_WC``) so that
    a view shows the most cells no view has seen yet (and nothing blocks): each sideways
    shift of ``shifts`` in 8 directions from over the floor's centre is scored by those
    cells that would fall in the image (of ``hidden``'s size) and outside its ``hidden``
    pixels (the held object hangs there in every view); the smaller shift wins a tie. None
    when no shift shows any."""
    todo = room.cells[~room.seen & ~room.blocked]
    if len(todo) == 0:
        return None
    p = np.array([room.center[0], room.center[1], X_WC.translation()[2]])
    best, where = 0, None
    for d in shifts:
        for k in range(8):
            a = k * np.pi / 4
            c = p + [d * np.cos(a), d * np.sin(a), 0.0]
            X = RigidTransform(X_WC.rotation(), c)
            inside, covered = _in_image(todo, room.floor, X, intrinsics, hidden)
            n = int((inside & ~covered).sum())
            if n > best:
                best, where = n, (float(c[0]), float(c[1]))
    return where


#: the footprint taken for an object whose extent no view measured (a scripted grasp): a
#: disc of this radius (m), about a catalogue tool's half width
UNMEASURED_RADIUS = 0.06


def disc(radius: float = UNMEASURED_RADIUS, n: int = 16) -> np.ndarray:
    """A round footprint of ``radius`` (``n`` points on its rim and its centre)."""
    a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.vstack([[0.0, 0.0], radius * np.column_stack([np.cos(a), np.sin(a)])])


def footprint(points: np.ndarray, yaw: float, most: int = 64, length: float = 0.0):
    """The footprint ``shape`` of `place` from an object's top-view points round its centre
    (N x 2, world axes): in the frame of a hand at ``yaw``, thinned to at most ``most``
    points (a deterministic stride), at least ``length`` long (`to_length`)."""
    pts = np.asarray(points, float).reshape(-1, 2)
    pts = to_length(pts[:: max(1, -(-len(pts) // most))], length)
    return _rotated(pts, -yaw) if len(pts) else np.zeros((1, 2))


#: points within this of a footprint's end (m, along its long axis) are that end's outline
END_BAND = 0.005


def to_length(points: np.ndarray, length: float) -> np.ndarray:
    """Top-view points (N x 2) of an object measured shorter than its catalogue ``length``
    (m) along their long axis, with each end's outline copied outwards by the shortfall.
    A view can lose a thin part (the screwdriver's 8 mm shaft: 0.167 m of its 0.17 m
    measured), and which end it lost is not known: both ends are lengthened, so a place
    keeps the whole object clear of its neighbours. The catalogue's length is what a robot
    knows of the classes it handles (`tamp.sim.lots.catalogue.Footprint`)."""
    if len(points) < 3 or length <= 0.0:
        return points
    centred = points - points.mean(axis=0)
    axis = np.linalg.svd(centred, full_matrices=False)[2][0]
    along = centred @ axis
    short = length - float(along.max() - along.min())
    if short <= END_BAND / 5:  # measured whole (to a millimetre)
        return points
    ends = (
        points[along <= along.min() + END_BAND] - short * axis,
        points[along >= along.max() - END_BAND] + short * axis,
    )
    return np.vstack([points, *ends])
