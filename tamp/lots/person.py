"""The scripted person of Zhou et al. §III-B: interference events timed by robot actions.

An interference script (`tamp.lots.task.Event`s from the interference YAML) says what a person
does after the robot's N-th action (``phase: idle``) or while the robot carries the object of
its next action (``phase: holding``, unseen by the eye-in-hand camera). A robot action ends
with a ``Place`` (a delivery, a return, a discard, the end of a removal) or a ``Wait`` skill
(`ACTION_SKILLS`); the holding phase starts when the hand holds what a ``Pick`` took.

`ScriptedPerson.slots` is the timing alone (which ``(N, phase)`` slots begin, given the
actions done and whether the hand holds something), so a Drake person with a kinematic hand
can share it; `ScriptedPerson.act` applies what is due to the one `tamp.world.SymbolicWorld`
as world events (`Appear` of a new or a moved object, `Remove`) and is called between the
controller's ticks. Idle events after N actions happen once the N-th action ended, before the
robot looks again; holding events of action N+1 right after its pick; a holding event of an
action without a pick (a wait) during that action, right before the idle events after it.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterable

from tamp.errors import InputError
from tamp.lots.cell import new_uid, objects_of
from tamp.lots.task import Event
from tamp.world.events import Appear, Remove
from tamp.world.symbolic import SymbolicWorld

#: Skills that end one robot action (what interference scripts count).
ACTION_SKILLS = frozenset({"Place", "Wait"})

#: A human policy: called at each slot ``(N, phase)`` with the world; the events it returns
#: (or yields: each is applied before the next is asked for) happen in that slot.
Policy = Callable[[int, str, SymbolicWorld], Iterable[Event]]


def actions_done(world: SymbolicWorld) -> int:
    """Robot actions completed so far in ``world`` (succeeded `ACTION_SKILLS`)."""
    return sum(1 for a in world.executed() if a.name in ACTION_SKILLS)


class ScriptedPerson:
    """Applies an interference script (and/or a ``policy``) to a `SymbolicWorld`.

    ``strict``: an event that cannot happen (fewer objects than it moves or removes) is an
    `InputError` naming the script's file and field; otherwise it is skipped. ``log`` holds
    ``(N, phase, event)`` for every event applied.
    """

    def __init__(
        self,
        events: Iterable[Event] = (),
        *,
        policy: Policy | None = None,
        strict: bool = True,
    ):
        self.events = sorted(events, key=lambda e: (e.after, e.phase != "holding"))
        self.policy = policy
        self.strict = strict
        self.log: list[tuple[int, str, Event]] = []
        self.actions_done = -1  # before the first slot
        self._holding = -1  # the last N whose holding slot has begun
        self._fired: set[int] = set()

    def slots(self, done: int, holding: bool) -> list[tuple[int, str]]:
        """The slots that begin now, in order, after ``done`` actions with/without a held object."""
        out: list[tuple[int, str]] = []
        if self.actions_done < 0:
            self.actions_done = 0
            out.append((0, "idle"))
        while self.actions_done < done:
            n = self.actions_done
            if self._holding != n:  # an action without a pick: its holding slot is now
                self._holding = n
                out.append((n, "holding"))
            self.actions_done = n + 1
            out.append((n + 1, "idle"))
        if holding and self._holding != self.actions_done:
            self._holding = self.actions_done
            out.append((self.actions_done, "holding"))
        return out

    def act(self, world: SymbolicWorld) -> None:
        """Do what is due now in ``world`` (call it before each controller tick)."""
        for n, phase in self.slots(actions_done(world), world.state.held is not None):
            for e in self._take(n, phase):
                self.apply(world, e, n, phase)
            if self.policy is not None:
                for e in self.policy(n, phase, world):
                    self.apply(world, e, n, phase)

    def due(self, done: int, holding: bool) -> list[tuple[int, str, Event]]:
        """The scripted events of the slots that begin now, as ``(N, phase, event)``, marked
        as happened: for a world that carries them out itself (the Drake person's hand)."""
        return [(n, ph, e) for n, ph in self.slots(done, holding) for e in self._take(n, ph)]

    def progress(self) -> tuple[int, int, int]:
        """Where the script stands: actions seen, last holding slot begun, events fired."""
        return (self.actions_done, self._holding, len(self._fired))

    def _take(self, n: int, phase: str) -> list[Event]:
        """The not yet fired events of slot ``(n, phase)``, now marked as fired."""
        out = []
        for i, e in enumerate(self.events):
            if i not in self._fired and e.after == n and e.phase == phase:
                self._fired.add(i)
                out.append(e)
        return out

    def __deepcopy__(self, memo: dict) -> ScriptedPerson:
        """Copy the progress (counters, fired events, log); share the immutable events."""
        new = copy.copy(self)
        new._fired = set(self._fired)
        new.log = list(self.log)
        return new

    def apply(self, world: SymbolicWorld, e: Event, n: int = 0, phase: str = "idle") -> bool:
        """Apply one human action now; an impossible one is an `InputError` (or skipped)."""
        state = world.state
        # the task parser requires 'side' of an add or remove, 'from' and 'to' of a move
        if e.kind == "add":  # one pile, however many: counts stay integers
            assert e.side is not None
            world.happen(Appear(new_uid(state, e.cls), e.side, kind=e.cls, count=e.count))
        else:
            side = e.src if e.kind == "move" else e.side
            assert side is not None
            piles = [(uid, state.objects[uid].count) for uid in objects_of(state, e.cls, side)]
            have = sum(k for _, k in piles)
            if have < e.count:
                return self._impossible(e, f"only {have} {e.cls} in W^{side}")
            left = e.count
            for uid, k in piles:
                take = min(left, k)
                if e.kind == "move":
                    assert e.dst is not None
                    world.happen(Appear(uid, e.dst, count=take))
                else:
                    world.happen(Remove(uid, count=take))
                left -= take
                if not left:
                    break
        self.log.append((n, phase, e))
        return True

    def pending_events(self) -> int:
        """Scripted events that have not happened (yet)."""
        return len(self.events) - len(self._fired)

    def unfired(self) -> list[Event]:
        """Scripted events that have not happened (at the end of a run: never will).

        An event timed after more actions than the run took (``after: 99`` in a six-action
        run) is not an error of the script — the run could have been longer — but a run that
        ignored it must say so (`tamp lots`, ``tamp-verify lots``: ``never happened: …``).
        """
        return [e for i, e in enumerate(self.events) if i not in self._fired]

    def _impossible(self, e: Event, why: str) -> bool:
        if self.strict:
            where = e.where or "interference"
            raise InputError(
                f"{e.describe()} impossible after {e.after} robot actions: {why}",
                file=where.split(": ")[0] if ": " in where else None,
                field=where.split(": ")[1] if ": " in where else None,
            )
        return False
