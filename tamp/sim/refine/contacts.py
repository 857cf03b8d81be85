"""ContactMonitor: every plant step, which pairs of bodies touch that should not.

Step 2 of the refinement executes a parallelized program once "to detect possible
failures, such as collisions" (Figueroa Heredia et al. 2018 §3.2), and every refined phase
is accepted only if it adds no collision the original run did not have. A collision is
judged over time, not on a sample: this system reads the plant's contact results (point
pairs and hydroelastic contact surfaces, each mapped to its two bodies) at every plant
step in its periodic update and accumulates, per pair that `CollisionRule.classify` calls
a collision, the first time of contact and the total time in contact (``ContactLog``).
A pair counts as a collision of the run once its accumulated contact reaches
``min_contact`` (two plant steps by default): one step's graze of a finger is noise of the
contact solver, a body pressed for 20 ms is a collision.

The rule (`CollisionRule.classify`): a robot's chassis (`base_link`, `arm_link`) touching
anything, a robot touching the other robot, or a robot touching the scene's fixed objects
(the table). A gripper touching the task's objects or the floor is the task; the first
such touch of each robot is kept too (``ContactLog.touches``): where its manipulation
starts (`tamp.refine.steps.locate`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, LeafSystem


@dataclass(frozen=True)
class CollisionRule:
    """Which body contacts are collisions (module docstring); bodies by plant index."""

    robot_of: Mapping[int, str]  # body index -> robot name
    chassis: frozenset[int]  # bodies whose every contact is a collision
    scenery: frozenset[int]  # bodies of the scene's fixed objects
    names: Mapping[int, str]  # body index -> "R1.base_link"
    objects: frozenset[int] = frozenset()  # bodies of the scene's free (task) objects

    def touch(self, a: int, b: int) -> tuple[str, str] | None:
        """The contact as ``(robot, object body)`` when a robot's gripper (a body that is not
        its chassis) touches a task object: an intended contact, where manipulation starts."""
        for mine, other in ((a, b), (b, a)):
            robot = self.robot_of.get(mine)
            if robot is not None and mine not in self.chassis and other in self.objects:
                return (robot, self.names.get(other, str(other)))
        return None

    def classify(self, a: int, b: int) -> tuple[str, str] | None:
        """The contact of bodies ``a`` and ``b`` as ``(robot body, other)``, or None."""
        for mine, other in ((a, b), (b, a)):
            robot = self.robot_of.get(mine)
            if robot is None:
                continue
            if (
                mine in self.chassis
                or other in self.scenery
                or self.robot_of.get(other, robot) != robot
            ):
                return (self.names.get(mine, str(mine)), self.names.get(other, str(other)))
        return None


@dataclass(frozen=True)
class ContactLog:
    """Per colliding pair: (first time in contact, total seconds in contact); per robot: the
    first time its gripper touched a task object, and which body (``touches``)."""

    spans: dict[tuple[str, str], tuple[float, float]] = field(default_factory=dict)
    touches: dict[str, tuple[float, str]] = field(default_factory=dict)

    def __deepcopy__(self, memo: dict) -> ContactLog:
        return self  # immutable: a new log is made when something changes

    def collisions(self, min_contact: float) -> dict[tuple[str, str], float]:
        """Pairs in contact for at least ``min_contact`` s in all -> first contact time."""
        return {k: first for k, (first, total) in self.spans.items() if total >= min_contact - 1e-9}


class ContactMonitor(LeafSystem):
    """Accumulates the plant's colliding contacts every ``period`` (the plant step)."""

    def __init__(
        self,
        rule: CollisionRule,
        geometry_body: Mapping[int, int],
        contact_model: AbstractValue,
        period: float,
    ):
        super().__init__()
        self.set_name("contact_monitor")
        self._rule = rule
        self._body = dict(geometry_body)  # GeometryId value -> body index
        self._period = period
        #: per body pair: (`CollisionRule.classify`, `CollisionRule.touch`), computed once
        self._verdicts: dict[tuple[int, int], tuple[Any, Any]] = {}
        self.contact_port = self.DeclareAbstractInputPort("contact_results", contact_model)
        self._state = self.DeclareAbstractState(AbstractValue.Make(ContactLog()))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)

    def log(self, context) -> ContactLog:
        return context.get_abstract_state(self._state).get_value()

    def _pairs(self, results) -> list[tuple[int, int]]:
        out = []
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            out.append((int(info.bodyA_index()), int(info.bodyB_index())))
        for i in range(results.num_hydroelastic_contacts()):
            surface = results.hydroelastic_contact_info(i).contact_surface()
            a = self._body.get(surface.id_M().get_value())
            b = self._body.get(surface.id_N().get_value())
            if a is not None and b is not None:
                out.append((a, b))
        return out

    def _verdict(self, pair: tuple[int, int]) -> tuple[Any, Any]:
        """(collision key or None, gripper touch or None) of a body pair (`CollisionRule`)."""
        v = self._verdicts.get(pair)
        if v is None:
            v = self._verdicts[pair] = (self._rule.classify(*pair), self._rule.touch(*pair))
        return v

    def _update(self, context, state) -> EventStatus:
        pairs = self._pairs(self.contact_port.Eval(context))
        if not pairs:
            return EventStatus.DidNothing()
        t = context.get_time()
        log = self.log(context)
        spans, touches = log.spans, log.touches
        for pair in pairs:
            key, touch = self._verdict(pair)
            if key is not None:
                if spans is log.spans:
                    spans = dict(spans)
                first, total = spans.get(key, (t, 0.0))
                spans[key] = (first, total + self._period)
            if touch is not None and touch[0] not in touches:
                touches = {**touches, touch[0]: (t, touch[1])}
        if spans is log.spans and touches is log.touches:
            return EventStatus.DidNothing()
        state.get_mutable_abstract_state(self._state).set_value(ContactLog(spans, touches))
        return EventStatus.Succeeded()
