"""Exact weighted search over the reachability graph without building it (§IV-B2).

The search state is (achieved goals, last goal reached): the last goal fixes where the
robot stands, which is what makes edge costs depend on the path. A* with an admissible
heuristic (re-opening states when a cheaper path appears) returns an optimal order:

    h(S, r) = per_metre · (Σ_{g ∉ S} carry(g) + E(S, r)) + per_goal · |remaining|

``carry(g)`` is fixed by the per-object goal chain. ``E`` bounds the remaining empty drives
from below. Every remaining goal g is approached from exactly one point: the robot's
position or the drop point of another remaining goal that may precede it (not one of its
successors in C). Two bounds are available:

* ``"min"`` — each goal's cheapest such approach, independently;
* ``"assignment"`` — the assignment-problem relaxation: the approach points must be
  distinct (the relaxation that lower-bounds asymmetric TSP tours). It is never weaker
  and prunes far more on hard layouts, at a higher cost per evaluation.

The true remaining route is one such assignment, so both never overestimate. Above
`BOUND_LIMIT` remaining goals neither is computed and ``E = 0`` (still admissible; the
search stays exact, it only prunes less).

What keeps the search cheap (no geometry is stored per pair of goals; memory is O(goals)
plus the states visited):

* **Lazy bounds.** A child is queued with ``h(parent) − step`` (admissible, since h(parent)
  is) and its own bound is computed only when it is popped; if that raises f, it is queued
  again. A state popped while nothing else is queued is expanded without computing its
  bound: with no competitor the bound cannot change what is expanded next (one object's
  chain of goals needs no bound at all).
* **The relaxation's own choice.** When the assignment sends the robot to goal g* next,
  the rest of that assignment is an optimal assignment of the child (S ∪ {g*}, g*) — its
  rows are the parent's minus the robot's, its columns minus g*, and the child's robot row
  is g*'s drop row — so the child's bound is ``h − step(r, g*)`` exactly and its own
  assignment is known: following the relaxation's chain costs no solve at all.
* **Partial expansion.** A state with a known choice queues only that child (same f) and
  one deferred entry at its own f for the others (each of their f is at least that); on
  equal f, exact bounds pop before lazy ones. The deferred entry is expanded only if the
  chain stops paying (a subtour of the relaxation must be broken): then the siblings are
  queued with the lazy bound, and the first one popped against a competitor solves the
  parent once with every child's exact bound (one Bellman-Ford pass, `_forced_robot_row`).
  f is compared to 1e-6 (`_key`): the same costs summed in another order must tie, or
  float drift sends the search through every state of a plateau of equal f (the cliff of
  wide tasks: 1,000 independent goals in a row took 9 minutes, now 2 s).
* **Dominance.** With a metric cost (triangle inequality), a state (S, b) reached at cost
  g_b is no better than (S, a) reached at g_a when ``g_a + per_metre·d(a, b) ≤ g_b``: any
  completion from b can be driven from a through b's position for at most that much more.
  Such states are not queued.

Ties on f (to 1e-6) go to exact bounds, then to deeper states.
"""

from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from tamp.demo.model import Demonstration
from tamp.rg.costs import CostModel, planar
from tamp.rg.graph import GoalIndex

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
    """A state's bound ``h``, and ``child[i]``: the bound of the child achieving ``goals[i]``."""

    h: float
    goals: np.ndarray | None = None
    child: np.ndarray | None = None
    #: the optimal assignment behind ``h``: approach row (a goal's drop, -1: the robot) →
    #: the goal it approaches; rows absent are unassigned (None: not an assignment bound)
    assign: dict[int, int] | None = None

    def restricted(self, g: int, step: float) -> Bound | None:
        """The bound of the child achieving ``g`` when ``g`` is the relaxation's own choice.

        The rest of an optimal assignment is an optimal assignment of the child (its matrix
        is the parent's without the robot's row and g's column; g's drop row becomes the
        robot's), so the child's bound is ``h − step`` and its assignment is known: no solve.
        """
        if self.assign is None or self.assign.get(-1) != g:
            return None
        child = dict(self.assign)
        del child[-1]
        if g in child:
            child[-1] = child.pop(g)
        return Bound(self.h - step, assign=child)

    def of_child(self, g: int) -> float | None:
        """The (exact) bound of the child that achieves goal ``g``; None when unknown."""
        if self.goals is None or self.child is None:
            return None
        return float(self.child[np.searchsorted(self.goals, g)])


def _bit_positions(mask: int, nbytes: int, k: int) -> np.ndarray:
    """Positions of the set bits of ``mask`` (< k), ascending."""
    bits = np.unpackbits(
        np.frombuffer(mask.to_bytes(nbytes, "little"), dtype=np.uint8), bitorder="little"
    )
    return np.flatnonzero(bits[:k])


