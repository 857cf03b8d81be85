"""The reachability graph of SMP-MRO §IV-B, Alg. 1, with equal states merged.

A node is the set of achieved goals (with the per-object intent chain, this fixes where
every object is); an edge achieves one more goal whose predecessors in C are all achieved
(Alg. 1 line 10, "goal not in constraints"). Alg. 1 expands depth-first and never merges
equal states, so it builds a tree with one node per constraint-respecting *prefix*; we merge
them into a DAG and report both sizes.

Cost: the enabled goals of a state are derived from its parent's (`GoalIndex.enabled_after`:
only the successors of the goal just achieved can become enabled), so enumerating the RG
costs O(edges · width) and never O(states · goals): one object's chain of 5,000 goals is a
5,001-state path enumerated in linear time. Alg. 1's node count is a dynamic programme over
the merged DAG (no recursion, so no depth limit).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import networkx as nx

from tamp.demo.model import Demonstration


@dataclass(frozen=True)
class GoalIndex:
    """Goals as bit positions, with their direct predecessors and successors in C."""

    ids: tuple[str, ...]
    preds: tuple[tuple[int, ...], ...]
    succs: tuple[tuple[int, ...], ...]

    @staticmethod
    def of(demo: Demonstration) -> GoalIndex:
        ids = tuple(demo.goal_ids)
        pos = {g: i for i, g in enumerate(ids)}
        preds: list[list[int]] = [[] for _ in ids]
        succs: list[list[int]] = [[] for _ in ids]
        for gi, gj in sorted(demo.constraints):
            preds[pos[gj]].append(pos[gi])
            succs[pos[gi]].append(pos[gj])
        return GoalIndex(
            ids, tuple(tuple(sorted(p)) for p in preds), tuple(tuple(sorted(s)) for s in succs)
        )

    @property
    def full(self) -> int:
        return (1 << len(self.ids)) - 1

    def ready(self, mask: int, g: int) -> bool:
        """Goal ``g`` is not achieved in ``mask`` and all its predecessors are."""
        return not mask >> g & 1 and all(mask >> p & 1 for p in self.preds[g])

    def enabled(self, mask: int) -> Iterator[int]:
        """Goals not yet achieved whose predecessors are all achieved in ``mask``."""
        for i in range(len(self.ids)):
            if self.ready(mask, i):
                yield i

    def initial(self) -> tuple[int, ...]:
        """The goals enabled before any is achieved (those without predecessors)."""
        return tuple(i for i, p in enumerate(self.preds) if not p)

    def enabled_after(self, enabled: tuple[int, ...], mask: int, g: int) -> tuple[int, ...]:
        """``enabled(mask | 1 << g)`` from ``enabled == enabled(mask)``, ascending.

        Only a successor of ``g`` can become enabled by achieving ``g``: O(width + out(g)).
        """
        child = mask | 1 << g
        new = [j for j in self.succs[g] if self.ready(child, j)]
        rest = [i for i in enabled if i != g]
        return tuple(sorted(rest + new)) if new else tuple(rest)

    def acyclic(self) -> bool:
        """True when C has an order at all (Kahn's algorithm, O(goals + constraints))."""
        missing = [len(p) for p in self.preds]
        ready = [i for i, n in enumerate(missing) if n == 0]
        seen = 0
        while ready:
            i = ready.pop()
            seen += 1
            for j in self.succs[i]:
                missing[j] -= 1
                if missing[j] == 0:
                    ready.append(j)
        return seen == len(self.ids)

    def names(self, mask: int) -> frozenset[str]:
        return frozenset(self.ids[i] for i in set_bits(mask))


def set_bits(mask: int) -> Iterator[int]:
    """Positions of the set bits of ``mask``, ascending (O(set bits · words))."""
    while mask:
        low = mask & -mask
        yield low.bit_length() - 1
        mask ^= low


@dataclass(frozen=True)
class RGStats:
    """Sizes of the RG: distinct states and edges (merged DAG) and Alg. 1's tree nodes."""

    states: int | None
    edges: int | None
    alg1_nodes: int
    complete: bool


class RGTooLarge(RuntimeError):
    """Raised when enumerating the RG would exceed the requested limit."""


def _masks(index: GoalIndex, limit: float) -> tuple[list[int], list[tuple[int, int, int]]]:
    """States (breadth-first) and edges ``(state, child, goal)`` of the merged RG; an edge
    names its states by their positions in the state list.

    Every subset of the goals without predecessors is a state, so 2^|those| > ``limit``
    proves the RG too large before enumerating anything.
    """
    initial = index.initial()
    if 2 ** len(initial) > limit:
        raise RGTooLarge(f"the RG has more than {limit} states")
    seen = {0: 0}
    order = [0]
    edges = []
    frontier = {0: initial}
    while frontier:
        nxt: dict[int, tuple[int, ...]] = {}
        for m, enabled in frontier.items():
            at = seen[m]
            for g in enabled:
                child = m | 1 << g
                to = seen.get(child)
                if to is None:
                    if len(seen) >= limit:
                        raise RGTooLarge(f"the RG has more than {limit} states")
                    to = seen[child] = len(order)
                    order.append(child)
                    nxt[child] = index.enabled_after(enabled, m, g)
                edges.append((at, to, g))
        frontier = nxt
    return order, edges


def _alg1_count(order: list[int], edges: list[tuple[int, int, int]]) -> int:
    """Alg. 1's tree nodes: count(S) = 1 + Σ count(child), over the DAG in reverse BFS order."""
    count = [1] * len(order)
    for at, to, _ in reversed(edges):  # edges leave states in BFS order: children first
        count[at] += count[to]
    return count[0]


def alg1_node_count(index: GoalIndex) -> int:
    """Nodes Alg. 1 generates without merging: one per constraint-respecting prefix."""
    order, edges = _masks(index, float("inf"))
    return _alg1_count(order, edges)


class ReachabilityGraph:
    """The merged RG of one demonstration, enumerated once (up to ``limit`` states).

    A plan's statistics, its verification gate and its DOT drawing all read this one
    enumeration; the networkx view is built on first use and kept.
    """

    def __init__(self, demo: Demonstration, limit: int = 200_000) -> None:
        self.demo = demo
        self.limit = limit
        self.index = GoalIndex.of(demo)
        # states and edges together, or None past ``limit`` (see `enumeration`)
        self._enum: tuple[list[int], list[tuple[int, int, int]]] | None
        try:
            self._enum = _masks(self.index, limit)
        except RGTooLarge:
            self._enum = None
        self._stats: RGStats | None = None
        self._nx: nx.DiGraph | None = None

    @property
    def complete(self) -> bool:
        """False when the RG has more than ``limit`` states (then only stats say so)."""
        return self._enum is not None

    @property
    def stats(self) -> RGStats:
        """State/edge counts when complete, and Alg. 1's node count."""
        if self._stats is None:
            if self._enum is None:
                self._stats = RGStats(None, None, -1, False)
            else:
                masks, edges = self._enum
                self._stats = RGStats(len(masks), len(edges), _alg1_count(masks, edges), True)
        return self._stats

    def enumeration(self) -> tuple[list[int], list[tuple[int, int, int]]] | None:
        """States as goal bit masks (breadth-first, the root first) and edges ``(state,
        child, goal)`` by state position; None past ``limit``. Shared, not to be modified."""
        return self._enum

    def networkx(self) -> nx.DiGraph:
        """The RG as a networkx DiGraph (see `build_rg`); `RGTooLarge` beyond ``limit``."""
        if self._enum is None:
            raise RGTooLarge(f"the RG has more than {self.limit} states")
        if self._nx is None:
            self._nx = self._to_networkx()
        return self._nx

    def _to_networkx(self) -> nx.DiGraph:
        demo, index = self.demo, self.index
        assert self._enum is not None  # called by networkx() only, after its limit check
        masks, edges = self._enum
        g = nx.DiGraph(source=demo.source)
        for m in masks:
            achieved = index.names(m)
            places = {obj: "P" for obj in demo.objects}
            for goal in demo.goals:  # demonstrated order: the last achieved goal wins
                if goal.id in achieved:
                    places[goal.object] = goal.id
            g.add_node(achieved, places=places, mask=m)
        for at, to, gi in edges:
            g.add_edge(index.names(masks[at]), index.names(masks[to]), goal=index.ids[gi])
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
