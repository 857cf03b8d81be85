"""Baseline: the product-automaton reactive planner that Lemma 2 compares LOTS against.

The classical approach ([7]-[10] in Zhou et al.) assumes global observability: the
transition system is the whole workspace — counts in W^A *and* W^B for every class — and the
planner searches the explicit product ``TS × B``. This module builds that product
(every TS state × every automaton state, every executable letter: deliveries, ∅, and taking
an object out of W^B into the waste basket, or back to W^A with our return action,
`Task.returns`) and runs Dijkstra in it from the
observed product state to a goal (accepting automaton state, W^B = ``s^B_final``) — the same
goal (a live accepting state with W^B at the end of a round of some accepting way,
`Lots.goals`) and costs as the LOTS planner, so both return runs of equal cost.

A state that is not in the product (a person added or removed objects, dis_2, so the totals
changed) is *unforeseen*: the product is rebuilt for the new totals before searching.
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass

from tamp.lots.automaton import EMPTY, Automaton
from tamp.lots.lots import Counts, Lots
from tamp.lots.task import Task

# action codes stored with each product edge
_IDLE, _MOVE, _TO_A, _TO_WASTE = 0, 1, 2, 3


@dataclass
class ProductPlan:
    """A run in the product: (action, proposition or class) pairs and its total cost."""

    actions: list[tuple[str, str]]
    cost: float


class ProductPlanner:
    """Explicit ``TS × B`` over global counts; Dijkstra from the observed product state."""

    def __init__(
        self,
        aut: Automaton,
        lots: Lots,
        task: Task,
        totals: Counts,
        goal_states: frozenset[int] | None = None,
    ):
        self.aut = aut
        #: automaton states a goal may end in (default the live accepting ones; the LOTS
        #: controller also ends a round where the round's cycle is accepted forever,
        #: `Planner.cycle_ok`)
        self.goal_states = aut.live_accepting if goal_states is None else goal_states
        self.lots = lots
        self.props = [p.name for p in task.propositions]
        self.cost_of = [p.cost for p in task.propositions]
        self.prop_cls = [lots.prop_class[p] for p in self.props]
        self.remove_cost = task.remove_cost
        self.returns = task.returns
        if len(self.props) > 31 or len(lots.classes) > 31:
            raise ValueError("the product baseline packs proposition indices in 5 bits")
        self.builds = 0
        self.build(totals)

    # ------------------------------------------------------------------ construction
    def build(self, totals: Counts) -> None:
        """Enumerate every TS state and every product edge (the cost Lemma 2 counts)."""
        self.totals = tuple(totals)
        self.builds += 1
        aut, n_cls = self.aut, len(totals)
        # per class: the (a, b) pairs with a + b <= total, and the radix of that class
        self._pairs = [
            [(a, b) for a in range(t + 1) for b in range(t + 1 - a)] for t in self.totals
        ]
        index = [{p: i for i, p in enumerate(pairs)} for pairs in self._pairs]
        radix = [1] * n_cls
        for c in range(1, n_cls):
            radix[c] = radix[c - 1] * len(self._pairs[c - 1])
        n_ts = math.prod(len(p) for p in self._pairs)
        nq = aut.num_states
        self.n_ts, self.nq, self._radix = n_ts, nq, radix
        # per-class moves as index deltas (None when not allowed)
        move: list[list[int | None]] = [[None] * len(p) for p in self._pairs]
        to_a: list[list[int | None]] = [[None] * len(p) for p in self._pairs]
        to_waste: list[list[int | None]] = [[None] * len(p) for p in self._pairs]
        for c, pairs in enumerate(self._pairs):
            for i, (a, b) in enumerate(pairs):
                if a >= 1:
                    move[c][i] = (index[c][(a - 1, b + 1)] - i) * radix[c]
                if b >= 1:
                    to_a[c][i] = (index[c][(a + 1, b - 1)] - i) * radix[c]
                    to_waste[c][i] = (index[c][(a, b - 1)] - i) * radix[c]
        succ_empty = [aut.successors(q, EMPTY) for q in range(nq)]
        succ_prop = [[aut.successors(q, frozenset({p})) for p in self.props] for q in range(nq)]
        goals = self.lots.goal_set
        goal_ts = bytearray(n_ts)
        digits_of = []
        for s in range(n_ts):
            digits = []
            rest = s
            for c in range(n_cls):
                rest, d = divmod(rest, len(self._pairs[c]))
                digits.append(d)
            digits_of.append(digits)
            if tuple(self._pairs[c][d][1] for c, d in enumerate(digits)) in goals:
                goal_ts[s] = 1
        live = self.goal_states
        self.goal = [bool(goal_ts[s]) and q in live for s in range(n_ts) for q in range(nq)]
        # edges: node = s * nq + q; each edge packed as (succ << 8 | code << 5 | arg)
        # with arg the proposition or class index (< 32)
        adj: list[list[int]] = [[] for _ in range(n_ts * nq)]
        for s in range(n_ts):
            digits = digits_of[s]
            base = s * nq
            for q in range(nq):
                out = adj[base + q]
                for q2 in succ_empty[q]:
                    out.append(((s * nq + q2) << 8) | (_IDLE << 5))
                for k, cls in enumerate(self.prop_cls):
                    d = move[cls][digits[cls]]
                    if d is None:
                        continue
                    s2 = s + d
                    for q2 in succ_prop[q][k]:
                        out.append(((s2 * nq + q2) << 8) | (_MOVE << 5) | k)
                for c in range(n_cls):
                    da, dw = to_a[c][digits[c]], to_waste[c][digits[c]]
                    if da is None:
                        continue
                    for q2 in succ_empty[q]:
                        if self.returns:
                            out.append((((s + da) * nq + q2) << 8) | (_TO_A << 5) | c)
                        out.append((((s + dw) * nq + q2) << 8) | (_TO_WASTE << 5) | c)
        self.adj = adj

    @property
    def num_states(self) -> int:
        return self.n_ts * self.nq

    @property
    def num_edges(self) -> int:
        return sum(len(x) for x in self.adj)

    def node(self, q: int, a: Counts, b: Counts) -> int | None:
        s = 0
        for c, (x, y) in enumerate(zip(a, b, strict=True)):
            if x + y > self.totals[c]:
                return None
            pairs = self._pairs[c]
            s += pairs.index((x, y)) * self._radix[c]
        return s * self.nq + q

    # ------------------------------------------------------------------ search
    def replan(self, q: int, a: Counts, b: Counts) -> ProductPlan | None:
        """Dijkstra in the product from the observed ``(s^A_s^B, q)``; rebuild if unforeseen."""
        totals = tuple(x + y for x, y in zip(a, b, strict=True))
        if totals != self.totals:
            self.build(totals)
        start = self.node(q, a, b)
        assert start is not None
        dist = {start: 0.0}
        parent: dict[int, tuple[int, int]] = {}
        tie = itertools.count()
        heap = [(0.0, next(tie), start)]
        done = set()
        adj, goal = self.adj, self.goal
        while heap:
            d, _, u = heapq.heappop(heap)
            if u in done:
                continue
            done.add(u)
            if goal[u]:
                return ProductPlan(self._actions(parent, u), d)
            for packed in adj[u]:
                v = packed >> 8
                code = (packed >> 5) & 7
                if code == _MOVE:
                    w = self.cost_of[packed & 31]
                elif code == _IDLE:
                    w = 0.0
                else:
                    w = self.remove_cost
                nd = d + w
                if v not in dist or nd < dist[v]:
                    dist[v] = nd
                    parent[v] = (u, packed)
                    heapq.heappush(heap, (nd, next(tie), v))
        return None

    def _actions(self, parent: dict[int, tuple[int, int]], u: int) -> list[tuple[str, str]]:
        out = []
        while u in parent:
            u, packed = parent[u]
            code, arg = (packed >> 5) & 7, packed & 31
            if code == _MOVE:
                out.append(("move", self.props[arg]))
            elif code == _TO_A:
                out.append(("remove", self.lots.classes[arg]))
            elif code == _TO_WASTE:
                out.append(("remove", self.lots.classes[arg]))
        out.reverse()
        return out
