"""The RG layer's front end: a demonstration in, the cheapest goal order (C_goal) out."""

from __future__ import annotations

from dataclasses import dataclass, field

import networkx as nx

from tamp.demo.model import Demonstration
from tamp.errors import InfeasibleError
from tamp.rg.costs import COST_MODELS, CostModel, Metric, planar
from tamp.rg.graph import ReachabilityGraph, RGStats
from tamp.rg.search import OrderProblem, astar
from tamp.world.predicates import IsObjectAt


@dataclass(frozen=True)
class PlanResult:
    """The chosen order, its cost, the RG sizes and the search effort."""

    demo: Demonstration
    order: list[str]
    cost: float
    cost_model: str
    expanded: int
    generated: int
    reachability: ReachabilityGraph = field(repr=False, compare=False)

    @property
    def rg(self) -> RGStats:
        """The RG's sizes (from the one enumeration of this plan)."""
        return self.reachability.stats

    def graph(self) -> nx.DiGraph:
        """The RG as networkx (built once per plan; `RGTooLarge` past the stats limit)."""
        return self.reachability.networkx()

    @property
    def c_goal(self) -> list[IsObjectAt]:
        """The order as the BT layer's goal conditions (Alg. 2 input C_goal)."""
        goals = {g.id: g for g in self.demo.goals}
        return [IsObjectAt(goals[g].object, goals[g].area.name) for g in self.order]

    def to_json(self) -> dict:
        d = self.demo
        return {
            "goals": [
                {
                    "id": g.id,
                    "object": g.object,
                    "position": [round(v, 6) for v in g.pos.as_tuple()],
                    "area": g.area.name,
                }
                for g in d.goals
            ],
            "initial": {k: [round(v, 6) for v in p.as_tuple()] for k, p in d.objects.items()},
            "constraints": sorted([list(c) for c in d.constraints]),
            "constraint_reasons": {
                f"{a}<={b}": r for (a, b), r in sorted(d.constraint_reasons.items())
            },
            "rg": {
                "states": self.rg.states,
                "edges": self.rg.edges,
                "alg1_nodes": self.rg.alg1_nodes,
            },
            "order": self.order,
            "c_goal": [str(c) for c in self.c_goal],
            "cost": round(self.cost, 9),
            "cost_model": self.cost_model,
            "search": {"expanded": self.expanded, "generated": self.generated},
            **({"buffers": [b.to_json() for b in d.buffers]} if d.buffers else {}),
        }


def plan(
    demo: Demonstration,
    cost: str = "distance",
    *,
    metric: Metric = planar,
    stats_limit: int = 200_000,
) -> PlanResult:
    """Optimal order of the demonstration's goals under ``cost``; `InfeasibleError` if none."""
    if cost not in COST_MODELS:
        raise ValueError(f"unknown cost model {cost!r} (known: {', '.join(COST_MODELS)})")
    model = CostModel.of(cost, demo.domain(), metric)
    result = astar(OrderProblem(demo, model))
    if result is None:
        raise InfeasibleError("no order of the goals satisfies the constraints C")
    return PlanResult(
        demo=demo,
        order=result.order,
        cost=result.cost,
        cost_model=cost,
        expanded=result.expanded,
        generated=result.generated,
        reachability=ReachabilityGraph(demo, stats_limit),
    )
