"""The reachability graph of SMP-MRO §IV-B, Alg. 1, with equal states merged.

A node is the set of achieved goals (with the per-object intent chain, this fixes where
every object is); an edge achieves one more goal whose predecessors in C are all achieved
(Alg. 1 line 10, "goal not in constraints"). Alg. 1 expands depth-first and never merges
equal states, so it builds a tree with one node per constraint-respecting *prefix*; we merge
them into a DAG and report both sizes.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache

import networkx as nx

from tamp.demo.model import Demonstration


@dataclass(frozen=True)
class GoalIndex:
    """Goals as bit positions, with the bitmask of their direct predecessors in C."""

    ids: tuple[str, ...]
    preds: tuple[int, ...]

    @staticmethod
    def of(demo: Demonstration) -> GoalIndex:
        ids = tuple(demo.goal_ids)
        pos = {g: i for i, g in enumerate(ids)}
        preds = [0] * len(ids)
        for gi, gj in demo.constraints:
            preds[pos[gj]] |= 1 << pos[gi]
        return GoalIndex(ids, tuple(preds))

    @property
    def full(self) -> int:
        return (1 << len(self.ids)) - 1

    def enabled(self, mask: int) -> Iterator[int]:
        """Goals not yet achieved whose predecessors are all achieved in ``mask``."""
        for i, p in enumerate(self.preds):
            if not mask >> i & 1 and p & mask == p:
                yield i

    def names(self, mask: int) -> frozenset[str]:
        return frozenset(g for i, g in enumerate(self.ids) if mask >> i & 1)


@dataclass(frozen=True)
class RGStats:
    """Sizes of the RG: distinct states and edges (merged DAG) and Alg. 1's tree nodes."""

    states: int | None
    edges: int | None
    alg1_nodes: int
    complete: bool


class RGTooLarge(RuntimeError):
    """Raised when enumerating the RG would exceed the requested limit."""


def _masks(index: GoalIndex, limit: int) -> tuple[list[int], list[tuple[int, int, int]]]:
    seen = {0}
    order = [0]
    edges = []
    frontier = [0]
    while frontier:
        nxt = []
        for m in frontier:
            for g in index.enabled(m):
                child = m | 1 << g
                edges.append((m, child, g))
                if child not in seen:
                    if len(seen) >= limit:
                        raise RGTooLarge(f"the RG has more than {limit} states")
                    seen.add(child)
                    order.append(child)
                    nxt.append(child)
        frontier = nxt
    return order, edges


def alg1_node_count(index: GoalIndex) -> int:
    """Nodes Alg. 1 generates without merging: one per constraint-respecting prefix."""

    @cache
    def count(mask: int) -> int:
        return 1 + sum(count(mask | 1 << g) for g in index.enabled(mask))

    # Deep recursion only on very long goal lists; the cache keeps the work to #states.
    import sys

    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, 10 * len(index.ids) + 100))
    try:
        return count(0)
    finally:
        sys.setrecursionlimit(old)


class ReachabilityGraph:
    """The merged RG of one demonstration, enumerated once (up to ``limit`` states).

    A plan's statistics, its verification gate and its DOT drawing all read this one
    enumeration; the networkx view is built on first use and kept.
    """

    def __init__(self, demo: Demonstration, limit: int = 200_000) -> None:
        self.demo = demo
        self.limit = limit
        self.index = GoalIndex.of(demo)
        try:
            self._masks, self._edges = _masks(self.index, limit)
        except RGTooLarge:
            self._masks, self._edges = None, None
        self._stats: RGStats | None = None
        self._nx: nx.DiGraph | None = None

    @property
    def complete(self) -> bool:
        """False when the RG has more than ``limit`` states (then only stats say so)."""
        return self._masks is not None

    @property
    def stats(self) -> RGStats:
        """State/edge counts when complete, and Alg. 1's node count."""
        if self._stats is None:
            if self._masks is None:
                self._stats = RGStats(None, None, -1, False)
            else:
                self._stats = RGStats(
                    len(self._masks), len(self._edges), alg1_node_count(self.index), True
                )
        return self._stats

    def networkx(self) -> nx.DiGraph:
        """The RG as a networkx DiGraph (see `build_rg`); `RGTooLarge` beyond ``limit``."""
        if self._masks is None:
            raise RGTooLarge(f"the RG has more than {self.limit} states")
        if self._nx is None:
            self._nx = self._to_networkx()
        return self._nx

    def _to_networkx(self) -> nx.DiGraph:
        demo, index = self.demo, self.index
        g = nx.DiGraph(source=demo.source)
        for m in self._masks:
            achieved = index.names(m)
            places = {obj: "P" for obj in demo.objects}
            for goal in demo.goals:  # demonstrated order: the last achieved goal wins
                if goal.id in achieved:
                    places[goal.object] = goal.id
            g.add_node(achieved, places=places, mask=m)
        for m, child, gi in self._edges:
            g.add_edge(index.names(m), index.names(child), goal=index.ids[gi])
        return g


def rg_stats(demo: Demonstration, limit: int = 200_000) -> RGStats:
    """State/edge counts when the RG has at most ``limit`` states, and Alg. 1's count."""
    return ReachabilityGraph(demo, limit).stats


def build_rg(demo: Demonstration, limit: int = 200_000) -> nx.DiGraph:
    """The merged RG as a networkx DiGraph.

    Nodes are ``frozenset`` of achieved goal ids, with attribute ``places`` (object → "P"
    or the id of the goal it last reached); edges carry ``goal`` (the goal achieved).
    Raises `RGTooLarge` beyond ``limit`` states (the planner itself never builds the RG).
    """
    return ReachabilityGraph(demo, limit).networkx()
