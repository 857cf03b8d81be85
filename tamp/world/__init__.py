"""The symbolic world shared by every layer: geometry, state, predicates, action templates,
and the one `SymbolicWorld` (with its outcome sources) that executors tick against."""

from tamp.world.actions import (
    Action,
    ActionTemplate,
    CondPattern,
    Domain,
    default_domain,
    load_domain,
)
from tamp.world.geometry import Area, Point, Pose, Quaternion
from tamp.world.outcomes import BranchingOutcomes, OutcomeSource, ScriptedOutcomes
from tamp.world.predicates import (
    DEFAULT_REACH,
    IsAreaFree,
    IsGraspedObject,
    IsHandFree,
    IsObjectAt,
    IsRobotCloseTo,
    Predicate,
)
from tamp.world.state import ObjectState, WorldState
from tamp.world.symbolic import SymbolicWorld

__all__ = [
    "DEFAULT_REACH",
    "Action",
    "ActionTemplate",
    "Area",
    "BranchingOutcomes",
    "CondPattern",
    "Domain",
    "IsAreaFree",
    "IsGraspedObject",
    "IsHandFree",
    "IsObjectAt",
    "IsRobotCloseTo",
    "ObjectState",
    "OutcomeSource",
    "Point",
    "Pose",
    "Predicate",
    "Quaternion",
    "ScriptedOutcomes",
    "SymbolicWorld",
    "WorldState",
    "default_domain",
    "load_domain",
]
