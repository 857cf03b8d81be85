"""Symmetries of an ordering task, so the search visits each class of equivalent states once.

An *automorphism* of the task is a permutation π of the goals that keeps every cost and
every constraint: ``approach(π a, π b) = approach(a, b)`` (the robot's start fixed, row −1),
``carry(π g) = carry(g)`` and ``(a, b) ∈ C ⇔ (π a, π b) ∈ C``. A state (S, last) and its
image (π S, π last) are then reached from the start at the same cost and have the same
cost-to-go, so A* over the reachability graph (Nakamura & Sekiyama, SMP-MRO, IEEE Access,
§IV-B2) may merge them: it stays exact and expands one state per class. On a ring of n
objects around the robot this divides the states expanded by about n.

Candidates come from the geometry (rotations and reflections of the plane about the robot's
start that map some goal's pick point onto another's); each is accepted only if the cost
tables and the constraints agree, to `TOLERANCE` of the largest approach (a candidate
failing on rounding is simply dropped: the search stays exact, it only merges less).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Goals up to which symmetries are looked for (the check is O(goals²) per candidate).
SYMMETRY_LIMIT = 400
#: Automorphisms kept at most (the closure of those found; any subset is still sound).
GROUP_LIMIT = 512
#: Relative tolerance on equal costs (of the largest finite approach cost).
TOLERANCE = 1e-9
_CHUNK = 8  # bits per mask-permutation table


@dataclass(frozen=True)
class Symmetry:
    """A set of automorphisms (identity first) and tables to permute goal bit masks fast."""

    perms: tuple[tuple[int, ...], ...]
    #: per automorphism, per chunk of `_CHUNK` goal bits: the image of each chunk value
    tables: tuple[tuple[tuple[int, ...], ...], ...]
    #: per automorphism, per goal: ``1 << π(g)``
    bits: tuple[tuple[int, ...], ...]

    @staticmethod
    def of(perms: list[tuple[int, ...]], k: int) -> Symmetry:
        chunks = (k + _CHUNK - 1) // _CHUNK
        tables, bits = [], []
        for p in perms:
            per_chunk = []
            for c in range(chunks):
                lo = c * _CHUNK
                width = min(_CHUNK, k - lo)
                row = [0] * (1 << width)
                for v in range(1, 1 << width):
                    low = v & -v
                    row[v] = row[v ^ low] | 1 << p[lo + low.bit_length() - 1]
                per_chunk.append(tuple(row))
            tables.append(tuple(per_chunk))
            bits.append(tuple(1 << j for j in p))
        return Symmetry(tuple(perms), tuple(tables), tuple(bits))

    def __len__(self) -> int:
        return len(self.perms)

    def images(self, mask: int) -> list[int]:
        """``π(mask)`` for every automorphism π, in `perms` order."""
        out = []
        for table in self.tables:
            m, acc, c = mask, 0, 0
            while m:
                acc |= table[c][m & 0xFF]
                m >>= _CHUNK
                c += 1
            out.append(acc)
        return out

    def canonical(self, images: list[int], g: int) -> tuple[int, int, int]:
        """The class representative of the state (S ∪ {g}, g), given ``images`` of S:
        the least image mask, ties to the least image of ``g``; returns (mask, last, which)."""
        best, arg = None, 0
        for i, (img, bit, p) in enumerate(zip(images, self.bits, self.perms, strict=True)):
            cand = (img | bit[g], p[g])
            if best is None or cand < best:
                best, arg = cand, i
        assert best is not None  # perms holds the identity at least, so the loop ran
        return best[0], best[1], arg


def find_symmetry(
    pick: np.ndarray,
    drop: np.ndarray,
    start: np.ndarray,
    approach: np.ndarray,
    carry: np.ndarray,
    constraints: set[tuple[int, int]],
) -> Symmetry | None:
    """The automorphisms found for a task (None when only the identity).

    ``pick``, ``drop``: k×3 points per goal; ``start``: the robot's (3,); ``approach``:
    (k+1)×k empty-drive costs from each drop (row k: the start) to each pick; ``carry``: k.
    """
    k = len(carry)
    if k < 2 or k > SYMMETRY_LIMIT:
        return None
    finite = approach[np.isfinite(approach)]
    tol = TOLERANCE * max(1.0, float(np.abs(finite).max()) if finite.size else 1.0)
    found = [tuple(range(k))]
    seen = {found[0]}
    for perm in _candidates(pick, drop, start, _depths(k, constraints)):
        if perm in seen:
            continue
        seen.add(perm)
        if _is_automorphism(perm, approach, carry, constraints, tol):
            found.append(perm)
    if len(found) == 1:
        return None
    group = _closure(found)
    return Symmetry.of(group, k)


def _depths(k: int, constraints: set[tuple[int, int]]) -> list[int]:
    """Each goal's depth in C (the longest chain of goals before it): kept by every
    automorphism, it tells apart goals with the same pick and drop points."""
    preds: list[list[int]] = [[] for _ in range(k)]
    for a, b in constraints:
        preds[b].append(a)
    depth = [-1] * k

    def of(g: int) -> int:
        stack = [g]
        while stack:
            v = stack[-1]
            todo = [p for p in preds[v] if depth[p] < 0]
            if todo:
                stack.extend(todo)
                continue
            stack.pop()
            depth[v] = 1 + max((depth[p] for p in preds[v]), default=-1)
        return depth[g]

    return [of(g) if depth[g] < 0 else depth[g] for g in range(k)]


def _candidates(pick: np.ndarray, drop: np.ndarray, start: np.ndarray, depth: list[int]):
    """Goal permutations induced by plane rotations/reflections about the start that map
    one anchor point onto a point of the same radius (each a candidate, checked later).
    A goal is matched by its pick and drop points and its depth in C."""
    k = len(pick)
    rel = np.vstack((pick, drop)) - start
    radius = np.hypot(rel[:, 0], rel[:, 1])
    scale = max(1.0, float(radius.max()))
    far = np.flatnonzero(radius > 1e-6 * scale)
    if not far.size:
        return
    a = int(far[0])
    angle = np.arctan2(rel[:, 1], rel[:, 0])
    quant = 1e6 / scale

    def key(xyz: np.ndarray) -> list[tuple[int, ...]]:
        return [tuple(v) for v in np.rint(xyz * quant).astype(np.int64).tolist()]

    goal_keys = [(*pk, *dk, d) for pk, dk, d in zip(key(rel[:k]), key(rel[k:]), depth, strict=True)]
    where: dict[tuple[int, ...], int] = {}
    for g, kk in enumerate(goal_keys):
        if kk in where:  # two goals alike in points and depth: no bijection by geometry
            return
        where[kk] = g
    same = np.flatnonzero(np.abs(radius - radius[a]) <= 1e-6 * scale)
    for b in same.tolist():
        for mirror in (False, True):
            if mirror:
                t = angle[a] + angle[b]
                m = np.array([[math.cos(t), math.sin(t)], [math.sin(t), -math.cos(t)]])
            else:
                t = angle[b] - angle[a]
                m = np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])
            moved = rel.copy()
            moved[:, :2] = rel[:, :2] @ m.T
            keys = [
                (*pk, *dk, d)
                for pk, dk, d in zip(key(moved[:k]), key(moved[k:]), depth, strict=True)
            ]
            perm = []
            for kk in keys:
                g = where.get(kk)
                if g is None:
                    break
                perm.append(g)
            else:
                if len(set(perm)) == k:
                    yield tuple(perm)


def _is_automorphism(perm, approach, carry, constraints, tol) -> bool:
    p = np.asarray(perm)
    if np.abs(carry[p] - carry).max() > tol:
        return False
    if {(perm[a], perm[b]) for a, b in constraints} != constraints:
        return False
    rows = np.append(p, len(p))  # the start row stays the start
    moved = approach[np.ix_(rows, p)]
    return bool(np.abs(moved - approach).max() <= tol)


def _closure(perms: list[tuple[int, ...]]) -> list[tuple[int, ...]]:
    """The group the automorphisms generate (identity first), up to `GROUP_LIMIT`."""
    group = list(perms)
    known = set(group)
    frontier = list(perms[1:])
    while frontier and len(group) < GROUP_LIMIT:
        nxt = []
        for p in frontier:
            for q in perms[1:]:
                r = tuple(p[i] for i in q)
                if r not in known and len(group) < GROUP_LIMIT:
                    known.add(r)
                    group.append(r)
                    nxt.append(r)
        frontier = nxt
    return group
