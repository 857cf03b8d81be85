"""Reference trajectories for the skills (no Drake import): base paths with velocity and
acceleration limits, smooth joint-space moves, and where the base stands to work on a place.

A `Segment` is what the `YouBotSkillController` keeps in its state: a start time, a duration, a
start and end configuration of the 10 robot joints, and a time-scaling profile; the
desired joint positions and velocities at any time come from `Segment.sample`.
Base motions follow a polyline (grid A* around the objects, shortened by line-of-sight)
with one trapezoidal speed profile along its arc length.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field

import numpy as np

from tamp.sim.smp.scenario import BaseLimits

STANDOFF = 0.40  # base centre to the object or area centre when picking or placing (m)
GRID = 0.05  # base planning grid (m)
CLEARANCE = 0.02  # extra gap kept between the base footprint and objects (m)


def wrap(a: float) -> float:
    """Angle in (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


@dataclass(frozen=True)
class Trapezoid:
    """Time scaling s(t) in [0, 1] with |s'| <= v, |s''| <= a (triangular when short)."""

    v: float
    a: float
    duration: float

    @staticmethod
    def of(v: float, a: float) -> Trapezoid:
        if v * v / a >= 1.0:  # never reaches full speed
            v = math.sqrt(a)
            return Trapezoid(v, a, 2.0 * v / a)
        return Trapezoid(v, a, 1.0 / v + v / a)

    def __call__(self, t: float) -> tuple[float, float]:
        v, a, T = self.v, self.a, self.duration
        t = min(max(t, 0.0), T)
        ta = v / a
        if t < ta:
            return 0.5 * a * t * t, a * t
        if t > T - ta:
            r = T - t
            return 1.0 - 0.5 * a * r * r, a * r
        return 0.5 * a * ta * ta + v * (t - ta), v


def quintic(t: float, T: float) -> tuple[float, float]:
    """Minimum-jerk time scaling s(t), s'(t) on [0, T] (zero velocity at both ends)."""
    if T <= 0.0:
        return 1.0, 0.0
    u = min(max(t / T, 0.0), 1.0)
    s = u**3 * (10 - 15 * u + 6 * u * u)
    ds = 30 * u * u * (1 - u) ** 2 / T
    return s, ds


@dataclass
class Segment:
    """One reference motion of all robot joints, from ``q0`` to ``q1``.

    ``kind`` "joint": minimum-jerk in joint space. "base": the base follows ``path``
    (planar waypoints, arc-length parametrised) with a trapezoidal profile while the yaw
    turns from q0 to q1 with the same scaling; the other joints hold ``q1``.
    """

    t0: float
    duration: float
    q0: np.ndarray
    q1: np.ndarray
    kind: str = "joint"
    path: np.ndarray | None = None
    profile: Trapezoid | None = None
    lengths: np.ndarray | None = field(default=None)

    @property
    def t_end(self) -> float:
        return self.t0 + self.duration

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        if self.kind == "joint":
            s, ds = quintic(t - self.t0, self.duration)
            return self.q0 + s * (self.q1 - self.q0), ds * (self.q1 - self.q0)
        assert self.profile is not None and self.path is not None and self.lengths is not None
        s, ds = self.profile(t - self.t0)
        q = self.q1.copy()
        v = np.zeros_like(q)
        total = self.lengths[-1]
        dist = s * total
        i = int(np.searchsorted(self.lengths, dist, side="right") - 1)
        i = min(max(i, 0), len(self.path) - 2)
        seg = self.lengths[i + 1] - self.lengths[i]
        d = self.path[i + 1] - self.path[i]
        u = 0.0 if seg <= 0 else (dist - self.lengths[i]) / seg
        q[0:2] = self.path[i] + u * d
        if seg > 0:
            v[0:2] = d / seg * ds * total
        q[2] = self.q0[2] + s * (self.q1[2] - self.q0[2])
        v[2] = ds * (self.q1[2] - self.q0[2])
        return q, v


def joint_segment(t0: float, q0: np.ndarray, q1: np.ndarray, speed: float, min_time: float):
    """A minimum-jerk move whose peak joint speed is about ``speed`` (rad/s or m/s)."""
    dq = float(np.max(np.abs(q1 - q0))) if len(q0) else 0.0
    duration = max(min_time, 1.875 * dq / speed)  # quintic peak speed = 1.875 dq / T
    return Segment(t0, duration, np.array(q0, float), np.array(q1, float))


def base_segment(
    t0: float, q0: np.ndarray, goal: tuple[float, float, float], path: list, lim: BaseLimits
) -> Segment:
    """Drive the base along ``path`` (planar waypoints from q0 to goal) and turn to goal yaw."""
    pts = np.array(path, float)
    lengths = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    total = float(lengths[-1])
    q1 = np.array(q0, float)
    q1[0], q1[1] = goal[0], goal[1]
    q1[2] = q0[2] + wrap(goal[2] - q0[2])
    dyaw = abs(q1[2] - q0[2])
    v = min(
        lim.max_speed / total if total > 1e-6 else math.inf,
        lim.max_yaw_rate / dyaw if dyaw > 1e-6 else math.inf,
    )
    a = min(
        lim.max_accel / total if total > 1e-6 else math.inf,
        lim.max_yaw_accel / dyaw if dyaw > 1e-6 else math.inf,
    )
    if not math.isfinite(v):
        return Segment(t0, 0.0, q1.copy(), q1, "joint")
    prof = Trapezoid.of(v, a)
    return Segment(t0, prof.duration, np.array(q0, float), q1, "base", pts, prof, lengths)


# -- where to stand, and how to get there -----------------------------------------------------


@dataclass(frozen=True)
class Disc:
    """A planar obstacle for the base: centre and radius (the object's footprint)."""

    x: float
    y: float
    r: float


def standoff_pose(
    target: tuple[float, float],
    robot: tuple[float, float],
    obstacles: list[Disc],
    workspace: tuple[float, float, float, float],
    footprint: float,
    *,
    distance: float = STANDOFF,
) -> tuple[float, float, float] | None:
    """A base pose ``distance`` from ``target`` facing it, clear of ``obstacles``.

    Candidates every 15 degrees around the target; the free one nearest the robot wins
    (ties: the direction the robot comes from). None when no side is free.
    """
    best, best_cost = None, math.inf
    tx, ty = target
    for k in range(24):
        ang = 2 * math.pi * k / 24
        x, y = tx + distance * math.cos(ang), ty + distance * math.sin(ang)
        xmin, xmax, ymin, ymax = workspace
        if not (
            xmin + footprint <= x <= xmax - footprint and ymin + footprint <= y <= ymax - footprint
        ):
            continue
        if any(math.hypot(x - o.x, y - o.y) < footprint + o.r + CLEARANCE for o in obstacles):
            continue
        cost = math.hypot(x - robot[0], y - robot[1])
        if cost < best_cost - 1e-9:
            best, best_cost = (x, y, math.atan2(ty - y, tx - x)), cost
    return best


class BasePlanner:
    """Grid A* for a disc-shaped base among disc obstacles, then line-of-sight shortcuts."""

    def __init__(self, workspace: tuple[float, float, float, float]):
        self.workspace = workspace
        xmin, xmax, ymin, ymax = workspace
        self.nx = int(math.ceil((xmax - xmin) / GRID)) + 1
        self.ny = int(math.ceil((ymax - ymin) / GRID)) + 1
        xs = xmin + GRID * np.arange(self.nx)
        ys = ymin + GRID * np.arange(self.ny)
        self.X, self.Y = np.meshgrid(xs, ys, indexing="ij")

    def _border(self, footprint: float) -> np.ndarray:
        xmin, xmax, ymin, ymax = self.workspace
        return (
            (self.X < xmin + footprint)
            | (self.X > xmax - footprint)
            | (self.Y < ymin + footprint)
            | (self.Y > ymax - footprint)
        )

    def cell(self, x: float, y: float) -> tuple[int, int]:
        i = int(round((x - self.workspace[0]) / GRID))
        j = int(round((y - self.workspace[2]) / GRID))
        return min(max(i, 0), self.nx - 1), min(max(j, 0), self.ny - 1)

    def _reaches(self, obstacles: list[Disc], footprint: float) -> list[tuple[float, float, float]]:
        return [(o.x, o.y, footprint + o.r + CLEARANCE) for o in obstacles]

    def _inside(self, p, footprint: float) -> bool:
        xmin, xmax, ymin, ymax = self.workspace
        return (
            xmin + footprint <= p[0] <= xmax - footprint
            and ymin + footprint <= p[1] <= ymax - footprint
        )

    def _escape(self, start, goal, discs, footprint: float):
        """Where to back away to when the base starts closer to objects than it may pass.

        After putting an object down the base stands 0.4 m from it, inside its inflated
        disc. Backing away radially only ever increases that distance (so the rotating
        corners stay clear); the result is the goal itself when the straight move there
        backs away (`_backs_away`), else a point outside every inflated disc, or None.
        """
        close = [(x, y, r) for x, y, r in discs if math.hypot(start[0] - x, start[1] - y) < r]
        if not close:
            return start
        others = [d for d in discs if d not in close]
        if self._backs_away(start, goal, close, others, footprint):
            return goal  # the way out is the way there: no detour past the goal
        dx = sum(
            (start[0] - x) / max(math.hypot(start[0] - x, start[1] - y), 1e-9) for x, y, _ in close
        )
        dy = sum(
            (start[1] - y) / max(math.hypot(start[0] - x, start[1] - y), 1e-9) for x, y, _ in close
        )
        base = math.atan2(dy, dx)
        found = []
        for turn in (0.0, 0.4, -0.4, 0.8, -0.8, 1.2, -1.2):  # |turn| < pi/2: never closer
            ang = base + turn
            for step in np.arange(0.05, 0.6, 0.05):
                p = (start[0] + step * math.cos(ang), start[1] + step * math.sin(ang))
                if not self._inside(p, footprint):
                    break
                clear = all(math.hypot(p[0] - x, p[1] - y) >= r + 0.01 for x, y, r in close)
                if clear and self._segment_free(others, start, p, footprint):
                    found.append(p)
                    break
        if found:  # the way out that leaves the base nearest its goal
            return min(found, key=lambda p: math.hypot(p[0] - goal[0], p[1] - goal[1]))
        return None

    def _backs_away(self, start, goal, close, others, footprint: float) -> bool:
        """Whether the straight move to ``goal`` only ever increases the distance to every
        disc the base starts inside (``(start - c) . (goal - start) >= 0``: the distance
        along a segment is convex, so it grows all the way), ends outside them and passes
        clear of the rest. Escaping along a fixed direction instead overshot such a goal
        by up to a step and, with the target not an obstacle, ran the base into the object
        it was going to pick (Case 3 camera, O_a pushed 3 cm, the grasp planned on the
        estimate before the push missed)."""
        vx, vy = goal[0] - start[0], goal[1] - start[1]
        for x, y, r in close:
            if (start[0] - x) * vx + (start[1] - y) * vy < 0:
                return False
            if math.hypot(goal[0] - x, goal[1] - y) < r + 0.01:
                return False
        return self._segment_free(others, start, goal, footprint)

    def _blocked(self, discs, start, footprint: float) -> np.ndarray:
        occ = self._border(footprint)
        for x, y, r in discs:
            # grid cells are GRID apart: keep cell centres half a diagonal further away
            occ |= np.hypot(self.X - x, self.Y - y) < r + 0.6 * GRID
        return occ

    def plan(
        self,
        start: tuple[float, float],
        goal: tuple[float, float],
        obstacles: list[Disc],
        footprint: float,
    ) -> list[tuple[float, float]] | None:
        """Waypoints from start to goal (both included), or None when there is no way.

        The base (and whatever it carries) is a disc of radius ``footprint``; it keeps
        ``footprint + r + CLEARANCE`` from every object's centre, backing away first when
        it starts closer than that (see `_escape`).
        """
        discs = self._reaches(obstacles, footprint)
        esc = self._escape(start, goal, discs, footprint)
        if esc is None:
            return None
        if esc == goal:
            return [start, goal]
        if esc != start:
            rest = self.plan(esc, goal, obstacles, footprint)
            return None if rest is None else [start, *rest]
        if self._segment_free(discs, start, goal, footprint):
            return [start, goal]
        occ = self._blocked(discs, start, footprint)
        gi = self.cell(*goal)
        si = self.cell(*start)
        occ[gi] = False
        occ[si] = False
        moves = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)]
        g = {si: 0.0}
        parent: dict = {si: None}
        frontier = [(0.0, si)]
        while frontier:
            _, c = heapq.heappop(frontier)
            if c == gi:
                break
            for dx, dy in moves:
                n = (c[0] + dx, c[1] + dy)
                if not (0 <= n[0] < self.nx and 0 <= n[1] < self.ny) or occ[n]:
                    continue
                cost = g[c] + math.hypot(dx, dy)
                if cost < g.get(n, math.inf):
                    g[n] = cost
                    parent[n] = c
                    h = math.hypot(n[0] - gi[0], n[1] - gi[1])
                    heapq.heappush(frontier, (cost + h, n))
        if gi not in parent:
            return None
        cells = []
        c = gi
        while c is not None:
            cells.append(c)
            c = parent[c]
        cells.reverse()
        pts = [start] + [self._xy(c) for c in cells[1:-1]] + [goal]
        return self._shortcut(discs, pts, footprint)

    def _xy(self, c: tuple[int, int]) -> tuple[float, float]:
        return (self.workspace[0] + GRID * c[0], self.workspace[2] + GRID * c[1])

    def _segment_free(self, discs, a, b, footprint: float) -> bool:
        """Exact: the segment keeps every inflated disc's distance (the region is convex)."""
        if not (self._inside(a, footprint) and self._inside(b, footprint)):
            return False
        ax, ay = a
        vx, vy = b[0] - a[0], b[1] - a[1]
        n2 = vx * vx + vy * vy
        for x, y, r in discs:
            u = 0.0 if n2 == 0 else min(max(((x - ax) * vx + (y - ay) * vy) / n2, 0.0), 1.0)
            if math.hypot(ax + u * vx - x, ay + u * vy - y) < r:
                return False
        return True

    def _shortcut(self, discs, pts: list, footprint: float) -> list:
        out = [pts[0]]
        i = 0
        while i < len(pts) - 1:
            j = len(pts) - 1
            while j > i + 1 and not self._segment_free(discs, pts[i], pts[j], footprint):
                j -= 1
            out.append(pts[j])
            i = j
        return out
