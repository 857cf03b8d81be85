"""What the LOTS controller needs from a world, and the symbolic world with human interference.

The controller only sees counts of one workspace at a time (the eye-in-hand camera over W^A
or over W^B) and commands one skill at a time. :class:`LocalWorld` is that contract; the
symbolic :class:`SymbolicLotsWorld` implements it with instant effects and scripted human
actions, and the Drake workcell implements the same methods with cameras and skills.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterable, Mapping
from typing import Protocol, runtime_checkable

from tamp.errors import InputError
from tamp.lots.task import Event, Task


@runtime_checkable
class LocalWorld(Protocol):
    """A workcell seen through a camera that covers one workspace at a time.

    Counts are per object class; a class never seen is absent or 0. Each method except
    ``observe`` and ``pick`` ends one robot action (what interference scripts count).
    """

    def observe(self, side: str) -> Mapping[str, int]:
        """Counts of the objects visible in W^A (``"A"``) or W^B (``"B"``) right now."""
        ...

    def pick(self, cls: str) -> bool:
        """Grasp one object of ``cls`` in W^A; False when there is none."""
        ...

    def place(self) -> None:
        """Put the held object into W^B."""
        ...

    def discard_held(self) -> None:
        """Drop the held object into the waste basket."""
        ...

    def return_held(self) -> None:
        """Put the held object back into W^A."""
        ...

    def remove_from_b(self, cls: str, dest: str) -> bool:
        """Move one object of ``cls`` from W^B to ``dest`` (``"A"`` or ``"waste"``).

        False when W^B holds none."""
        ...

    def wait(self) -> None:
        """Do nothing for one action slot."""
        ...


#: A human policy: called at (actions completed, phase, world) → events to apply now.
Policy = Callable[[int, str, "SymbolicLotsWorld"], Iterable[Event]]


class SymbolicLotsWorld:
    """Counts in W^A, W^B, the waste basket and the gripper; instant effects.

    Human events come from a script (`Event.after` / `Event.phase`) and/or a ``policy``
    callback (used by the property tests). ``phase="idle"`` events fire once ``after``
    actions have completed; ``phase="holding"`` events fire right after the pick of the next
    action, while the robot carries an object (unseen by the camera).
    """

    def __init__(
        self,
        task: Task,
        events: Iterable[Event] = (),
        *,
        policy: Policy | None = None,
        strict: bool = True,
    ):
        self.a: Counter[str] = Counter({k: v for k, v in task.initial_a.items() if v})
        self.b: Counter[str] = Counter({k: v for k, v in task.initial_b.items() if v})
        self.waste: Counter[str] = Counter()
        self.held: str | None = None
        self.actions_done = 0
        self.events = sorted(events, key=lambda e: (e.after, e.phase != "holding"))
        self.policy = policy
        self.strict = strict
        self.log: list[tuple[int, str, Event]] = []  # (actions done, phase, event) applied
        self._fired: set[int] = set()
        self._fire("idle")

    # ------------------------------------------------------------------ human side
    def _fire(self, phase: str) -> None:
        for i, e in enumerate(self.events):
            if i not in self._fired and e.after == self.actions_done and e.phase == phase:
                self._fired.add(i)
                self.apply(e, phase)
        if self.policy is not None:
            for e in self.policy(self.actions_done, phase, self):
                self.apply(e, phase)

    def apply(self, e: Event, phase: str = "idle") -> bool:
        """Apply one human action; an impossible one is an `InputError` (or skipped if lax)."""
        side = {"A": self.a, "B": self.b}
        if e.kind == "move":
            src, dst = side[e.src], side[e.dst]
            if src[e.cls] < e.count:
                return self._impossible(e, f"only {src[e.cls]} {e.cls} in W^{e.src}")
            src[e.cls] -= e.count
            dst[e.cls] += e.count
        elif e.kind == "add":
            side[e.side][e.cls] += e.count
        else:
            where = side[e.side]
            if where[e.cls] < e.count:
                return self._impossible(e, f"only {where[e.cls]} {e.cls} in W^{e.side}")
            where[e.cls] -= e.count
        self.log.append((self.actions_done, phase, e))
        return True

    def _impossible(self, e: Event, why: str) -> bool:
        if self.strict:
            where = e.where or "interference"
            raise InputError(
                f"{e.describe()} impossible after {e.after} robot actions: {why}",
                file=where.split(": ")[0] if ": " in where else None,
                field=where.split(": ")[1] if ": " in where else None,
            )
        return False

    def pending_events(self) -> int:
        return len(self.events) - len(self._fired)

    # ------------------------------------------------------------------ LocalWorld
    def observe(self, side: str) -> dict[str, int]:
        counts = self.a if side == "A" else self.b
        return {k: v for k, v in counts.items() if v > 0}

    def pick(self, cls: str) -> bool:
        if self.held is not None:
            raise RuntimeError("the gripper already holds an object")
        if self.a[cls] < 1:
            return False
        self.a[cls] -= 1
        self.held = cls
        self._fire("holding")
        return True

    def _end_action(self) -> None:
        # a 'holding' event scheduled for an action without a pick (a removal, a wait)
        # happens during that action rather than never
        for i, e in enumerate(self.events):
            if i not in self._fired and e.after == self.actions_done and e.phase == "holding":
                self._fired.add(i)
                self.apply(e, "holding")
        self.actions_done += 1
        self._fire("idle")

    def _release(self) -> str:
        if self.held is None:
            raise RuntimeError("the gripper holds nothing")
        cls, self.held = self.held, None
        return cls

    def place(self) -> None:
        self.b[self._release()] += 1
        self._end_action()

    def discard_held(self) -> None:
        self.waste[self._release()] += 1
        self._end_action()

    def return_held(self) -> None:
        self.a[self._release()] += 1
        self._end_action()

    def remove_from_b(self, cls: str, dest: str) -> bool:
        if self.b[cls] < 1:
            self._end_action()
            return False
        self.b[cls] -= 1
        (self.a if dest == "A" else self.waste)[cls] += 1
        self._end_action()
        return True

    def wait(self) -> None:
        self._end_action()

    # ------------------------------------------------------------------ reporting
    def counts(self) -> dict[str, dict[str, int]]:
        """Ground truth (not visible to the controller): every side, positive counts only."""

        def pos(c: Counter[str]) -> dict[str, int]:
            return {k: v for k, v in sorted(c.items()) if v > 0}

        return {"A": pos(self.a), "B": pos(self.b), "waste": pos(self.waste)}
