"""Pairs of steps that no goal order can take both, priced into the assignment bound.

The assignment relaxation of the order search (`tamp.rg.search`; SMP-MRO, Nakamura &
Sekiyama, IEEE Access, §IV-B2) picks for every remaining goal the drop point it is approached
from. Call that choice an *arc* a → b: goal b is achieved right after goal a. The relaxation
lets every arc be taken at once, even arcs that no order respecting the constraints C can
contain together. On a cyclic swap each object may go buffer-then-target directly (an arc of
length 0) only if the next object left earlier, and the relaxation takes that shortcut for
every object at once: its bound was 4.7 % below the optimum at 24 objects.

**Conflicting arcs.** Let <* be C's transitive closure and x ≤* y mean x = y or x <* y. If b
comes right after a, every goal p with p <* b, p ≠ a and not p ≤* a comes before a; and every
goal s with a <* s, s ≠ b and not b ≤* s comes after b. A second arc c → d with a ≤* c and
d ≤* p (or s ≤* c and d ≤* b) forces the opposite order (a ≤ c < d ≤ p), so no order takes
both arcs: ``x(a→b) + x(c→d) ≤ 1`` holds for every order. An arc a → b with a goal p between
(a <* p <* b) is never taken at all (`never_adjacent`).

**Lagrangian bound.** For multipliers λ ≥ 0, one per pair, and any set Q of pairs,

    min_x  c·x + Σ_{q ∈ Q} λ_q (x_q1 + x_q2 − 1)

over the assignments x is a lower bound of the cheapest order (an order is an assignment,
and each term it adds is ≤ 0), and it is an assignment problem with every arc's cost raised
by the λ of its pairs, less Σ_Q λ (Fisher, "The Lagrangian relaxation method for solving
integer programming problems", Management Science 27(1), 1981). The search takes for Q the
pairs with at least one arc in a state's matrix: then a state's matrix is one gather from a
single penalised table, and a child's is still a submatrix of its parent's (what the search's
shortcuts rely on). λ is fitted once, by subgradient ascent on the first state's problem;
only pairs that its assignments break can get λ > 0, so the pairs are collected among the
arcs of each assignment met (an O(goals³) boolean product per step), never enumerated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

#: Goals up to which conflicts are priced (each fitting step is O(goals³)).
CONFLICT_LIMIT = 200
#: Subgradient steps when fitting λ (each one assignment of the first state's size), and at
#: most two per goal: a search expands at least one state per goal, each with about one
#: assignment, so fitting never costs more than about twice the least search.
ITERATIONS = 120
#: First subgradient step, as a fraction of the mean allowed approach cost; then ×0.97.
STEP = 0.05
#: Steps without a better bound (by 0.01 %) after which the fitting stops.
PATIENCE = 20


@dataclass(frozen=True)
class Conflicts:
    """Pairs of arcs no order takes both (goal indices: arc ``r1[i] → c1[i]`` against arc
    ``r2[i] → c2[i]``, the lesser arc first) and their multipliers ``lam`` (in the units of
    the costs they were fitted on)."""

    r1: np.ndarray
    c1: np.ndarray
    r2: np.ndarray
    c2: np.ndarray
    lam: np.ndarray

    def __len__(self) -> int:
        return len(self.lam)

    def penalty(self, size: int) -> np.ndarray:
        """``size``×``size`` table: each arc's summed λ (rows, columns: goal indices)."""
        flat = np.bincount(self.r1 * size + self.c1, self.lam, size * size).astype(float)
        flat += np.bincount(self.r2 * size + self.c2, self.lam, size * size)
        return flat.reshape(size, size)

    def present(self, rows: np.ndarray, cols: np.ndarray) -> float:
        """Σ λ over the pairs with an arc in the matrix whose rows and columns are marked
        in the boolean vectors ``rows`` and ``cols`` (indexed by goal)."""
        on = (rows[self.r1] & cols[self.c1]) | (rows[self.r2] & cols[self.c2])
        return float(self.lam[on].sum())

    def present_without(self, rows: np.ndarray, cols: np.ndarray, size: int) -> np.ndarray:
        """Per goal g: `present` once column g is removed too (``size``: goal count + 1)."""
        one = rows[self.r1] & cols[self.c1]
        two = rows[self.r2] & cols[self.c2]
        total = float(self.lam[one | two].sum())
        only1, only2 = one & ~two, two & ~one  # pairs whose only arcs in are in column g
        lost = np.bincount(self.c1[only1], self.lam[only1], size).astype(float)
        lost += np.bincount(self.c2[only2], self.lam[only2], size)
        return total - lost


def order_closure(succs: list[int], k: int) -> np.ndarray:
    """``le[x, y]``: x ≤* y (x = y or x must precede y), from each goal's bit mask of the
    goals that must follow it."""
    le = np.eye(k, dtype=bool)
    for x, mask in enumerate(succs):
        while mask:
            low = mask & -mask
            le[x, low.bit_length() - 1] = True
            mask ^= low
    return le


def never_adjacent(le: np.ndarray) -> np.ndarray:
    """``[a, b]``: some goal lies between (a <* p <* b), so b never comes right after a."""
    lt = (le & ~np.eye(len(le), dtype=bool)).astype(np.float32)
    return (lt @ lt) > 0


