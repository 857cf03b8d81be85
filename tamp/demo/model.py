"""Data of a demonstration after the transforms: places P, goals G, constraints C (§IV-A)."""

from __future__ import annotations

from dataclasses import dataclass, field

from tamp.demo.constraints import Buffer
from tamp.world.events import Appear
from tamp.world.geometry import Area, Point, Pose
from tamp.world.state import ObjectState, WorldState


@dataclass(frozen=True)
class Goal:
    """One illustrated step: object ``object`` must reach area ``area`` (centre ``pos``).

    ``step`` is the index of the step in the person's order; goal ids are ``G<step>`` and
    their areas ``L<step>`` (the paper's L_i centred on G_i). A buffer goal the robot adds
    to break a swap with no room (`tamp.demo.constraints`) is numbered after the steps and
    its area is the free area it uses; goals are listed in the order they happen.
    """

    id: str
    object: str
    pos: Point
    area: Area
    step: int


@dataclass(frozen=True)
class Demonstration:
    """What the person showed, in the robot frame: the input of the RG layer (Alg. 1)."""

    objects: dict[str, Point]
    goals: list[Goal]
    constraints: frozenset[tuple[str, str]]
    free_areas: list[Area]
    robot_start: Pose
    area_radius: float
    object_height: float = 0.2
    domain_file: str | None = None
    source: str = "<memory>"
    constraint_reasons: dict[tuple[str, str], str] = field(default_factory=dict)
    #: What happens during execution that the person did not show (SMP-MRO §V-D Case 3: an
    #: obstacle O_a appears at l_1); flags of the CLI override entries of the same object.
    appear: tuple[Appear, ...] = ()
    #: Goals the robot adds to pass an object through a free area (a swap with no room).
    buffers: tuple[Buffer, ...] = ()

    def goal(self, gid: str) -> Goal:
        """The goal ``gid``: O(1) for the ``G<step>`` ids the demonstration gives its goals."""
        if gid[:1] == "G" and gid[1:].isdigit() and int(gid[1:]) < len(self.goals):
            g = self.goals[int(gid[1:])]
            if g.id == gid:
                return g
        for g in self.goals:
            if g.id == gid:
                return g
        raise KeyError(f"unknown goal {gid!r}")

    @property
    def goal_ids(self) -> list[str]:
        return [g.id for g in self.goals]

    def goal_chain(self, obj: str) -> list[Goal]:
        """The goals of one object in demonstrated order (intent constraints chain them)."""
        return [g for g in self.goals if g.object == obj]

    def pick_points(self) -> list[Point]:
        """`pick_point` of every goal in demonstrated order, in one pass (O(goals))."""
        where = dict(self.objects)
        out = []
        for g in self.goals:
            out.append(where[g.object])
            where[g.object] = g.pos
        return out

    def pick_point(self, goal: Goal) -> Point:
        """Where the object of ``goal`` is just before it: its previous goal, or its P."""
        prev = None
        for g in self.goals:
            if g.id == goal.id:
                break
            if g.object == goal.object:
                prev = g
        return prev.pos if prev is not None else self.objects[goal.object]

    def initial_world(self) -> WorldState:
        """Robot at its start, hand free, objects at P; areas L_k and the free areas."""
        areas = {g.area.name: g.area for g in self.goals}
        areas.update({a.name: a for a in self.free_areas})
        objects = {uid: ObjectState(uid, Pose(p)) for uid, p in self.objects.items()}
        return WorldState(robot=self.robot_start, held=None, objects=objects, areas=areas)

    def domain(self):
        """The robot's action templates (the file named in the demonstration, or youBot)."""
        from tamp.world.actions import default_domain, load_domain

        return load_domain(self.domain_file) if self.domain_file else default_domain()
