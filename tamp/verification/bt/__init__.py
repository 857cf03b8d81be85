"""Verification of grown behavior trees: every execution explored and model-checked.

Modules, one job each: `explore` (the executions as a transition system, on the one
`SymbolicWorld` with branching outcomes), `labels` (the propositions properties may use),
`check` (`check_tree`, the entry point), `demo` (an executor for a demonstration).
"""

from tamp.verification.bt.check import VerificationUnknown, check_tree
from tamp.verification.bt.demo import executor_for
from tamp.verification.bt.explore import DEFAULT_MAX_STATES, Exploration, explore
from tamp.verification.bt.labels import DEFAULT_PROPERTIES, FLAGS, Labeller

__all__ = [
    "DEFAULT_MAX_STATES",
    "DEFAULT_PROPERTIES",
    "FLAGS",
    "Exploration",
    "Labeller",
    "VerificationUnknown",
    "check_tree",
    "executor_for",
    "explore",
]