def _forced_robot_row(cost: np.ndarray, rows: np.ndarray, cols: np.ndarray, opt: float):
    """Optimal assignment value once the robot's row (row 0) is forced onto each column.

    ``rows → cols`` is an optimal assignment of the (n+1)×n matrix ``cost`` (squared with a
    zero-cost dummy column that takes the unassigned row). Forcing row 0 onto column g
    frees its column σ(0) and displaces g's row ρ(g), which takes another column, whose row
    moves on, until some row takes σ(0): the cheapest such alternating path is a shortest
    path from g to σ(0) over arcs j → j' of weight c(ρ(j), j') − c(ρ(j), j), without
    negative cycles because the assignment is optimal (Bellman-Ford, vectorised). Returns,
    per real column g, the optimum without row 0 and column g:
    ``opt − c(0, σ(0)) + dist(g → σ(0))`` — exactly the child's assignment value, since
    the child's matrix is the parent's without the robot's row and g's column.
    """
    m, n = cost.shape
    square = np.hstack((cost, np.zeros((m, 1))))
    sigma = np.full(m, n, dtype=np.intp)
    sigma[rows] = cols
    rho = np.empty(m, dtype=np.intp)
    rho[sigma] = np.arange(m)
    by_col = square[rho]  # row j: the costs of the row now holding column j
    # wt[j', j]: weight of the arc j -> j' (transposed so a round gathers rows)
    wt = np.ascontiguousarray((by_col - by_col[np.arange(m), np.arange(m)][:, None]).T)
    target = sigma[0]
    dist = np.full(m, np.inf)
    dist[target] = 0.0
    changed = np.array([target])
    for _ in range(m):  # a round relaxes only through the columns the last one improved
        cand = (wt[changed] + dist[changed][:, None]).min(axis=0)
        better = cand < dist - 1e-12
        better[target] = False
        if not better.any():
            break
        dist = np.where(better, cand, dist)
        changed = np.flatnonzero(better)
    return opt - square[0, target] + dist[:n]


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
        if self.k == 0:
            return np.empty(0, dtype=np.intp)
        return _bit_positions(~mask & ((1 << self.k) - 1), self._nbytes, self.k)

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
        """Up to `DENSE_LIMIT` goals, tabulate approach costs and the successor relation once."""
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
        self, mask: int, last: int, children: bool = True, assign: dict[int, int] | None = None
    ) -> Bound:
        """The admissible bound of state (mask, last), with its optimal assignment and (when
        ``children``) the exact bounds of all its children (`_forced_robot_row`).

        ``assign``: the state's optimal assignment when already known (`Bound.restricted`):
        only the children's bounds are computed then, no assignment is solved.
        """
        idx = self.remaining(mask)
        n = len(idx)
        if n == 0:
            return Bound(0.0)
        carry = float(self.carry[idx].sum())
        if n > BOUND_LIMIT:
            return Bound(self.per_metre * carry + self.per_goal * n)
        self._prepare()
        row = self._approach(np.array([self.k if last < 0 else last]), idx)[0]
        if n == 1:
            return Bound(self.per_metre * (carry + float(row[0])) + self.per_goal)
        self.bounds_solved += 1
        sub = self._predecessor_costs(idx)
        if self.bound_kind == "min":
            empty = float(np.minimum(row, sub.min(axis=0)).sum())
            return Bound(self.per_metre * (carry + empty) + self.per_goal * n)
        cost = np.vstack((row, sub))
        if assign is not None and len(assign) == n:
            rows_of = np.fromiter(assign.keys(), dtype=np.intp, count=n)
            cols_of = np.fromiter(assign.values(), dtype=np.intp, count=n)
            r = np.where(rows_of < 0, 0, np.searchsorted(idx, rows_of) + 1)
            c = np.searchsorted(idx, cols_of)
            order = np.argsort(r)
            r, c = r[order], c[order]
        else:
            r, c = linear_sum_assignment(cost)
        empty = float(cost[r, c].sum())
        h = self.per_metre * (carry + empty) + self.per_goal * n
        goal_of = [-1, *idx.tolist()]
        cols = idx[c].tolist()
        assign = {goal_of[i]: j for i, j in zip(r.tolist(), cols, strict=True)}
        if not children:
            return Bound(h, assign=assign)
        child_empty = _forced_robot_row(cost, r, c, empty)
        child = self.per_metre * (carry - self.carry[idx] + child_empty) + self.per_goal * (n - 1)
        return Bound(h, idx, child, assign)

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


