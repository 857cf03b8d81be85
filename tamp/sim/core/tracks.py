"""Perception's own identities: tracks that associate detections across views by class and
3-D position.

A detector reports, per view, instances with a class and a world-frame centroid (the mask
back-projected through its depth, the intrinsics and the camera pose from the arm's own
kinematics: `tamp.sim.core.instances.located`); it gives them no identity that lasts from
one view to the next. A consumer needs one: the grasp descent follows *its* target over a
dozen views, occlusion memory remembers *which* instance it cannot see now, the lift check
asks whether *the target* left the table. `update` gives each detection of a view the id of
a track:

- a detection is associated with a live track of the **same class** whose position lies
  within ``gate`` metres of its centroid, or whose last points it overlaps (at least
  `SHARE` of the smaller point set lies within `OVERLAP` of the other: one long object
  seen partly hidden from two sides has centroids 10 cm apart but some surface in common);
  among several, the assignment that minimises the summed centroid distance
  (Hungarian, `scipy.optimize.linear_sum_assignment`, per class), so two neighbours of one
  class never swap;
- then, among what is left (detections without a track, live tracks without a detection),
  the same assignment with a wider gate (`REGATE`, or per class the object's own length:
  `regate_for`): one object seen partly, from two sides
  or cut by the image's edge, has centroids farther apart than the gate and may share no
  surface (a scissors' two visible parts lay 8 cm apart, a saw's 10 cm; the second stage
  never takes a track another detection of this view could have: only leftovers meet), and
  never a track whose last position lies under another detection's mask (``under``): that
  object is in view, merged into its neighbour's detection (two objects touching seen as
  one), not moved 10 cm to where a new detection appears;
- a detection still left without a track starts a new one (a fresh id, never reused);
- a track not associated for longer than ``lifetime`` seconds is dropped, unless the caller
  keeps it (occlusion memory: an instance remembered as hidden keeps its track);
- each track counts the views it was associated in (``hits``): a consumer can hold a
  track seen once as tentative (`tamp.sim.core.perception.CONFIRM_VIEWS`: a detector's
  one-view false positive or class swap starts a track that is never seen again).

The gate (`GATE`, 7 cm) is larger than a centroid's drift between views of one still object
(a few centimetres: the visible part changes as the camera moves) and smaller than two
objects' centres lying side by side; an object moved farther than the gate (and off its
own last surface) gets a fresh id (the noisy detector's "fresh identity" error jumps 8 cm
for that reason). Pure Python and
numpy, no Drake: the learned detector plugs into the same tracker as the label image does.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

#: largest distance (m) between a track's position and a detection's centroid to associate
GATE = 0.07
#: the second stage's gate (m): about half the longest object's length
REGATE = 0.15
#: sim seconds a track lives without being associated (a detection missed in a few views)
LIFETIME = 3.0
#: two point sets overlap when this share of the smaller lies within `OVERLAP` m of the other:
#: a saw seen past the held hammer from one side, then the other, shares 18 % (its centroids
#: 10 cm apart); objects 1 cm apart or more share none
OVERLAP = 0.01
SHARE = 0.1
#: points kept per track (an even subsample of its last detection's)
KEEP_POINTS = 300


@dataclass(frozen=True)
class Track:
    """One instance as the tracker knows it: its id, class, last world position (the
    centroid of its last detection), the sim time of that detection, a subsample of that
    detection's world points (3 x N; None: none given), and the number of views it was
    associated in."""

    id: int
    cls: str
    position: tuple[float, float, float]
    seen: float
    points: np.ndarray | None = field(default=None, compare=False, repr=False)
    hits: int = 1


@dataclass(frozen=True)
class Tracks:
    """The tracker's state: the live tracks and the next fresh id (never mutated)."""

    tracks: tuple[Track, ...] = ()
    next_id: int = 1

    def get(self, track: int | None) -> Track | None:
        return next((t for t in self.tracks if t.id == track), None)

    def without(self, ids: set[int] | frozenset[int]) -> Tracks:
        """These tracks forgotten (an object taken into the gripper is in no workspace)."""
        return Tracks(tuple(t for t in self.tracks if t.id not in ids), self.next_id)


def overlaps(a: np.ndarray | None, b: np.ndarray | None, r: float = OVERLAP) -> float:
    """The share of the smaller of two point sets (3 x N) lying within ``r`` of the other
    (0 when either is missing or empty)."""
    if a is None or b is None or a.shape[1] == 0 or b.shape[1] == 0:
        return 0.0
    small, big = (a, b) if a.shape[1] <= b.shape[1] else (b, a)
    d, _ = cKDTree(big.T).query(small.T, distance_upper_bound=r)
    return float(np.mean(np.isfinite(d)))


def _subsample(points: np.ndarray | None, n: int = KEEP_POINTS) -> np.ndarray | None:
    if points is None or points.shape[1] <= n:
        return points
    return points[:, :: int(np.ceil(points.shape[1] / n))]