def conflicting(a: np.ndarray, b: np.ndarray, le: np.ndarray) -> np.ndarray:
    """``[i, j]``: arcs a[i] → b[i] and a[j] → b[j] conflict (module notes); arcs sharing
    a row or a column are left out (an assignment never takes both anyway)."""
    lt = le & ~np.eye(len(le), dtype=bool)
    first = lt[:, b].T & ~le[:, a].T  # [i, p]: p comes before a[i] when b[i] follows it
    last = lt[a] & ~le[b]  # [i, s]: s comes after b[i] when b[i] follows a[i]
    f = np.float32
    one = le[np.ix_(a, a)] & ((first.astype(f) @ le[b].T.astype(f)) > 0)  # a ≤ c, d ≤ p
    two = le[np.ix_(b, b)].T & ((last.astype(f) @ le[:, a].astype(f)) > 0)  # s ≤ c, d ≤ b
    both = one | two
    both |= both.T
    both &= (a[:, None] != a[None, :]) & (b[:, None] != b[None, :])
    return both


def fit(cost: np.ndarray, le: np.ndarray, big: float) -> Conflicts | None:
    """Conflicting pairs and their multipliers by subgradient ascent on the assignment
    problem ``cost`` (rows, columns: the goals of ``le``, then one more each; entries
    ≥ ``big`` are forbidden): the pairs the assignments met break, with the best λ met
    (pairs at λ = 0 dropped); None when none gets λ > 0."""
    m = cost.shape[0]
    k = m - 1
    finite = cost[cost < big]
    step = STEP * (float(finite[finite > 0].mean()) if (finite > 0).any() else 1.0)
    where: dict[tuple[int, int, int, int], int] = {}
    quads = np.empty((0, 4), dtype=np.intp)
    lam = np.zeros(0)
    best, best_lam, since = -np.inf, lam, 0
    pen = np.zeros(m * m)
    for _ in range(min(ITERATIONS, 2 * k)):
        r, c = linear_sum_assignment(cost + pen.reshape(m, m))
        value = float(cost[r, c].sum() + pen[r * m + c].sum() - lam.sum())
        if value > best + 1e-4 * abs(value):  # a gain of 0.01 % or more
            best, best_lam, since = value, lam.copy(), 0
        else:
            since += 1
            if since >= PATIENCE:
                break
        arcs = (r < k) & (c < k)
        a, b = r[arcs], c[arcs]
        i, j = np.nonzero(np.triu(conflicting(a, b, le)))
        new = [
            q
            for q in (
                (x, y, u, v) if (x, y) < (u, v) else (u, v, x, y)
                for x, y, u, v in zip(
                    a[i].tolist(), b[i].tolist(), a[j].tolist(), b[j].tolist(), strict=True
                )
            )
            if q not in where
        ]
        if new:
            for q in new:
                where[q] = len(where)
            quads = np.vstack((quads, np.array(new, dtype=np.intp)))
            lam = np.append(lam, np.zeros(len(new)))
            best_lam = np.append(best_lam, np.zeros(len(new)))
        used = np.zeros(m * m, dtype=bool)
        used[r * m + c] = True
        f1 = quads[:, 0] * m + quads[:, 1]
        f2 = quads[:, 2] * m + quads[:, 3]
        grad = used[f1].astype(float) + used[f2] - 1.0
        if not (grad > 0).any() and not (lam[grad < 0] > 0).any():
            break  # no pair broken and no λ on a slack pair: optimal multipliers
        lam = np.maximum(0.0, lam + step * grad)
        step *= 0.97
        pen = np.bincount(f1, lam, m * m).astype(float) + np.bincount(f2, lam, m * m)
    keep = best_lam > 0
    if not keep.any():
        return None
    q = quads[keep]
    return Conflicts(q[:, 0], q[:, 1], q[:, 2], q[:, 3], best_lam[keep])


def symmetrised(conflicts: Conflicts, perms: tuple[tuple[int, ...], ...]) -> Conflicts:
    """``conflicts`` averaged over the automorphisms ``perms`` (a group): each pair's λ is
    spread evenly over its images, which conflict too (conflicts are defined by C and the
    forbidden arcs alone, which every automorphism keeps). The result is invariant, and
    still a valid set of multipliers (any λ ≥ 0 is)."""
    total: dict[tuple[int, int, int, int], float] = {}
    share = conflicts.lam / len(perms)
    quads = zip(
        conflicts.r1.tolist(),
        conflicts.c1.tolist(),
        conflicts.r2.tolist(),
        conflicts.c2.tolist(),
        share.tolist(),
        strict=True,
    )
    for a, b, c, d, w in quads:
        for p in perms:
            one, two = (p[a], p[b]), (p[c], p[d])
            q = (*one, *two) if one < two else (*two, *one)
            total[q] = total.get(q, 0.0) + w
    arr = np.array(list(total), dtype=np.intp).reshape(-1, 4)
    return Conflicts(
        arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3], np.fromiter(total.values(), dtype=float)
    )
