"""Values that travel on the abstract ports between the LeafSystems (no Drake import).

    BtExecutor --SkillCommand--> SkillController --SkillStatus--> BtExecutor
    SkillController --GraspRequest--> grasp switch (weld constraints) and WorldStateEstimator

A command carries an id; the controller reports the status of the id it is working on,
so the executor never mistakes the result of an earlier skill for the current one.
"""

from __future__ import annotations

from dataclasses import dataclass

from tamp.world.geometry import Area
from tamp.world.interface import Status


@dataclass(frozen=True)
class SkillCommand:
    """Run ``name(args)`` (MoveTo, Pick, Place); ``cancel`` halts skill ``id``. id 0 = none.

    ``areas`` carries areas the tree found at run time (not in the demonstration) that the
    arguments name, so the controller knows where they are.
    """

    id: int = 0
    name: str = ""
    args: tuple[str, ...] = ()
    cancel: bool = False
    areas: tuple[Area, ...] = ()

    def __str__(self) -> str:
        return f"{self.name}({', '.join(self.args)})" if self.name else "<none>"

    def __deepcopy__(self, memo: dict) -> SkillCommand:
        return self  # immutable: Drake's copies of port values and state cost nothing


@dataclass(frozen=True)
class SkillStatus:
    """What the controller reports for command ``id`` (RUNNING until it ends, then sticky).

    ``cause``: on FAILURE, why, as one of `tamp.sim.core.outcome.CAUSES`, set by the skill
    where it fails (a run's cause is read from it, never parsed from ``detail``)."""

    id: int = 0
    status: Status = Status.SUCCESS
    detail: str = ""
    cause: str | None = None

    def __deepcopy__(self, memo: dict) -> SkillStatus:
        return self


@dataclass(frozen=True)
class GraspRequest:
    """The gripper's state: the weld it asks for and what it reports holding.

    ``obj``/``variant``: the weld to switch on (object ``obj``, weld 0 or 1), or none. Two
    welds exist per object (the object turned by 0 or pi about its axis relative to the
    fingers), so the wrist never turns more than 90 degrees to match the object.
    ``holding``: the object the gripper reports as held (the robot's grasp sensor): set once
    a pick has lifted the object and checked it on the plant, cleared once a place has put
    it down, let go and checked it. So ``IsGraspedObject``/``IsObjectAt`` change when the
    skill ends, not half-way through it (the reactive tree would otherwise halt the skill).
    """

    obj: str | None = None
    variant: int = 0
    holding: str | None = None

    def __deepcopy__(self, memo: dict) -> GraspRequest:
        return self