def astar(problem: OrderProblem) -> SearchResult | None:
    """Cheapest constraint-respecting order of all goals, or None when none exists.

    Bounds are solved only where they can change what is expanded, and children are
    generated only when they can be next (module notes): a state whose optimal assignment
    is known (the relaxation's own choice from its parent) queues that one child with its
    exact bound, and the rest of its children as one deferred entry at the state's own f
    (a lower bound of each of theirs: partial expansion). The deferred entry, popped, queues
    the siblings with the lazy bound; the first sibling popped against a competitor solves
    the parent once with every child's exact bound (`_forced_robot_row`).
    """
    index = problem.index
    if not index.acyclic():
        return None
    full = index.full
    start = (0, -1)
    best_g = {start: 0.0}
    b0 = problem.bound(0, -1, children=False)
    exact_h: dict[tuple[int, int], float] = {start: b0.h}
    own: dict[tuple[int, int], Bound] = {start: b0}  # a state's assignment, when known
    family: dict[tuple[int, int], Bound] = {}  # solved with the exact bounds of all children
    parent: dict[tuple[int, int], tuple[int, int]] = {}
    enabled: dict[int, tuple[int, ...]] = {0: index.initial()}
    lasts: dict[int, list[int]] = {0: [-1]}  # states (mask, last) queued, for dominance
    tie = itertools.count()
    # (f to 1e-9, lazy?, -g, tie, mask, last, queued h, deferred?): on equal f, exact
    # bounds first — a lazy sibling ties with its parent's f and must not be solved first
    heap = [(_key(b0.h), False, 0.0, next(tie), 0, -1, b0.h, False)]
    expanded = generated = 0
    while heap:
        f, _, neg_g, _, mask, last, lazy, deferred = heapq.heappop(heap)
        g_cost = -neg_g
        state = (mask, last)
        if g_cost > best_g.get(state, INF) + 1e-12:
            continue  # stale entry
        if not deferred and state not in exact_h and heap:  # lazy bound against a competitor
            p = parent[state]
            fam = family.get(p)
            if fam is None:
                pb = own.get(p)
                fam = family[p] = problem.bound(*p, assign=pb.assign if pb else None)
            exact = fam.of_child(last)
            hc = exact_h[state] = lazy if exact is None else max(0.0, exact)
            if _key(g_cost + hc) > f:
                heapq.heappush(
                    heap, (_key(g_cost + hc), False, neg_g, next(tie), mask, last, hc, False)
                )
                continue
        h = exact_h.get(state, lazy)
        if mask == full:
            order = []
            while state != start:
                order.append(index.ids[state[1]])
                state = parent[state]
            return SearchResult(order[::-1], g_cost, expanded, generated, problem.bounds_solved)
        b = own.get(state)
        if not deferred:
            expanded += 1
            if b is None and heap and state in exact_h:  # its assignment, for its own choice
                b = own[state] = problem.bound(mask, last, children=False)
        here = enabled.get(mask)
        if here is None:  # derived from the parent's set (only last's successors join)
            prev = parent[state][0]
            here = enabled[mask] = index.enabled_after(enabled[prev], prev, last)
        choice = b.assign.get(-1) if b is not None and b.assign is not None else None
        # the relaxation ignores the ordering constraints, so its choice may not be enabled yet
        if not deferred and choice is not None and len(here) > 1 and choice in here:
            here = (choice,)  # partial expansion: the rest waits in one deferred entry
            heapq.heappush(heap, (f, True, neg_g, next(tie), mask, last, h, True))
        for g in here:
            child_mask = mask | 1 << g
            child = (child_mask, g)
            step = problem.step_cost(last, g)
            cost = g_cost + step
            if cost + 1e-12 >= best_g.get(child, INF):
                continue
            if _dominated(problem, best_g, lasts.get(child_mask, ()), child_mask, g, cost):
                continue
            best_g[child] = cost
            parent[child] = state
            queued = lasts.setdefault(child_mask, [])
            if g not in queued:
                queued.append(g)
            generated += 1
            hc = exact_h.get(child)
            key = None
            if hc is None:
                cb = b.restricted(g, step) if b is not None else None
                if cb is not None:
                    hc = exact_h[child] = max(0.0, cb.h)
                    own[child] = cb
                else:
                    hc = max(0.0, h - step)
                if h >= step:  # f(child) = f(state) exactly: keep the key (no float drift)
                    key = f
            if key is None:
                key = _key(cost + hc)
            heapq.heappush(
                heap, (key, child not in exact_h, -cost, next(tie), child_mask, g, hc, False)
            )
    return None


def _key(f: float) -> float:
    """f rounded to 1e-6 (a micrometre, a microsecond): equal sums in another order tie."""
    return round(f, 6)


def _dominated(problem, best_g, lasts, mask: int, g: int, cost: float) -> bool:
    """(mask, g) at ``cost`` is no better than a queued (mask, a): see the module notes."""
    for a in lasts:
        if a != g and best_g[(mask, a)] + problem.drive(a, g) <= cost - 1e-9:
            return True
    return False
