"""Behavior trees grown at run time, PA-BT style (SMP-MRO §IV-C, Alg. 2-3).

`PaBtExecutor` builds the initial tree from C_goal, ticks it against any `World`
(`SymbolicWorld` here, the Drake adapter in `tamp.sim`) and grows it between ticks,
resolving conflicts by moving subtrees up in execution order and adding recovery trees.
"""

from tamp.bt.executor import ActionRecord, ExecutorStats, GrowthEvent, PaBtExecutor
from tamp.bt.expand import ExpansionError
from tamp.bt.nodes import (
    ActionNode,
    Condition,
    Fallback,
    Node,
    PriorityFallback,
    ReactiveFallback,
    ReactiveSequence,
    Sequence,
)
from tamp.world.symbolic import Appear, Move, ScriptedFailure, SymbolicWorld

__all__ = [
    "ActionNode",
    "ActionRecord",
    "Appear",
    "Condition",
    "ExecutorStats",
    "ExpansionError",
    "Fallback",
    "GrowthEvent",
    "Move",
    "Node",
    "PaBtExecutor",
    "PriorityFallback",
    "ReactiveFallback",
    "ReactiveSequence",
    "ScriptedFailure",
    "Sequence",
    "SymbolicWorld",
]
