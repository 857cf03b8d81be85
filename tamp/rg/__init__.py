"""Reachability graph (SMP-MRO §IV-B, Alg. 1) and exact weighted search for the goal order."""

from tamp.rg.costs import COST_MODELS, CostModel
from tamp.rg.graph import GoalIndex, RGStats, RGTooLarge, alg1_node_count, build_rg, rg_stats
from tamp.rg.plan import PlanResult, plan
from tamp.rg.search import OrderProblem, SearchResult, astar

__all__ = [
    "COST_MODELS",
    "CostModel",
    "GoalIndex",
    "OrderProblem",
    "PlanResult",
    "RGStats",
    "RGTooLarge",
    "SearchResult",
    "alg1_node_count",
    "astar",
    "build_rg",
    "plan",
    "rg_stats",
]