def regate_for(span: float) -> float:
    """The second stage's gate for a class whose footprint's diagonal is ``span`` (m): two
    visible parts of one object lie no farther apart than the object is long, so a screw's
    track (7.7 cm) is never handed to a screw 9 cm away; at least `GATE`, at most
    `REGATE`."""
    return min(REGATE, max(GATE, span))


def associate(
    tracks: Sequence[Track],
    observed: Sequence[tuple[str, Sequence[float]]],
    gate: float | Mapping[str, float] = GATE,
    points: Sequence[np.ndarray | None] | None = None,
    share: float = SHARE,
) -> list[int | None]:
    """For each observed (class, centroid), the index in ``tracks`` of its track, or None:
    per class, the minimum-distance assignment among pairs within ``gate`` (one for all, or
    per class: every observed class must be in it) or whose points overlap (``points``:
    each observation's world points; module docstring)."""
    out: list[int | None] = [None] * len(observed)
    for cls in {c for c, _ in observed}:
        limit = gate[cls] if isinstance(gate, Mapping) else gate
        rows = [i for i, (c, _) in enumerate(observed) if c == cls]
        cols = [j for j, t in enumerate(tracks) if t.cls == cls]
        if not cols:
            continue
        a = np.array([observed[i][1] for i in rows], float).reshape(len(rows), 3)
        b = np.array([tracks[j].position for j in cols], float).reshape(len(cols), 3)
        dist = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
        ok = dist <= limit
        if points is not None:
            for r, i in enumerate(rows):
                for c, j in enumerate(cols):
                    if not ok[r, c] and overlaps(points[i], tracks[j].points) >= share:
                        ok[r, c] = True
        # ineligible pairs cost more than any set of eligible ones: never preferred
        finite = np.where(np.isfinite(dist), dist, 0.0)
        big = (finite[ok].sum() if ok.any() else 0.0) + 1.0
        cost = np.where(ok, finite, big)
        for r, c in zip(*linear_sum_assignment(cost), strict=True):
            if ok[r, c]:
                out[rows[r]] = cols[c]
    return out


def update(
    state: Tracks,
    observed: Sequence[tuple[str, Sequence[float]]],
    time: float,
    *,
    keep: frozenset[int] | set[int] = frozenset(),
    gate: float = GATE,
    lifetime: float = LIFETIME,
    points: Sequence[np.ndarray | None] | None = None,
    regate: float | Mapping[str, float] = REGATE,
    firm: frozenset[int] | set[int] = frozenset(),
    under: Mapping[int, Sequence[int]] | None = None,
) -> tuple[Tracks, tuple[int, ...]]:
    """The tracker after one view at sim ``time`` whose detections are ``observed`` (class,
    world centroid; ``points``: their world points, when known), and the track id of each
    detection. Associated tracks move to their detection's centroid; unassociated
    detections start tracks with fresh ids; tracks unseen for longer than ``lifetime`` are
    dropped unless their id is in ``keep``. Tracks in ``firm`` take part in the first stage
    only (the lift's check: is the target's own surface still on the table?). ``regate``:
    the second stage's gate, one for all or per class (`regate_for`; a class not in it:
    `REGATE`). ``under``: per track id, the indices of the detections whose mask covers the
    track's last position in this view; a track covered by any detection but a leftover of
    its own class takes part in the first stage only (module docstring)."""
    live = [t for t in state.tracks if time - t.seen <= lifetime or t.id in keep]
    match = associate(live, observed, gate, points)
    left = [k for k, j in enumerate(match) if j is None]

    def merged(t: Track) -> bool:
        covers = (under or {}).get(t.id, ())
        return any(k not in left or observed[k][0] != t.cls for k in covers)

    taken = set(match)
    spare = [
        j
        for j in range(len(live))
        if j not in taken and live[j].id not in firm and not merged(live[j])
    ]
    if left and spare:
        gates = {
            c: regate.get(c, REGATE) if isinstance(regate, Mapping) else regate for c, _ in observed
        }
        again = associate([live[j] for j in spare], [observed[k] for k in left], gates)
        for k, j in zip(left, again, strict=True):
            if j is not None:
                match[k] = spare[j]
    next_id = state.next_id
    ids: list[int] = []
    moved: dict[int, Track] = {}
    fresh: list[Track] = []
    for k, ((cls, p), j) in enumerate(zip(observed, match, strict=True)):
        position = tuple(float(x) for x in p)
        pts = _subsample(points[k]) if points is not None else None
        if j is None:
            fresh.append(Track(next_id, cls, position, time, pts))
            ids.append(next_id)
            next_id += 1
        else:
            moved[j] = Track(live[j].id, cls, position, time, pts, live[j].hits + 1)
            ids.append(live[j].id)
    tracks = tuple(moved.get(j, t) for j, t in enumerate(live)) + tuple(fresh)
    return Tracks(tracks, next_id), tuple(ids)
