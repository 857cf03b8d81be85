"""An exact optimum by dynamic programming, written apart from the search it checks.

Held-Karp over (achieved goals, last goal) for every set the constraints allow: O(2^goals ·
goals²), so for tasks of up to about 12 goals. Costs are recomputed from the demonstration
(planar distances, robot → object → goal), not taken from `tamp.rg.search`.
"""

from __future__ import annotations

import math

from tamp.demo.model import Demonstration


def dp_optimum(demo: Demonstration) -> float:
    """Least travel distance over every order of the goals that respects C."""
    assert not demo.buffers, "the oracle reads pick points from the demonstrated order"
    ids = list(demo.goal_ids)
    pos = {g: i for i, g in enumerate(ids)}
    k = len(ids)
    where = dict(demo.objects)
    pick, drop = [None] * k, [None] * k
    for goal in demo.goals:  # demonstrated order: an object's goals come in its own order
        pick[pos[goal.id]] = where[goal.object]
        drop[pos[goal.id]] = goal.pos
        where[goal.object] = goal.pos
    need = [0] * k
    for a, b in demo.constraints:
        need[pos[b]] |= 1 << pos[a]

    def dist(p, q) -> float:
        return math.hypot(p.x - q.x, p.y - q.y)

    start = demo.robot_start.pos
    layer = {(0, -1): 0.0}
    for _ in range(k):
        nxt: dict[tuple[int, int], float] = {}
        for (mask, last), cost in layer.items():
            here = start if last < 0 else drop[last]
            for g in range(k):
                if mask >> g & 1 or need[g] & ~mask:
                    continue
                c = cost + dist(here, pick[g]) + dist(pick[g], drop[g])
                key = (mask | 1 << g, g)
                if c < nxt.get(key, math.inf):
                    nxt[key] = c
        layer = nxt
    return min(layer.values())
