"""The symbolic world every layer shares (SMP-MRO §V-A1 state variables r, h, o_uid, l_uid)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from tamp.world.geometry import Area, Point, Pose


@dataclass(frozen=True, slots=True)
class ObjectState:
    """A known object: its uid, pose (the paper's ``Object``), ``kind`` and ``count``.

    ``kind`` is the object's class where a task names objects by class (LOTS: "a hammer",
    Zhou et al. §III); empty where objects are named one by one (SMP-MRO). ``count`` > 1 makes
    the entry a pile of that many interchangeable objects of ``kind`` at one pose: LOTS knows
    objects only by class, so a workspace's contents stay integers however many objects a
    person pours in (picking one splits it off the pile, `WorldState.split`).
    """

    uid: str
    pose: Pose
    kind: str = ""
    count: int = 1

    @property
    def pos(self) -> Point:
        return self.pose.pos


@dataclass(frozen=True)
class WorldState:
    """Robot pose ``r``, held object ``h`` (None when the hand is free), objects and areas.

    Immutable: actions return a new state (`with_robot_at`, `with_held`, `with_object_at`),
    so planners can keep states in sets and executors can compare before/after.
    """

    robot: Pose
    held: str | None = None
    objects: Mapping[str, ObjectState] = field(default_factory=dict)
    areas: Mapping[str, Area] = field(default_factory=dict)

    # -- lookups --------------------------------------------------------------------------
    def object_pos(self, uid: str) -> Point:
        try:
            return self.objects[uid].pos
        except KeyError:
            raise KeyError(f"unknown object {uid!r}") from None

    def area(self, name: str) -> Area:
        try:
            return self.areas[name]
        except KeyError:
            raise KeyError(f"unknown area {name!r}") from None

    def position_of(self, ref: str) -> Point:
        """Position of a named object or area (objects first)."""
        if ref in self.objects:
            return self.objects[ref].pos
        if ref in self.areas:
            return self.areas[ref].pos
        raise KeyError(f"unknown object or area {ref!r}")

    def objects_in(self, area: Area, *, ignore_held: bool = True) -> list[str]:
        """Objects whose position lies in ``area`` (the held one is carried, not placed)."""
        return [
            uid
            for uid, o in self.objects.items()
            if area.contains(o.pos) and not (ignore_held and uid == self.held)
        ]

    def kinds_in(self, area: Area) -> dict[str, int]:
        """How many objects of each kind lie in ``area`` (not held), kinds in sorted order."""
        counts: dict[str, int] = {}
        for uid in self.objects_in(area):
            o = self.objects[uid]
            counts[o.kind] = counts.get(o.kind, 0) + o.count
        return dict(sorted(counts.items()))

    # -- updates --------------------------------------------------------------------------
    def with_robot_at(self, pose: Pose) -> WorldState:
        return replace(self, robot=pose)

    def with_held(self, uid: str | None) -> WorldState:
        return replace(self, held=uid)

    def with_object_at(
        self, uid: str, pose: Pose, kind: str | None = None, count: int | None = None
    ) -> WorldState:
        """``uid`` at ``pose``; a known object keeps its kind and count unless they are given."""
        objects = dict(self.objects)
        old = objects.get(uid)
        if kind is None:
            kind = old.kind if old is not None else ""
        if count is None:
            count = old.count if old is not None else 1
        if count < 1:
            raise ValueError(f"object {uid!r}: count {count} (at least 1)")
        objects[uid] = ObjectState(uid, pose, kind, count)
        return replace(self, objects=objects)

    def with_count(self, uid: str, count: int) -> WorldState:
        """Pile ``uid`` holding ``count`` objects (0 removes the entry)."""
        if count == 0:
            return self.without_object(uid)
        o = self.objects[uid]
        return self.with_object_at(uid, o.pose, o.kind, count)

    def fresh_uid(self, prefix: str) -> str:
        """The first free ``<prefix>_<n>`` name (n = 1, 2, …)."""
        n = 1
        while f"{prefix}_{n}" in self.objects:
            n += 1
        return f"{prefix}_{n}"

    def split(self, uid: str, n: int = 1) -> tuple[WorldState, str]:
        """Take ``n`` objects off pile ``uid`` into a new entry at the same pose.

        Returns the new state and the new entry's uid; taking a whole pile returns ``uid``
        itself. Entries stay few (one per pile plus one per object the robot or a person
        handled), so a count of 10^7 costs what a count of 1 does.
        """
        o = self.objects[uid]
        if not 0 < n <= o.count:
            raise ValueError(f"cannot take {n} of {o.count} from {uid!r}")
        if n == o.count:
            return self, uid
        new = self.fresh_uid(o.kind or uid)
        state = self.with_count(uid, o.count - n)
        return state.with_object_at(new, o.pose, o.kind, n), new

    def without_object(self, uid: str) -> WorldState:
        objects = dict(self.objects)
        objects.pop(uid, None)
        return replace(self, objects=objects, held=None if self.held == uid else self.held)

    def with_area(self, area: Area) -> WorldState:
        areas = dict(self.areas)
        areas[area.name] = area
        return replace(self, areas=areas)

    def summary(self) -> dict:
        """JSON-friendly view: robot xy+yaw, held object, object positions (and the counts
        of piles, when there are any)."""
        out = {
            "robot": [
                round(self.robot.pos.x, 4),
                round(self.robot.pos.y, 4),
                round(self.robot.orientation.yaw(), 4),
            ],
            "held": self.held,
            "objects": {
                uid: [round(v, 4) for v in o.pos.as_tuple()]
                for uid, o in sorted(self.objects.items())
            },
        }
        piles = {uid: o.count for uid, o in sorted(self.objects.items()) if o.count != 1}
        if piles:
            out["counts"] = piles
        return out
