"""The symbolic world shared by every layer: geometry, state, predicates, action templates."""

from tamp.world.actions import (
    Action,
    ActionTemplate,
    CondPattern,
    Domain,
    default_domain,
    load_domain,
)
from tamp.world.geometry import Area, Point, Pose, Quaternion
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

__all__ = [
    "DEFAULT_REACH",
    "Action",
    "ActionTemplate",
    "Area",
    "CondPattern",
    "Domain",
    "IsAreaFree",
    "IsGraspedObject",
    "IsHandFree",
    "IsObjectAt",
    "IsRobotCloseTo",
    "ObjectState",
    "Point",
    "Pose",
    "Predicate",
    "Quaternion",
    "WorldState",
    "default_domain",
    "load_domain",
]
