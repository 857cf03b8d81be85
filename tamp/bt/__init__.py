"""Behavior trees grown at run time, PA-BT style (SMP-MRO §IV-C, Alg. 2-3).

`PaBtExecutor` builds the initial tree from C_goal, ticks it against any `World`
(`SymbolicWorld` of `tamp.world`, the Drake adapter in `tamp.sim`) and grows it between
ticks, resolving conflicts by moving subtrees up in execution order and adding recovery
trees. `Appear` / `Fail` (the run vocabulary of `tamp.world.events`) and `SymbolicWorld`
are re-exported for convenience.
"""

from tamp.bt.executor import (
    ActionRecord,
    ExecutorSnapshot,
    ExecutorStats,
    GrowthEvent,
    PaBtExecutor,
)
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
from tamp.world.events import Appear, Fail
from tamp.world.symbolic import SymbolicWorld

__all__ = [
    "ActionNode",
    "ActionRecord",
    "Appear",
    "Condition",
    "ExecutorSnapshot",
    "ExecutorStats",
    "ExpansionError",
    "Fail",
    "Fallback",
    "GrowthEvent",
    "Node",
    "PaBtExecutor",
    "PriorityFallback",
    "ReactiveFallback",
    "ReactiveSequence",
    "Sequence",
    "SymbolicWorld",
]
