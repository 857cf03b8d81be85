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

The true remaining route is one such assignment, so both never overestimate. Bounds are
evaluated lazily: a child is queued with ``h(parent) − step`` (admissible, since
h(parent) is) and its own bound is computed only when it is popped; if that raises f,
it is queued again. Ties on f go to deeper states.
"""

from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from tamp.demo.model import Demonstration
from tamp.rg.costs import CostModel
from tamp.rg.graph import GoalIndex

INF = float("inf")
_BIG = 1e12  # a forbidden approach; never chosen, because a finite assignment exists
BOUNDS = ("assignment", "min")


@dataclass(frozen=True)
class SearchResult:
    """An optimal goal order, its cost, and how much work the search did."""

    order: list[str]
    cost: float
    expanded: int
    generated: int


class OrderProblem:
    """Precomputed geometry of a demonstration for the search (and for brute force)."""

    def __init__(self, demo: Demonstration, model: CostModel, bound: str = "assignment"):
        if bound not in BOUNDS:
            raise ValueError(f"unknown bound {bound!r} (known: {', '.join(BOUNDS)})")
        self.demo = demo
        self.model = model
        self.bound_kind = bound
        self.index = GoalIndex.of(demo)
        goals = demo.goals
        k = len(goals)
        m = model.metric
        self.pick = [demo.pick_point(g) for g in goals]
        self.drop = [g.pos for g in goals]
        start = demo.robot_start.pos
        self.carry = np.array([m(self.pick[i], self.drop[i]) for i in range(k)])
        # approach[a][b]: from the drop point of goal a (row k: the start) to pick(b)
        approach = np.empty((k + 1, k))
        for a in range(k + 1):
            here = start if a == k else self.drop[a]
            for b in range(k):
                approach[a, b] = m(here, self.pick[b])
        self.approach = approach
        # a goal may not be approached from itself or from a goal that must come after it
        after = _successor_closure(self.index)
        allowed = np.ones((k, k), dtype=bool)
        for g in range(k):
            for s in range(k):
                if after[g] >> s & 1 or s == g:
                    allowed[s, g] = False
        self.predecessor_cost = np.where(allowed, approach[:k], _BIG)
        self.per_metre = model.per_metre
        self.per_goal = model.per_goal
        # plain-float copies for the scalar hot path of `step_cost`
        self._approach = approach.tolist()
        self._carry = self.carry.tolist()
        self._mask_cache: dict[int, tuple[np.ndarray, float, np.ndarray]] = {}

    def step_cost(self, last: int, g: int) -> float:
        """Cost of achieving goal ``g`` with the robot at the drop of ``last`` (−1: start)."""
        row = len(self.drop) if last < 0 else last
        return self.per_metre * (self._approach[row][g] + self._carry[g]) + self.per_goal

    def _remaining(self, mask: int) -> tuple[np.ndarray, float, np.ndarray]:
        """Indices of the remaining goals, their carry sum and their predecessor matrix."""
        hit = self._mask_cache.get(mask)
        if hit is None:
            idx = np.array([i for i in range(len(self.drop)) if not mask >> i & 1])
            sub = self.predecessor_cost[idx][:, idx] if len(idx) else np.empty((0, 0))
            hit = (idx, float(self.carry[idx].sum()) if len(idx) else 0.0, sub)
            if len(self._mask_cache) < 50_000:
                self._mask_cache[mask] = hit
        return hit

    def heuristic(self, mask: int, last: int) -> float:
        """Admissible lower bound on the cost of achieving every remaining goal."""
        idx, carry, sub = self._remaining(mask)
        n = len(idx)
        if n == 0:
            return 0.0
        row = self.approach[len(self.drop) if last < 0 else last, idx]
        if n == 1:
            empty = float(row[0])
        elif self.bound_kind == "min":
            empty = float(np.minimum(row, sub.min(axis=0)).sum())
        else:
            cost = np.vstack((row, sub))
            r, c = linear_sum_assignment(cost)
            empty = float(cost[r, c].sum())
        return self.per_metre * (carry + empty) + self.per_goal * n

    def order_cost(self, order: list[str]) -> float:
        """Cost of a given order (no feasibility check)."""
        pos = {g: i for i, g in enumerate(self.index.ids)}
        last, total = -1, 0.0
        for gid in order:
            g = pos[gid]
            total += self.step_cost(last, g)
            last = g
        return total


def _successor_closure(index: GoalIndex) -> list[int]:
    """For each goal, the bitmask of goals that must come (transitively) after it."""
    k = len(index.ids)
    succ = [0] * k
    for j, p in enumerate(index.preds):
        for i in range(k):
            if p >> i & 1:
                succ[i] |= 1 << j
    changed = True
    while changed:
        changed = False
        for i in range(k):
            acc = succ[i]
            for j in range(k):
                if succ[i] >> j & 1:
                    acc |= succ[j]
            if acc != succ[i]:
                succ[i] = acc
                changed = True
    return succ


def astar(problem: OrderProblem) -> SearchResult | None:
    """Cheapest constraint-respecting order of all goals, or None when none exists."""
    index = problem.index
    full = index.full
    start = (0, -1)
    best_g = {start: 0.0}
    exact_h: dict[tuple[int, int], float] = {start: problem.heuristic(0, -1)}
    parent: dict[tuple[int, int], tuple[int, int]] = {}
    tie = itertools.count()
    heap = [(exact_h[start], 0.0, next(tie), 0, -1)]  # (f, -g, tie, mask, last)
    expanded = generated = 0
    while heap:
        f, neg_g, _, mask, last = heapq.heappop(heap)
        g_cost = -neg_g
        state = (mask, last)
        if g_cost > best_g.get(state, INF) + 1e-12:
            continue  # stale entry
        h = exact_h.get(state)
        if h is None:
            h = exact_h[state] = problem.heuristic(mask, last)
            if g_cost + h > f + 1e-9:
                heapq.heappush(heap, (g_cost + h, neg_g, next(tie), mask, last))
                continue
        if mask == full:
            order = []
            while state != start:
                order.append(index.ids[state[1]])
                state = parent[state]
            return SearchResult(order[::-1], g_cost, expanded, generated)
        expanded += 1
        for g in index.enabled(mask):
            child = (mask | 1 << g, g)
            step = problem.step_cost(last, g)
            cost = g_cost + step
            if cost + 1e-12 < best_g.get(child, INF):
                best_g[child] = cost
                parent[child] = state
                generated += 1
                known = exact_h.get(child)
                hc = known if known is not None else max(0.0, h - step)
                heapq.heappush(heap, (cost + hc, -cost, next(tie), child[0], g))
    return None
