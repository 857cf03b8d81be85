"""Exact weighted search over the reachability graph without building it (§IV-B2).

The search state is (achieved goals, last goal reached): the last goal fixes where the
robot stands, which is what makes edge costs depend on the path. A* with an admissible
heuristic (re-opening states when a cheaper path appears) returns an optimal order:

    h(S, r) = per_metre · (Σ_{g ∉ S} carry(g) + E(S, r)) + per_goal · |remaining|

``carry(g)`` is fixed by the per-object goal chain. ``E`` bounds the remaining empty drives
from below. Every remaining goal g is approached from exactly one point: the robot's
position or the drop point of another remaining goal that may precede it (not one of its
successors in C). The robot's first drive goes to an *enabled* goal (all its predecessors
achieved), and the goal reached last — the one drop point that approaches nothing — has
no successors in C. Two bounds are available:

* ``"min"`` — each goal's cheapest such approach, independently;
* ``"assignment"`` — the assignment-problem relaxation: the approach points must be
  distinct (the relaxation that lower-bounds asymmetric TSP tours; a dummy column takes
  the last goal's row, only for goals without successors). It prunes far more on hard
  layouts, at a higher cost per evaluation. Sending the robot to enabled goals only
  expands about 40 % fewer states on the cyclic swaps than the bare relaxation. Up to
  `CONFLICT_LIMIT` goals it is also a Lagrangian bound (`tamp.rg.conflicts`): pairs of
  approaches that no order takes both (b right after a, and d right after c) have a
  multiplier λ priced into both, less Σλ; an arc with a goal forced between its ends is
  forbidden. On the cyclic swap of 24 objects this raises the first bound from 4.7 % to
  2.2 % below the optimum and expands 8 times fewer states.

The true remaining route is one such assignment, so ``"min"`` and the bare assignment never
overestimate; for the priced one, the route's cost plus its Lagrangian terms (each ≤ 0,
since the route takes at most one arc of each pair) is at least the relaxation's minimum.
It is at least the bare assignment in the first state, where λ is fitted; deeper, a pair
that lost one arc keeps its λ, and the bound may fall below the bare one (still
admissible, not consistent: the search re-opens states and keeps ``max(h, h(parent) −
step)``). Above `BOUND_LIMIT` remaining goals no bound is computed and ``E = 0`` (still
admissible; the search stays exact, it only prunes less).

What keeps the search cheap (no geometry is stored per pair of goals above `DENSE_LIMIT`;
below it one (goals+1)² table makes a state's assignment matrix a single gather):

* **Lazy bounds.** A child is queued with ``h(parent) − step`` (admissible, since h(parent)
  is) and its own bound is computed only when it is popped; if that raises f, it is queued
  again. A state popped while nothing else is queued is expanded without computing its
  bound: with no competitor the bound cannot change what is expanded next (one object's
  chain of goals needs no bound at all).
* **The relaxation's own choice.** When the assignment sends the robot to goal g* next,
  the rest of that assignment is an optimal assignment of the child (S ∪ {g*}, g*) — its
  rows are the parent's minus the robot's, its columns minus g*, and the child's robot row
  is g*'s drop row — so, when g*'s row goes to a goal enabled in the child, the child's
  bound is ``h − step(r, g*)`` exactly (plus the multipliers of the pairs that leave with
  that row and column, `OrderProblem.chain_gain`) and its own assignment is known:
  following the relaxation's chain costs no solve at all.
* **Partial expansion.** A state with a known choice queues only that child (same f) and
  one deferred entry at its own f for the others (each of their f is at least that); on
  equal f, exact bounds pop before lazy ones. The deferred entry is expanded only if the
  chain stops paying (a subtour of the relaxation must be broken): then, with a competitor
  queued, the state is solved once for a lower bound of every child (one Bellman-Ford pass,
  `_forced_robot_row`: the child's matrix without the rule that its robot row goes to an
  enabled goal), the siblings whose bound gives the state's own f are queued, and the
  deferred entry waits again at the least f of the others (most are never queued: on the
  24-object swap, before the conflict pricing, 7,000 children were queued instead of
  58,000); a child popped against a competitor solves its own assignment, and is queued
  again if that raises its f.
  f is compared to 1e-6 (`_key`): the same costs summed in another order must tie, or
  float drift sends the search through every state of a plateau of equal f (the cliff of
  wide tasks: 1,000 independent goals in a row took 9 minutes, now 2 s).
* **Dominance.** With a metric cost (triangle inequality), a state (S, b) reached at cost
  g_b is no better than (S, a) reached at g_a when ``g_a + per_metre·d(a, b) ≤ g_b``: any
  completion from b can be driven from a through b's position for at most that much more.
  Such states are not queued.
* **Symmetry.** States that an automorphism of the task (a permutation of the goals that
  keeps every cost and constraint, `tamp.rg.symmetry`) maps onto each other have the same
  cost from the start and to the goal; each is replaced by one representative of its class
  (the least permuted goal mask) and the order is mapped back at the end. A ring of n
  objects around the robot expands about n times fewer states.

Ties on f (to 1e-6) go to exact bounds, then to deeper states.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Literal, NamedTuple

import numpy as np
from scipy.optimize import linear_sum_assignment

from tamp.demo.model import Demonstration
from tamp.rg.conflicts import (
    CONFLICT_LIMIT,
    Conflicts,
    fit,
    never_adjacent,
    order_closure,
    symmetrised,
)
from tamp.rg.costs import CostModel, planar
from tamp.rg.graph import GoalIndex
from tamp.rg.symmetry import Symmetry, find_symmetry

INF = float("inf")
_BIG = 1e12  # a forbidden approach; never chosen, because a finite assignment exists
BOUNDS = ("assignment", "min")
#: Remaining goals above which the empty-drive bound E is 0 (an assignment over n goals
#: costs O(n³); the search stays exact). Chosen so one bound takes well under a second.
BOUND_LIMIT = 1500
#: Goals up to which pairwise approach costs and the successor relation are tabulated once
#: (O(goals²) memory: 36 MB at this size); above, each bound computes its own block.
DENSE_LIMIT = 2000


@dataclass(frozen=True)
class SearchResult:
    """An optimal goal order, its cost, and how much work the search did."""

    order: list[str]
    cost: float
    expanded: int
    generated: int
    #: heuristic evaluations that solved a bound (for benchmarks)
    bounds: int = 0


@dataclass(frozen=True)
class Bound:
    """A state's bound ``h``, and ``child[i]``: a lower bound of the bound of the child
    achieving ``goals[i]`` (its matrix without the enabled-goal rule on the robot's row)."""

    h: float
    goals: np.ndarray | None = None
    child: np.ndarray | None = None
    #: the optimal assignment behind ``h``: approach row (a goal's drop, -1: the robot) →
    #: the goal it approaches; rows absent are unassigned (None: not an assignment bound)
    assign: dict[int, int] | None = None
    #: the solver's own rows → columns behind ``assign`` (positions in the state's matrix,
    #: `OrderProblem.bound`), so bounding the children reuses them; None when inherited
    pairs: tuple[np.ndarray, np.ndarray] | None = field(default=None, compare=False, repr=False)

    def restricted(self, g: int, step: float, enabled: Callable[[int], bool]) -> Bound | None:
        """The bound of the child achieving ``g`` when ``g`` is the relaxation's own choice.

        The rest of an optimal assignment is an optimal assignment of the child (its matrix
        is the parent's without the robot's row and g's column; g's drop row becomes the
        robot's, restricted to the goals ``enabled`` in the child), so when g's row goes to
        such a goal the child's bound is ``h − step`` and its assignment is known: no solve.
        """
        if self.assign is None or self.assign.get(-1) != g:
            return None
        child = dict(self.assign)
        del child[-1]
        nxt = child.pop(g, None)
        if nxt is None:  # g was the relaxation's last goal: only right if it is the last
            return Bound(self.h - step, assign=child) if not child else None
        if not enabled(nxt):  # the child's robot must drive to a goal enabled in the child
            return None
        child[-1] = nxt
        return Bound(self.h - step, assign=child)

    def mapped(self, perm: tuple[int, ...]) -> Bound:
        """The same bound in the frame of an automorphism ``perm`` (`tamp.rg.symmetry`)."""
        if self.assign is None:
            return Bound(self.h)
        return Bound(
            self.h, assign={(r if r < 0 else perm[r]): perm[c] for r, c in self.assign.items()}
        )


class _Rows(NamedTuple):
    """What a state's matrix needs from its goal set alone (kept per mask, `OrderProblem`;
    a named tuple: one is made per state bounded, on the search's hot path)."""

    #: the remaining goals, ascending
    idx: np.ndarray
    #: Σ carry over them
    carry: float
    #: the matrix's columns: ``idx``, then the dummy column k
    cols: np.ndarray
    #: the matrix's rows: the start (k, replaced by the robot's position), then ``idx``
    at: np.ndarray
    #: per remaining goal, True when a predecessor remains (the robot may not drive to it)
    waiting: np.ndarray
    #: per goal (and the start, last), True when it remains
    has: np.ndarray


def _bit_positions(mask: int, nbytes: int, k: int) -> np.ndarray:
    """Positions of the set bits of ``mask`` (< k), ascending."""
    bits = np.unpackbits(
        np.frombuffer(mask.to_bytes(nbytes, "little"), dtype=np.uint8), bitorder="little"
    )
    return np.flatnonzero(bits[:k])


def _forced_robot_row(square: np.ndarray, rows: np.ndarray, cols: np.ndarray, opt: float):
    """Optimal assignment value once the robot's row (row 0) is forced onto each column.

    ``rows → cols`` is an optimal assignment of the square matrix ``square`` (its last
    column: the dummy that takes the unassigned row). Forcing row 0 onto column g frees its
    column σ(0) and displaces g's row ρ(g), which takes another column, whose row moves on,
    until some row takes σ(0): the cheapest such alternating path is a shortest path from g
    to σ(0) over arcs j → j' of weight c(ρ(j), j') − c(ρ(j), j), without negative cycles
    because the assignment is optimal (Bellman-Ford, vectorised: each round relaxes every
    arc at once, one m×m add and row minimum, until nothing improves). Returns, per real
    column g, the optimum without row 0 and column g: ``opt − c(0, σ(0)) + dist(g → σ(0))``.
    """
    m = square.shape[0]
    sigma = np.empty(m, dtype=np.intp)
    sigma[rows] = cols
    rho = np.empty(m, dtype=np.intp)
    rho[sigma] = np.arange(m)
    wt = square[rho]  # wt[j, j']: the weight of the arc j -> j'
    wt -= square[rho, np.arange(m)][:, None]  # c(ρ(j), j): what column j costs now
    target = sigma[0]
    dist = wt[:, target].copy()  # one arc straight to σ(0)
    dist[target] = 0.0
    buf = np.empty_like(wt)
    for _ in range(m):
        np.add(wt, dist, out=buf)
        cand = buf.min(axis=1)
        if not (cand < dist - 1e-12).any():
            break
        np.minimum(cand, dist, out=dist)
    return opt - square[0, target] + dist[: m - 1]


class OrderProblem:
    """Geometry of a demonstration for the search (and for brute force), O(goals) memory."""

    def __init__(self, demo: Demonstration, model: CostModel, bound: str = "assignment"):
        if bound not in BOUNDS:
            raise ValueError(f"unknown bound {bound!r} (known: {', '.join(BOUNDS)})")
        self.demo = demo
        self.model = model
        self.bound_kind = bound
        self.index = GoalIndex.of(demo)
        goals = demo.goals
        k = len(goals)
        self.k = k
        m = model.metric
        self.pick = demo.pick_points()
        self.drop = [g.pos for g in goals]
        self.start = demo.robot_start.pos
        self._here = [*self.drop, self.start]  # row k: the robot's start
        self.carry = np.array([m(self.pick[i], self.drop[i]) for i in range(k)], dtype=float)
        self._carry = self.carry.tolist()
        self.per_metre = model.per_metre
        self.per_goal = model.per_goal
        self._planar = m is planar
        self._pick_xy = np.array([(p.x, p.y) for p in self.pick], dtype=float).reshape(k, 2)
        self._here_xy = np.array([(p.x, p.y) for p in self._here], dtype=float).reshape(k + 1, 2)
        self._dense: np.ndarray | None = None  # (k+1)×k approach costs (≤ DENSE_LIMIT)
        self._blocked: np.ndarray | None = None  # k×k successor relation (≤ DENSE_LIMIT)
        # `_dense` with forbidden approaches `_BIG`, and the dummy column (≤ DENSE_LIMIT)
        self._square: np.ndarray | None = None
        self._step_rows: dict[int, list[float]] = {}
        self._step_vectors: dict[int, np.ndarray] = {}
        self._drive_rows: dict[int, list[float]] = {}
        self._rows_of: dict[int, _Rows] = {}
        # masks whose `_Rows` are kept: about half a million goals in all (four arrays each,
        # some 16 MB)
        self._rows_limit = max(256, (1 << 19) // max(1, k))
        self._symmetry: Symmetry | None | Literal[False] = False  # False: not looked for yet
        self._conflicts: Conflicts | None = None  # arcs priced into `_square` (conflicts.py)
        self._penalty = np.zeros(0)  # their multipliers per arc, (k+1)² (with _conflicts)
        # per goal: the bit mask of its direct predecessors (enabled once they are achieved)
        self._pred_masks = [sum(1 << p for p in ps) for ps in self.index.preds]
        # the dummy column's cost per goal: only a goal without successors can be the last
        self._dummy = np.array([_BIG if s else 0.0 for s in self.index.succs])
        self._prepared = False
        self._closure: dict[int, int] = {}  # goal -> bitmask of its transitive successors
        self._nbytes = (k + 7) // 8
        self.bounds_solved = 0

    def step_cost(self, last: int, g: int) -> float:
        """Cost of achieving goal ``g`` with the robot at the drop of ``last`` (−1: start)."""
        here = self._here[last]  # last == -1 is the start (row k)
        return (
            self.per_metre * (self.model.metric(here, self.pick[g]) + self._carry[g])
            + self.per_goal
        )

    def drive(self, a: int, b: int) -> float:
        """Cost of driving empty from the drop of ``a`` to the drop of ``b`` (−1: start)."""
        return self.per_metre * self.model.metric(self._here[a], self._here[b])

    # -- the bound ---------------------------------------------------------------------------
    def remaining(self, mask: int) -> np.ndarray:
        """Indices of the goals not achieved in ``mask``, ascending."""
        return self._rows(mask).idx

    def _rows(self, mask: int) -> _Rows:
        """The goal-set part of a state's matrix (`_Rows`), kept per mask (up to
        `_rows_limit` masks): a state is bounded up to twice, for its own assignment and
        then for its children's, and the states with one goal set share it."""
        rows = self._rows_of.get(mask)
        if rows is None:
            if len(self._rows_of) >= self._rows_limit:
                self._rows_of.clear()
            k = self.k
            if k == 0:
                idx = np.empty(0, dtype=np.intp)
            else:
                idx = _bit_positions(~mask & ((1 << k) - 1), self._nbytes, k)
            rem = ~mask & self.index.full
            pm = self._pred_masks
            n = len(idx)
            cols = np.empty(n + 1, dtype=np.intp)
            cols[:n] = idx
            cols[n] = k
            at = np.empty(n + 1, dtype=np.intp)
            at[0] = k
            at[1:] = idx
            has = np.zeros(k + 1, dtype=bool)
            has[idx] = True
            rows = self._rows_of[mask] = _Rows(
                idx,
                float(self.carry[idx].sum()),
                cols,
                at,
                np.array([pm[b] & rem != 0 for b in idx.tolist()], dtype=bool),
                has,
            )
        return rows

    def _approach(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Empty-drive metres from the drops ``rows`` (k: the start) to the picks ``cols``."""
        if self._dense is not None:
            return self._dense[np.ix_(rows, cols)]
        if self._planar:
            here, pick = self._here_xy[rows], self._pick_xy[cols]
            return np.hypot(here[:, :1] - pick[:, 0], here[:, 1:] - pick[:, 1])
        m = self.model.metric
        return np.array(
            [[m(self._here[a], self.pick[b]) for b in cols.tolist()] for a in rows.tolist()],
            dtype=float,
        ).reshape(len(rows), len(cols))

    def _successors(self, g: int) -> int:
        """Bitmask of the goals that must come (transitively) after ``g`` (memoised)."""
        known = self._closure.get(g)
        if known is not None:
            return known
        stack = [(g, False)]
        while stack:
            v, done = stack.pop()
            if v in self._closure:
                continue
            succs = self.index.succs[v]
            if done:
                acc = 0
                for j in succs:
                    acc |= 1 << j | self._closure[j]
                self._closure[v] = acc
            else:
                stack.append((v, True))
                stack.extend((j, False) for j in succs if j not in self._closure)
        return self._closure[g]

    def _prepare(self) -> None:
        """Up to `DENSE_LIMIT` goals, tabulate approach costs and the successor relation once,
        and the approach costs with the forbidden pairs already `_BIG` (`_square`): a state's
        assignment matrix is then one gather."""
        if self._prepared:
            return
        self._prepared = True
        if self.k > DENSE_LIMIT:
            return
        every = np.arange(self.k)
        dense = self._approach(np.arange(self.k + 1), every)
        blocked = np.zeros((self.k, self.k), dtype=bool)  # [a, b]: a must come after b
        for b in range(self.k):
            after = self._successors(b)
            if after:
                blocked[_bit_positions(after, self._nbytes, self.k), b] = True
        self._dense, self._blocked = dense, blocked
        square = np.empty((self.k + 1, self.k + 1))  # column k: the dummy (see `bound`)
        square[:, : self.k] = dense
        sub = square[: self.k, : self.k]
        sub[blocked] = _BIG
        np.fill_diagonal(sub, _BIG)
        square[: self.k, self.k] = self._dummy
        square[self.k, self.k] = _BIG
        self._square = square
        if self.k <= CONFLICT_LIMIT and self.index.acyclic():
            self._price_conflicts()

    def _price_conflicts(self) -> None:
        """Up to `CONFLICT_LIMIT` goals: forbid the arcs no order takes (a goal between), and
        raise `_square` by the multipliers of conflicting arcs (`tamp.rg.conflicts`), fitted
        on the first state's problem and spread over the task's automorphisms (symmetric
        states keep equal bounds, which `Bound.mapped` relies on)."""
        k = self.k
        square = self._square
        assert square is not None  # called by _prepare once the table exists
        le = order_closure([self._successors(g) for g in range(k)], k)
        square[:k, :k][never_adjacent(le)] = _BIG
        if self.bound_kind != "assignment":
            return
        first = square.copy()  # the first state: the robot at the start, nothing achieved
        first[k, :k][[bool(m) for m in self._pred_masks]] = _BIG
        priced = fit(first, le, _BIG)
        if priced is None:
            return
        sym = self.symmetry()
        if sym is not None:
            priced = symmetrised(priced, sym.perms)
        self._conflicts = priced
        self._penalty = priced.penalty(k + 1)
        self._square = square + self._penalty

    @property
    def conflicts(self) -> Conflicts | None:
        """The conflicting arcs priced into the bound (`tamp.rg.conflicts`); None if none."""
        self._prepare()
        return self._conflicts

    def chain_gain(self, mask: int, last: int, g: int) -> float:
        """What the bound of the child achieving ``g`` has above ``h − step`` when the child
        keeps the rest of the state's assignment (`Bound.restricted`): the multipliers of the
        conflicting pairs (`tamp.rg.conflicts`) that leave the matrix with the robot's row and
        g's column, less those priced into the arc driven; 0 without conflicts. It may be
        negative: the conflict bound is admissible but not consistent."""
        priced = self._conflicts
        if priced is None:
            return 0.0
        here = self.k if last < 0 else last
        has = self._rows(mask).has
        rows = has.copy()
        rows[here] = True
        cols = has.copy()
        cols[g] = False
        lost = priced.present(rows, has) - priced.present(has, cols)
        return self.per_metre * (lost - float(self._penalty[here, g]))

    def step_row(self, last: int) -> list[float] | None:
        """`step_cost` (last, g) for every goal g, tabulated once per ``last`` (None above
        `DENSE_LIMIT`: then each step is computed on its own)."""
        row = self._step_rows.get(last)
        if row is None:
            costs = self.step_vector(last)
            if costs is None:
                return None
            row = self._step_rows[last] = costs.tolist()
        return row

    def step_vector(self, last: int) -> np.ndarray | None:
        """`step_row` as an array (None above `DENSE_LIMIT`), tabulated once per ``last``."""
        row = self._step_vectors.get(last)
        if row is None:
            self._prepare()
            if self._dense is None:
                return None
            row = self._step_vectors[last] = (
                self.per_metre * (self._dense[last] + self.carry) + self.per_goal
            )
        return row

    def drive_row(self, a: int) -> list[float]:
        """`drive` (a, b) for every goal b (and the start, at −1), tabulated once per ``a``."""
        row = self._drive_rows.get(a)
        if row is None:
            if self._planar:
                d = self._here_xy - self._here_xy[a]
                row = (self.per_metre * np.hypot(d[:, 0], d[:, 1])).tolist()
            else:
                m, here = self.model.metric, self._here[a]
                row = [self.per_metre * m(here, p) for p in self._here]
            self._drive_rows[a] = row
        return row

    def symmetry(self) -> Symmetry | None:
        """The task's automorphisms (`tamp.rg.symmetry`), found once; None when none."""
        if self._symmetry is False:
            self._prepare()
            found = None
            if self._dense is not None and self.index.acyclic():
                found = find_symmetry(
                    np.array([p.as_tuple() for p in self.pick], dtype=float).reshape(self.k, 3),
                    np.array([p.as_tuple() for p in self.drop], dtype=float).reshape(self.k, 3),
                    np.array(self.start.as_tuple(), dtype=float),
                    self._dense,
                    self.carry,
                    {(a, b) for b, ps in enumerate(self.index.preds) for a in ps},
                )
            self._symmetry = found
        return self._symmetry

    def _predecessor_costs(self, idx: np.ndarray) -> np.ndarray:
        """Approach costs among the remaining goals ``idx``; forbidden pairs are `_BIG`.

        Entry [a, b]: from the drop of idx[a] to the pick of idx[b]; forbidden when a == b
        or idx[a] must come after idx[b] (it cannot be the point b is approached from).
        """
        sub = self._approach(idx, idx)
        np.fill_diagonal(sub, _BIG)
        if self._blocked is not None:
            sub[self._blocked[np.ix_(idx, idx)]] = _BIG
            return sub
        rmask = 0
        for i in idx.tolist():
            rmask |= 1 << i
        pos = np.full(self.k, -1, dtype=np.intp)
        pos[idx] = np.arange(len(idx))
        for b, g in enumerate(idx.tolist()):
            after = self._successors(g) & rmask
            if after:
                sub[pos[_bit_positions(after, self._nbytes, self.k)], b] = _BIG
        return sub

    def bound(
        self, mask: int, last: int, children: bool = True, known: Bound | None = None
    ) -> Bound:
        """The admissible bound of state (mask, last), with its optimal assignment and (when
        ``children``) a lower bound of each child's bound (`_forced_robot_row`).

        ``known``: the state's bound when already solved (its own, or `Bound.restricted`
        from its parent): only the children's bounds are computed then, no assignment is
        solved.
        """
        rows = self._rows(mask)
        idx = rows.idx
        n = len(idx)
        if n == 0:
            return Bound(0.0)
        carry = rows.carry
        if n > BOUND_LIMIT:
            return Bound(self.per_metre * carry + self.per_goal * n)
        self._prepare()
        here = self.k if last < 0 else last
        # the robot drives to an enabled goal first, and the goal left unassigned (the last
        # one) has no successors: the dummy column n takes only such rows, never the robot's
        if self._square is not None:  # one gather: the robot's row, then the remaining drops
            at = rows.at.copy()
            at[0] = here
            cost = self._square[at[:, None], rows.cols]
        else:
            cost = np.empty((n + 1, n + 1))
            cost[0, :n] = self._approach(np.array([here]), idx)[0]
            cost[1:, :n] = self._predecessor_costs(idx)
            cost[0, n] = _BIG
            cost[1:, n] = self._dummy[idx]
        cost[0, :n][rows.waiting] = _BIG
        # conflicting arcs are priced into the table: their multipliers come back off
        priced = self._conflicts
        if priced is not None:
            inr = rows.has.copy()  # the matrix's rows: the remaining goals and the robot's
            inr[here] = True
            carry -= priced.present(inr, rows.has)
        if n == 1:
            return Bound(self.per_metre * (carry + float(cost[0, 0])) + self.per_goal)
        self.bounds_solved += 1
        if self.bound_kind == "min":
            empty = float(cost[:, :n].min(axis=0).sum())
            return Bound(self.per_metre * (carry + empty) + self.per_goal * n)
        assign = known.assign if known is not None else None
        if known is not None and known.pairs is not None:
            r, c = known.pairs
        elif assign is not None and len(assign) == n:
            rows_of = np.fromiter(assign.keys(), dtype=np.intp, count=n)
            cols_of = np.fromiter(assign.values(), dtype=np.intp, count=n)
            r = np.arange(n + 1)
            c = np.full(n + 1, n, dtype=np.intp)  # the row absent from the dict: the dummy
            c[np.where(rows_of < 0, 0, np.searchsorted(idx, rows_of) + 1)] = np.searchsorted(
                idx, cols_of
            )
        else:
            r, c = linear_sum_assignment(cost)
            real = c < n  # the row on the dummy column is unassigned
            row_goal = rows.at.copy()
            row_goal[0] = -1
            assign = dict(zip(row_goal[r[real]].tolist(), idx[c[real]].tolist(), strict=True))
        empty = float(cost[r, c].sum())
        h = self.per_metre * (carry + empty) + self.per_goal * n
        if not children:
            return Bound(h, assign=assign, pairs=(r, c))
        child_empty = _forced_robot_row(cost, r, c, empty)
        child_carry = rows.carry - self.carry[idx]
        if priced is not None:  # a child's matrix loses the robot's row and its goal's column
            child_carry -= priced.present_without(rows.has, rows.has, self.k + 1)[idx]
        child = self.per_metre * (child_carry + child_empty) + self.per_goal * (n - 1)
        return Bound(h, idx, child, assign, (r, c))

    def heuristic(self, mask: int, last: int) -> float:
        """Admissible lower bound on the cost of achieving every remaining goal."""
        return self.bound(mask, last).h

    def order_cost(self, order: list[str]) -> float:
        """Cost of a given order (no feasibility check)."""
        pos = {g: i for i, g in enumerate(self.index.ids)}
        last, total = -1, 0.0
        for gid in order:
            g = pos[gid]
            total += self.step_cost(last, g)
            last = g
        return total


def astar(problem: OrderProblem, symmetry: bool = True) -> SearchResult | None:
    """Cheapest constraint-respecting order of all goals, or None when none exists.

    Bounds are solved only where they can change what is expanded, and children are
    generated only when they can be next (module notes): a state whose optimal assignment
    is known (the relaxation's own choice from its parent) queues that one child with its
    exact bound, and the rest of its children as one deferred entry at the state's own f
    (a lower bound of each of theirs: partial expansion). The deferred entry, popped against
    a competitor, solves the state once for a lower bound of every child
    (`_forced_robot_row`) and queues the siblings with it; a child popped against a
    competitor solves its own assignment and is queued again when that raises its f.

    ``symmetry``: merge states that an automorphism of the task maps onto each other
    (`tamp.rg.symmetry`); every state is then kept as its class representative, and the
    order is mapped back to the real goals at the end.
    """
    index = problem.index
    if not index.acyclic():
        return None
    sym = problem.symmetry() if symmetry else None
    perms = sym.perms if sym is not None else None
    full = index.full
    start: tuple[int, int] = (0, -1)
    best_g: dict[tuple[int, int], float] = {start: 0.0}
    b0 = problem.bound(0, -1, children=False)
    # a solved bound per state (not a lazy one): its own assignment, or its parent's family
    solved_h: dict[tuple[int, int], float] = {start: b0.h}
    own: dict[tuple[int, int], Bound] = {start: b0}  # a state's assignment, when known
    family: dict[tuple[int, int], np.ndarray | None] = {}  # a bound of every child (`children_of`)
    # state -> (parent, goal achieved in the parent's frame, automorphism to the child's)
    parent: dict[tuple[int, int], tuple[tuple[int, int], int, int]] = {}
    enabled: dict[int, tuple[int, ...]] = {0: index.initial()}
    lasts: dict[int, list[int]] = {0: [-1]}  # states (mask, last) queued, for dominance
    # a deferred state -> (its g, its siblings not yet queued: (f, goal), the least f last)
    waiting: dict[tuple[int, int], tuple[float, list[tuple[float, int]]]] = {}
    step_row, drive_row, step_cost = problem.step_row, problem.drive_row, problem.step_cost
    step_vector = problem.step_vector
    push, pop = heapq.heappush, heapq.heappop

    def children_of(p: tuple[int, int]) -> np.ndarray | None:
        """A lower bound of every child of ``p``, by goal (NaN: none; None: no bound for any
        child), one solve per state, kept."""
        if p in family:
            return family[p]
        fb = problem.bound(*p, known=own.get(p))
        fam = None
        if fb.goals is not None and fb.child is not None:
            fam = np.full(problem.k, np.nan)
            fam[fb.goals] = np.maximum(fb.child, 0.0)
        family[p] = fam
        return fam

    tie = itertools.count()
    # (f to 1e-6, lazy?, -g, tie, mask, last, queued h, deferred?): on equal f, exact
    # bounds first — a lazy sibling ties with its parent's f and must not be solved first
    heap = [(_key(b0.h), False, 0.0, next(tie), 0, -1, b0.h, False)]
    expanded = generated = 0
    while heap:
        f, _, neg_g, _, mask, last, lazy, deferred = pop(heap)
        g_cost = -neg_g
        state = (mask, last)
        if g_cost > best_g.get(state, INF) + 1e-12:
            continue  # stale entry
        if not deferred and state not in solved_h and heap:  # lazy bound against a competitor
            p, pg, _ = parent[state]
            fam = children_of(p)
            exact = float(fam[pg]) if fam is not None else math.nan
            # the queued h(parent) − step bounds it too (the priced bound is not consistent)
            hc = solved_h[state] = lazy if math.isnan(exact) else max(lazy, exact)
            fc = _key(g_cost + hc)
            if fc > f:
                push(heap, (fc, False, neg_g, next(tie), mask, last, hc, False))
                continue
        h = solved_h.get(state, lazy)
        if mask == full:
            return _result(problem, state, parent, perms, g_cost, expanded, generated)
        b = own.get(state)
        if not deferred:
            if b is None and heap and state in solved_h:  # its assignment, for its own choice
                b = own[state] = problem.bound(mask, last, children=False)
                if b.h > h:  # its parent gave a lower bound only (module notes): re-queue
                    h = solved_h[state] = b.h
                    fs = _key(g_cost + h)
                    if fs > f:
                        push(heap, (fs, False, neg_g, next(tie), mask, last, h, False))
                        continue
            expanded += 1
        here = enabled.get(mask)
        if here is None:  # derived from the parent's set (only last's successors join)
            (pmask, _), pg, which = parent[state]
            here = index.enabled_after(enabled[pmask], pmask, pg)
            if which:
                assert perms is not None  # a nonzero automorphism index implies a symmetry
                perm = perms[which]
                here = tuple(sorted(perm[j] for j in here))
            enabled[mask] = here
        choice = b.assign.get(-1) if b is not None and b.assign is not None else None
        # the relaxation ignores the ordering constraints, so its choice may not be enabled yet
        if not deferred and choice is not None and len(here) > 1 and choice in here:
            here = (choice,)  # partial expansion: the rest waits in one deferred entry
            push(heap, (f, True, neg_g, next(tie), mask, last, h, True))
        steps = step_row(last)
        fam = None
        if deferred:  # the siblings of the relaxation's choice, in order of their f
            todo = waiting.get(state)
            if todo is None or todo[0] != g_cost:  # its first pop (at this g)
                # with a competitor queued, solve this state once for a bound of every child,
                # rather than queue them lazily and re-queue each
                fam = children_of(state) if heap else None
                todo = waiting[state] = (
                    g_cost,
                    _sibling_order(here, fam, step_vector(last), f, g_cost),
                )
            rest = todo[1]
            now = []
            while rest and rest[-1][0] <= f:
                now.append(rest.pop()[1])
            if rest:  # the others wait again, at the least f among them
                push(heap, (rest[-1][0], True, neg_g, next(tie), mask, last, h, True))
            else:
                del waiting[state]
            here = tuple(now)
            fam = family.get(state)
        images = sym.images(mask) if sym is not None else []
        for g in here:
            if sym is None:
                child_mask, child_last, which = mask | 1 << g, g, 0
            else:
                child_mask, child_last, which = sym.canonical(images, g)
            child = (child_mask, child_last)
            step = _step(steps, step_cost, last, g)
            cost = g_cost + step
            if cost + 1e-12 >= best_g.get(child, INF):
                continue
            queued = lasts.get(child_mask)
            if queued is None:
                queued = lasts[child_mask] = []
            elif _dominated(drive_row, best_g, queued, child_mask, child_last, cost):
                continue
            best_g[child] = cost
            parent[child] = (state, g, which)
            if child_last not in queued:
                queued.append(child_last)
            generated += 1
            hc = solved_h.get(child)
            key = None
            if hc is None:
                cb, gain = None, 0.0
                if g == choice:
                    assert b is not None  # choice comes from b's assignment
                    child_real = mask | 1 << g  # the child in this state's frame
                    gain = problem.chain_gain(mask, last, g)
                    cb = b.restricted(g, step - gain, partial(index.ready, child_real))
                if cb is not None:
                    if which:
                        assert perms is not None  # as above: which > 0 only under a symmetry
                        cb = cb.mapped(perms[which])
                    # h − step bounds every child too (h is admissible): keep the larger
                    hc = solved_h[child] = max(0.0, cb.h, h - step)
                    own[child] = cb
                elif fam is not None and not math.isnan(fam[g]):
                    hc = solved_h[child] = max(float(fam[g]), h - step)
                else:
                    hc = max(0.0, h - step)
                if (
                    h >= step
                    and (cb is None or gain <= 0)
                    and (cb is not None or child not in solved_h)
                ):
                    key = f  # f(child) = f(state) exactly: keep the key (no float drift)
            if key is None:
                key = _key(cost + hc)
            push(
                heap,
                (key, child not in solved_h, -cost, next(tie), child_mask, child_last, hc, False),
            )
    return None


def _result(problem, state, parent, perms, cost, expanded, generated) -> SearchResult:
    """The order that reached ``state``, in real goals: each step was taken in its parent's
    frame, and the automorphisms met on the way compose back to the start's (identity)."""
    steps = []
    while state in parent:
        state, g, which = parent[state]
        steps.append((g, which))
    ids = problem.index.ids
    if perms is None:
        return SearchResult(
            [ids[g] for g, _ in reversed(steps)], cost, expanded, generated, problem.bounds_solved
        )
    to_real = list(range(problem.k))  # the current frame's goal -> the real goal
    order = []
    for g, which in reversed(steps):
        order.append(ids[to_real[g]])
        if which:  # the child's frame is perms[which] of the parent's: invert it
            perm = perms[which]
            nxt = [0] * problem.k
            for j, pj in enumerate(perm):
                nxt[pj] = to_real[j]
            to_real = nxt
    return SearchResult(
        order, problem.order_cost(order), expanded, generated, problem.bounds_solved
    )


def _sibling_order(here, fam, steps, f: float, g_cost: float) -> list[tuple[float, int]]:
    """The goals ``here`` with a lower bound of their child's f, the least f *last*.

    ``fam``: the children's bounds (`children_of`; None, or NaN for a goal: f, their
    parent's); ``steps``: `OrderProblem.step_vector` (None: f for all). Each bound is
    lowered by 1e-6 so that it is never above the child's key rounded by `_key`: a sibling
    is queued no later than its f is reached.
    """
    if fam is None or steps is None:
        return [(f, g) for g in reversed(here)]
    goals = np.fromiter(here, dtype=np.intp, count=len(here))
    est = g_cost + steps[goals] + fam[goals] - 1e-6
    est[np.isnan(est)] = f
    order = np.argsort(-est, kind="stable")
    return list(zip(est[order].tolist(), goals[order].tolist(), strict=True))


def _step(steps: list[float] | None, step_cost, last: int, g: int) -> float:
    """The step cost from ``last`` to ``g``: tabulated (`OrderProblem.step_row`) or computed."""
    return steps[g] if steps is not None else step_cost(last, g)


def _key(f: float) -> float:
    """f rounded to 1e-6 (a micrometre, a microsecond): equal sums in another order tie."""
    return round(f, 6)


def _dominated(drive_row, best_g, lasts, mask: int, g: int, cost: float) -> bool:
    """(mask, g) at ``cost`` is no better than a queued (mask, a): see the module notes."""
    bar = cost - 1e-9
    for a in lasts:
        if a != g and best_g[(mask, a)] + drive_row(a)[g] <= bar:
            return True
    return False
