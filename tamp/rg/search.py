"""Exact weighted search over the reachability graph without building it (§IV-B2).

The search state is (achieved goals, last goal reached): the last goal fixes where the
robot stands, which is what makes edge costs depend on the path. A* with an admissible
heuristic (re-opening states when a cheaper path appears) returns an optimal order:

    h(S, r) = Σ_{g ∉ S} [ per_metre · (carry(g) + min_{u ∈ U(g)} |u − pick(g)|) + per_goal ]

where ``carry(g)`` is fixed by the per-object goal chain, and ``U(g)`` holds the robot's
position and the drop points of the remaining goals that may precede ``g`` (not its
successors in C). Each remaining goal is approached from exactly one such point, so ``h``
never overestimates.
"""

from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

import numpy as np

from tamp.demo.model import Demonstration
from tamp.rg.costs import CostModel
from tamp.rg.graph import GoalIndex

INF = float("inf")


@dataclass(frozen=True)
class SearchResult:
    """An optimal goal order, its cost, and how much work the search did."""

    order: list[str]
    cost: float
    expanded: int
    generated: int


class OrderProblem:
    """Precomputed geometry of a demonstration for the search (and for brute force)."""

    def __init__(self, demo: Demonstration, model: CostModel):
        self.demo = demo
        self.model = model
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
        # a goal may not be approached from a goal that must come after it
        after = _successor_closure(self.index)
        self.bound = approach[:k].copy()
        for g in range(k):
            for s in range(k):
                if after[g] >> s & 1 or s == g:
                    self.bound[s, g] = INF
        self.per_metre = model.per_metre
        self.per_goal = model.per_goal
        # plain-float copies for the scalar hot path of `step_cost`
        self._approach = approach.tolist()
        self._carry = self.carry.tolist()

    def step_cost(self, last: int, g: int) -> float:
        """Cost of achieving goal ``g`` with the robot at the drop of ``last`` (−1: start)."""
        row = len(self.drop) if last < 0 else last
        return self.per_metre * (self._approach[row][g] + self._carry[g]) + self.per_goal

    def heuristic(self, mask: int, last: int) -> float:
        k = len(self.drop)
        rem = [i for i in range(k) if not mask >> i & 1]
        if not rem:
            return 0.0
        row = k if last < 0 else last
        idx = np.array(rem)
        best = self.approach[row, idx]
        if len(rem) > 1:
            best = np.minimum(best, self.bound[np.ix_(idx, idx)].min(axis=0))
        total = float(self.carry[idx].sum() + best.sum())
        return self.per_metre * total + self.per_goal * len(rem)

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
    parent: dict[tuple[int, int], tuple[int, int]] = {}
    tie = itertools.count()
    heap = [(problem.heuristic(0, -1), 0.0, next(tie), 0, -1)]
    expanded = generated = 0
    while heap:
        f, g_cost, _, mask, last = heapq.heappop(heap)
        if g_cost > best_g.get((mask, last), INF) + 1e-12:
            continue  # stale entry
        if mask == full:
            order = []
            state = (mask, last)
            while state != start:
                order.append(index.ids[state[1]])
                state = parent[state]
            return SearchResult(order[::-1], g_cost, expanded, generated)
        expanded += 1
        for g in index.enabled(mask):
            child = (mask | 1 << g, g)
            cost = g_cost + problem.step_cost(last, g)
            if cost + 1e-12 < best_g.get(child, INF):
                best_g[child] = cost
                parent[child] = (mask, last)
                generated += 1
                heapq.heappush(
                    heap, (cost + problem.heuristic(child[0], g), cost, next(tie), child[0], g)
                )
    return None
