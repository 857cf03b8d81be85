"""The reactive LOTS controller: Zhou et al. Alg. 1, ticked against a `tamp.world.World`.

Each cycle the robot looks at W^A (where it picks), infers W^B from what it believes the
whole workspace holds (Alg. 1 lines 6-11), looks the W^B state up in the table ``T``
(line 12) and acts; an unknown W^B state runs the tree update (Alg. 3) and rebuilds ``T``
(lines 15-21); a state that cannot lead to completion makes it wait (line 23). Before
placing, the camera sees W^B: if a person changed it meanwhile (unseen, dis_1/dis_2), the robot
re-decides on what it sees — it places the object if ``T`` still wants it, puts it back in
W^A if the rest of the task needs it, and otherwise drops it into the waste basket (the
surplus scissors of Fig. 8, the tower body of Fig. 10).

Tick-based, like `tamp.bt.PaBtExecutor`: ``tick(world)`` never blocks. It starts one skill of
the ``lots_arm`` domain (`tamp.lots.cell`: ``LookAt(l)``, ``Pick(k, l)``, ``Place(l)``,
``Wait(l)``) with ``world.start``, polls it on later ticks, and when it ends takes the next
decision — which only fixes the skill started on the next tick, so a world (and a person in
it) can change between any two skills. The only thing the controller reads from the world is
`tamp.lots.cell.visible_counts` of ``world.observe()`` when a ``LookAt`` ends (it observes at
no other time): the counts per class of the workspace under the eye-in-hand camera. Its
state is small (belief, counters, the pending skill, tree and table) and `snapshot`/`restore`
copy it, sharing the automaton and planner, so a Drake LeafSystem can keep it in abstract
state.

When the task can no longer be completed (Assumption 1 broken: every hammer taken away, a
W^B state no run can finish from), the robot waits a bounded number of times and then stops
with FAILURE and the reason; it never loops forever. A skill that fails is started again
(a failed pick: the cycle restarts with a fresh look), at most ``max_retries`` times in a row;
the looks that start each retry do not break the row (a pick that never finds a grasp stops
the robot after ``max_retries`` retries, not at the action bound).

The run's word (`tamp.lots.word.RunWord`: the robot's deliveries and the W^B states the
camera saw, in order) is kept as the run goes: a table entry is used only when the word can
have led the automaton to the entry's state, and a replan starts only from such states (the
tree update of Alg. 3 is restricted to them), so the robot never takes an object that was
already in W^B, or that a person brought, for a delivery that did not happen. Without our
return action (`Task.returns`, off by default: Zhou et al.'s actions only deliver from W^A
or discard) a replanned run delivers no more objects than W^A was last seen to hold.

Every table the controller builds (the initial one, Alg. 1 line 3, and each rebuilt after an
unforeseen W^B state, line 20) is described by a :class:`Build` — the plan, the table and the
pair ``(q, s^B)`` it starts from — and handed to the optional ``check`` (the verification
gate) *before* it is used: a check that raises stops the controller (the exception leaves
``tick``) before the robot acts on the table.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from tamp.lots.automaton import Automaton, Letter
from tamp.lots.cell import WASTE, held_kind, skill, visible_counts
from tamp.lots.lots import Counts, Lots
from tamp.lots.planner import (
    Entry,
    Plan,
    Planner,
    Step,
    Table,
    Tree,
    initial_lasso,
    round_goals,
)
from tamp.lots.task import Task
from tamp.lots.word import RunWord
from tamp.world.actions import Action
from tamp.world.interface import Status, World


@dataclass(frozen=True)
class ActionRecord:
    """One robot action as executed. ``kind``: move, remove, discard_held, return_held, wait."""

    index: int
    kind: str
    cls: str | None = None
    prop: str | None = None
    dest: str | None = None
    w_b: tuple[int, ...] | None = None  # W^B counts the robot believes after the action
    note: str = ""

    def key(self) -> tuple[str, str | None]:
        """What tests compare: (kind, proposition or class)."""
        return (self.kind, self.prop if self.kind == "move" else self.cls)

    def text(self) -> str:
        if self.kind == "move":
            return f"{self.prop}: move {self.cls} W^A→W^B"
        if self.kind == "remove":
            return f"remove {self.cls} W^B→{'W^A' if self.dest == 'A' else 'waste basket'}"
        if self.kind == "discard_held":
            return f"drop held {self.cls} into the waste basket"
        if self.kind == "return_held":
            return f"put held {self.cls} back into W^A"
        return f"wait ({self.note})" if self.note else "wait"

    def to_json(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "prop": self.prop,
            "class": self.cls,
            "dest": self.dest,
            "text": self.text(),
        }


@dataclass(frozen=True)
class Build:
    """One table ``T`` the controller built, and where its run starts.

    ``plan.start`` is the pair ``(q, s^B)`` the table was planned from: ``(q_0, s^B_0)`` for
    the initial table, the automaton state and observed W^B counts of the replan otherwise.
    ``history`` is a word of executable letters that leads the automaton from ``q_0`` to
    that ``q`` (the tree path to the pair), so ``history · plan.prefix · plan.cycle^ω`` can
    be checked against the formula itself. ``label``: ``initial`` or ``replan N at W^B …``.
    """

    label: str
    plan: Plan
    table: Table
    history: tuple[Letter, ...] = ()

    @property
    def start(self) -> tuple[int, Counts]:
        return self.plan.start


class Belief:
    """What the robot believes the workspace holds (task classes only).

    ``total`` counts objects in W^A, W^B and the gripper. Looking at W^A infers
    ``s^B = s \\ s_lo`` (Alg. 1 line 7); looking at W^B infers W^A the same way (line 9).
    A person who adds or removes objects (dis_2) makes ``total`` wrong: when W^B turns out to
    differ from the inference, the next look at W^A re-anchors ``total`` on the two fresh
    observations, so a wrong inference is corrected after one trip instead of repeating.
    """

    def __init__(self, a0: Counts, b0: Counts):
        self.total = [x + y for x, y in zip(a0, b0, strict=True)]
        self.b = list(b0)
        self.held: int | None = None
        self._resync = False

    def _held_vec(self) -> list[int]:
        return [1 if i == self.held else 0 for i in range(len(self.b))]

    def on_a(self, a_obs: Counts) -> Counts:
        h = self._held_vec()
        if self._resync:
            self.total = [a + b + x for a, b, x in zip(a_obs, self.b, h, strict=True)]
            self._resync = False
        self.b = [max(0, t - a - x) for t, a, x in zip(self.total, a_obs, h, strict=True)]
        self.total = [a + b + x for a, b, x in zip(a_obs, self.b, h, strict=True)]
        return tuple(self.b)

    def on_b(self, b_obs: Counts) -> Counts:
        if list(b_obs) != self.b:
            self._resync = True
        self.b = list(b_obs)
        h = self._held_vec()
        self.total = [max(t, b + x) for t, b, x in zip(self.total, b_obs, h, strict=True)]
        return tuple(self.b)

    def picked(self, i: int) -> None:
        self.held = i

    def placed(self) -> None:
        self.b[self._holding()] += 1
        self.held = None

    def returned(self) -> None:
        self.held = None

    def dropped(self) -> None:
        self.total[self._holding()] -= 1
        self.held = None

    def _holding(self) -> int:
        """The class held: placing or dropping follows a pick (`picked`)."""
        assert self.held is not None, "placed or dropped with nothing picked"
        return self.held

    def lost(self) -> None:
        """The held object left the gripper on the way, to somewhere unknown: the next looks
        find it (in W^A or W^B) or not (W^B then differs from the inference and re-anchors)."""
        self.held = None
        self._resync = True

    def removed(self, i: int, dest: str) -> None:
        self.b[i] -= 1
        if dest != "A":
            self.total[i] -= 1


@dataclass(frozen=True)
class Pending:
    """The skill the controller starts (or runs) and what to do when it ends.

    ``then`` names the continuation (``_on_<then>``); the other fields carry what the
    decision that chose the skill knew: the W^B state it expected, the table entry, the
    class handled, the removal's destination, a note for the record.
    """

    then: str
    action: Action
    b: Counts | None = None
    entry: Entry | None = None
    cls: int | None = None
    dest: str | None = None
    note: str = ""
    blocked: bool = False  # a wait because the task cannot go on (counts towards max_waits)


class LotsController:
    """Alg. 1 for one task, ticked against any `World` (symbolic or Drake).

    ``mode``: tree update variant (``bfs`` deterministic, ``random`` as in Alg. 3, seeded by
    ``seed``). ``max_waits``: consecutive waits after which the task is declared infeasible
    (at least 1). ``max_actions``: bound on robot actions (default `default_limit`).
    ``max_retries``: failures of a skill in a row before the controller stops. ``check``:
    called with the controller after every table it builds, before the table is used
    (``self.build`` is then the new one); it raises to stop the robot.
    """

    def __init__(
        self,
        task: Task,
        *,
        mode: str = "bfs",
        seed: int = 0,
        max_waits: int = 3,
        max_actions: int | None = None,
        max_retries: int = 3,
        automaton: Automaton | None = None,
        check: Callable[[LotsController], Any] | None = None,
    ):
        self.task = task
        self.aut = automaton or Automaton(task.formula, task.props, file=task.file)
        steps, cycle, final = initial_lasso(self.aut, task)
        idx = {c: i for i, c in enumerate(task.classes)}
        prop_class = {p.name: idx[p.cls] for p in task.propositions}
        self.lots = Lots(task.classes, prop_class, final, round_goals(self.aut, task, final))
        self.planner = Planner(self.aut, self.lots, task)
        self.planner.round_cycle = list(cycle)
        b0 = self.lots.vector(task.initial_b)
        root = (self.aut.initial, b0)
        cost = sum(self.planner.step_cost(s) for s in steps)
        #: Alg. 1 lines 2-3: the initial run (prefix + one cycle), the tree and the table.
        self.initial_plan = Plan(root, steps, cycle, cost)
        self.plan = self.initial_plan
        self.tree = Tree(self.planner, root, mode=mode, seed=seed)
        self.tree.add_plan(self.plan)
        self.table = Table.from_plan(self.plan, self.lots)
        self.tables: list[tuple[str, list[dict]]] = [("initial", self.table.rows())]
        self.max_waits = max(1, max_waits)
        self.max_actions = max_actions if max_actions is not None else self.default_limit(8)
        self.max_retries = max_retries
        self.replans = 0
        self.belief = Belief(self.lots.vector(task.initial_a), b0)
        self._last: Entry | None = None  # the entry whose action was executed last
        # tick state
        self.actions: list[ActionRecord] = []
        self.pending: Pending | None = None  # the skill to start, or running
        self.handle: int | None = None  # its world handle while it runs
        self.waits = 0  # consecutive waits because the task cannot go on
        self.looks = 0  # consecutive cycles that only looked (guard against oscillation)
        self.failures = 0  # consecutive skill failures (the looks between them do not count)
        self.ticks = 0
        self.skills = 0  # skills started
        self.result: Status | None = None
        self.reason = ""
        self.final_b: Counts | None = None  # W^B seen when the round was found complete
        #: the run's word so far (robot deliveries, observed W^B states), read by the automaton
        self.word = RunWord(self.aut, self.lots, b0)
        self._history: tuple[Letter, ...] = ()  # a word of the run reaching the plan's start
        self._a_seen: Counts | None = None  # W^A at the last look there (the stock)
        self.check = check
        if check is not None:
            check(self)

    @property
    def build(self) -> Build:
        """The table in use (``self.table``), its plan and where that plan starts."""
        return Build(self.tables[-1][0], self.plan, self.table, self._history)

    # ------------------------------------------------------------------ Alg. 1 lines 12-24
    def decide(self, b: Counts) -> Entry | None:
        """Table hit, or tree update + new table (Alg. 3, Alg. 2); None: cannot complete.

        While W^B is where the current run expects it, the run's next entry is used (a run may
        pass one W^B state twice); otherwise ``T[b]`` (one dict lookup).
        """
        states = self.word.peek(b)
        if self._last is not None:
            e = self.table.next_after(self._last, b)
            if e is not None and self._fits(e, states):
                return e
        e = self.table.get(b)
        if e is not None and self._fits(e, states):
            return e
        return self._replan(b)

    def _fits(self, e: Entry, states: dict[int, tuple[Letter, ...]]) -> bool:
        """Does following ``T`` from ``e`` complete the task after what happened?

        Yes when the word can be in ``e``'s automaton state; otherwise when the rest of the
        planned run, read from a state the word can be in, still ends where the round's
        cycle is accepted (a person's delivery may have done part of the run already).
        """
        if e.q in states:
            return True
        rest: list[Letter] = []
        for r in self.table.run[e.index :]:
            if r.kind == "done":
                break
            rest.append(r.letter)
        return self.word.completes(states, rest, list(self.plan.cycle))

    def _replan(self, b: Counts, cap: Counts | None = None) -> Entry | None:
        """Alg. 1 lines 15-21: tree update (Alg. 3) for W^B ``b`` and a new table ``T``.

        ``cap`` (objects per class that exist) is given when the table's way needs a class
        W^A has run out of: the replan then considers only the ways still possible.
        """
        states = self.word.peek(b)
        stock = None if self.task.returns else self._a_seen
        found = self.tree.update(b, cap, stock, allowed=states)
        if found is None:
            return None
        q, plan = found
        self._history = states[q]
        self.replans += 1
        self._last = None
        self.tree.add_plan(plan)
        self.plan = plan
        self.table = Table.from_plan(plan, self.lots)
        label = f"replan {self.replans} at W^B {self.lots.format(b)}"
        self.tables.append((label, self.table.rows()))
        if self.check is not None:
            self.check(self)  # before the new table is used
        return self.table.get(b)

    def plan_letters(self) -> tuple[list[Letter], list[Letter]]:
        """The current planned run as (prefix, cycle) letters, read from ``self.plan.start``."""
        return self.plan.prefix, self.plan.cycle

    def _still_needed(self, i: int, b: Counts) -> bool:
        """Could the rest of the task (from W^B state ``b``) deliver class ``i`` again?"""
        return self.lots.needs(i, b)

    def _needs_later(self, entry: Entry) -> bool:
        """Keep a removed object (back to W^A) when the rest of the plan delivers its class
        (only with our return action; Zhou et al.'s robot discards it)."""
        if not self.task.returns:
            return False
        rest = self.table.run[entry.index + 1 :]
        return any(e.kind == "move" and e.cls == entry.cls for e in rest)

    def default_limit(self, events: int = 0) -> int:
        """Bound on robot actions: one round, plus a few actions per human event."""
        n = sum(1 for s in self.initial_plan.steps if s.kind != "idle")
        return 2 * n + 6 + events * (2 * n + 4) + self.max_waits

    # ------------------------------------------------------------------ ticking
    @property
    def running(self) -> Action | None:
        """The skill running now, if any."""
        return self.pending.action if self.handle is not None and self.pending else None

    def tick(self, world: World) -> Status:
        """One step of Alg. 1: start the pending skill or poll the running one; never blocks.

        When a skill ends, its result is read (a ``LookAt``: the counts the camera sees) and
        the next skill is chosen; it starts on the next tick. Returns RUNNING until the round
        is complete (SUCCESS) or the task is found infeasible (FAILURE, ``reason``).
        """
        if self.result is not None:
            return self.result
        self.ticks += 1
        if self.handle is None:
            if self.pending is None:
                self._cycle()
                if self.result is not None:
                    return self.result
            self.handle = world.start(self._chosen().action)
            self.skills += 1
        status = world.poll(self.handle)
        if status is Status.RUNNING:
            return Status.RUNNING
        done, self.pending, self.handle = self._chosen(), None, None
        if status is Status.SUCCESS:
            if done.action.name != "LookAt":  # a retry starts with a look: not progress
                self.failures = 0
            getattr(self, f"_on_{done.then}")(done, world)
        else:
            self._on_failure(done, world)
        return self.result or Status.RUNNING

    def run(self, world: World, *, max_ticks: int = 100_000, step=None) -> Status:
        """Tick until SUCCESS or FAILURE (``step()`` is called before each tick if given)."""
        for _ in range(max_ticks):
            if step is not None:
                step()
            status = self.tick(world)
            if status is not Status.RUNNING:
                return status
        self.halt(world)
        return self._stop(f"no result after {max_ticks} ticks")

    def halt(self, world: World) -> None:
        """Cancel the running skill (the next tick starts the cycle again with a look)."""
        if self.handle is not None:
            world.cancel(self.handle)
        self.handle = self.pending = None

    def snapshot(self) -> LotsController:
        """This point of the run, to `restore` later (any number of times)."""
        return copy.deepcopy(self)

    def restore(self, snapshot: LotsController) -> None:
        """Continue from ``snapshot``: every counter, the belief, tree and table become a copy."""
        twin = copy.deepcopy(snapshot)
        self.__dict__.clear()
        self.__dict__.update(twin.__dict__)

    def __deepcopy__(self, memo: dict) -> LotsController:
        """Copy what a tick changes; share what never changes (task, automaton, planner,
        plans, tables: a replan replaces them, it does not edit them)."""
        new = LotsController.__new__(LotsController)
        memo[id(self)] = new
        new.__dict__.update(self.__dict__)
        new.tree = copy.deepcopy(self.tree, memo)
        new.tables = list(self.tables)
        new.belief = copy.deepcopy(self.belief, memo)
        new.actions = list(self.actions)
        new.word = copy.copy(self.word)
        new.word.events = list(self.word.events)
        return new

    # ------------------------------------------------------------------ Alg. 1, one skill at a time
    def _record(self, kind: str, i: int | None = None, prop=None, dest=None, note="") -> None:
        self.actions.append(
            ActionRecord(
                len(self.actions) + 1,
                kind,
                self.lots.classes[i] if i is not None else None,
                prop,
                dest,
                tuple(self.belief.b),
                note,
            )
        )

    def _chosen(self) -> Pending:
        """The skill to start or running: `_cycle` or the last continuation chose it (or
        set ``result``, which `tick` returns first)."""
        assert self.pending is not None, "no skill chosen"
        return self.pending

    def _next(self, then: str, name: str, *args: str, **kw: Any) -> None:
        self.pending = Pending(then, skill(name, *args), **kw)

    def _stop(self, reason: str) -> Status:
        self.result, self.reason = Status.FAILURE, reason
        return Status.FAILURE

    def _cycle(self) -> None:
        """Top of Alg. 1's loop: within the action bound, look at W^A."""
        if len(self.actions) >= self.max_actions:
            self._stop(f"task not completed within {self.max_actions} robot actions")
            return
        self._next("look_a", "LookAt", "A")

    def _seen(self, world: World, side: str) -> Counts | None:
        """What the camera sees of ``side`` now (the only read of the world), as counts."""
        counts = visible_counts(world.observe(), side)
        return None if counts is None else self.lots.vector(counts)

    def _look_b(self, done: Pending, world: World) -> Counts | None:
        b_obs = self._seen(world, "B")
        if b_obs is None:
            self._on_failure(done, world)
            return None
        self.word.observe(b_obs)
        return self.belief.on_b(b_obs)

    def _wait(self, note: str, *, blocked: bool = False) -> None:
        self._next("waited", "Wait", "A", note=note, blocked=blocked)

    def _on_failure(self, done: Pending, world: World | None = None) -> None:
        """A failed skill: try it again (a pick: look again first), up to ``max_retries``.

        A failed ``Place`` is decided by what the camera sees in the gripper: still holding
        the object, the place is tried again; the gripper empty (the object slipped out on
        the way), there is nothing to place: the robot forgets what it held and starts the
        cycle again with a look, continuing from where the object is now seen (or not).
        """
        self.failures += 1
        if self.failures > self.max_retries:
            self._stop(f"{done.action} failed {self.failures} times in a row")
        elif done.action.name == "Place" and world is not None and self._hand_empty(world):
            self.belief.lost()
        elif done.action.name != "Pick":
            self.pending = done

    def _hand_empty(self, world: World) -> bool:
        """Does the camera see the gripper empty while the robot believes it holds something?"""
        return self.belief.held is not None and held_kind(world.observe()) is None

    def _on_look_a(self, done: Pending, world: World) -> None:
        """Alg. 1 lines 5-24 from the view of W^A: remove a surplus, decide, act or wait."""
        a_obs = self._seen(world, "A")
        if a_obs is None:
            self._on_failure(done, world)
            return
        lots = self.lots
        self._a_seen = a_obs
        b = self.belief.on_a(a_obs)  # Alg. 1 lines 5-11
        self.looks += 1
        if self.looks > 8:  # observations keep disagreeing: let an action slot pass
            self.looks = 0
            self._wait("observations of W^A and W^B disagree")
            return
        if lots.surplus(b) is not None:  # more in W^B than one round needs (Lemma 1)
            self._next("look_b_surplus", "LookAt", "B")
            return
        entry = self.decide(b)
        missing = entry is not None and entry.kind == "move" and a_obs[_cls(entry)] == 0
        if missing:  # this way needs a class W^A lacks: replan over the ways still possible
            other = self._replan(b, cap=tuple(self.belief.total))
            if other is not None and not (other.kind == "move" and a_obs[_cls(other)] == 0):
                entry, missing = other, False
        if entry is None or missing:
            if entry is None:
                reason = self._shortage(b, a_obs) or (
                    f"W^B state {lots.format(b)} cannot lead to completion of "
                    f"{self.task.formula!r} (tree update exhausted {len(self.tree)} pairs)"
                    + ("" if self.task.returns else _NO_RETURN)
                )
            else:
                reason = f"no {lots.classes[_cls(entry)]} left in W^A for {entry.prop}"
            if self.looks == 1:  # the W^A inference may be stale: look at W^B first
                self._next("look_b_stale", "LookAt", "B", b=b, note=reason)
            else:
                self._blocked(reason)
        elif entry.kind == "done":
            self._next("look_b_done", "LookAt", "B", b=b)
        elif entry.kind == "remove":
            self._next("look_b_remove", "LookAt", "B", b=b, entry=entry)
        else:  # move: pick in W^A, carry to W^B, look before placing
            c = _cls(entry)
            self._next("picked", "Pick", lots.classes[c], "A", b=b, entry=entry, cls=c)

    def _shortage(self, b: Counts, a_obs: Counts) -> str | None:
        """Why no run is left, when W^A's stock is the cause: the class a run would need."""
        if self.task.returns:
            return None
        states = self.word.peek(b)
        found = self.tree.update(b, None, None, allowed=states)
        if found is None:
            return None
        left = list(a_obs)
        for s in found[1].steps:
            if s.kind == "move":
                c = _cls(s)
                if left[c] == 0:
                    return f"no {self.lots.classes[c]} left in W^A for {s.prop}"
                left[c] -= 1
        return None

    def _blocked(self, reason: str) -> None:
        self.looks = 0
        self._wait(reason, blocked=True)

    def _on_waited(self, done: Pending, world: World) -> None:
        self._record("wait", note=done.note)
        self.looks = 0
        if done.blocked:
            self.waits += 1
            if self.waits >= self.max_waits:
                self._stop(f"{done.note} (waited {self.waits} times)")

    def _on_look_b_surplus(self, done: Pending, world: World) -> None:
        b_obs = self._look_b(done, world)
        if b_obs is None:
            return
        j = self.lots.surplus(b_obs)
        if j is not None:
            name = self.lots.classes[j]
            self._next("removing", "Pick", name, "B", cls=j, dest=WASTE, note="surplus")

    def _on_look_b_stale(self, done: Pending, world: World) -> None:
        b_obs = self._look_b(done, world)
        if b_obs is not None and b_obs == done.b:
            self._blocked(done.note)

    def _on_look_b_done(self, done: Pending, world: World) -> None:
        b_obs = self._look_b(done, world)
        if b_obs is None:
            return
        if b_obs == done.b:
            self.final_b = b_obs
            self.result, self.reason = Status.SUCCESS, "round complete"
        elif self.looks > 4:
            self.looks = 0
            self._wait("W^B keeps changing")

    def _on_look_b_remove(self, done: Pending, world: World) -> None:
        b_obs = self._look_b(done, world)
        if b_obs is None or b_obs != done.b:
            return
        entry = _entry(done)
        dest = "A" if self._needs_later(entry) else WASTE
        name = self.lots.classes[_cls(entry)]
        self._next("removing", "Pick", name, "B", entry=entry, cls=entry.cls, dest=dest)

    def _on_removing(self, done: Pending, world: World) -> None:
        self.pending = Pending("removed", skill("Place", _dest(done)), **_carry(done))

    def _on_removed(self, done: Pending, world: World) -> None:
        self.belief.removed(_cls(done), _dest(done))
        self.word.remove(_cls(done))
        if done.entry is not None:
            self._last = done.entry
        self._record("remove", done.cls, dest=done.dest, note=done.note)
        self.waits = self.looks = 0

    def _on_picked(self, done: Pending, world: World) -> None:
        self.belief.picked(_cls(done))
        self.pending = Pending("carried", skill("LookAt", "B"), **_carry(done))

    def _on_carried(self, done: Pending, world: World) -> None:
        """At W^B with the object: place it, or re-decide if W^B changed meanwhile."""
        b_obs = self._look_b(done, world)
        if b_obs is None:
            return
        self.waits = self.looks = 0
        c = _cls(done)
        if b_obs == done.b:
            self._next("placed", "Place", "B", entry=done.entry, cls=c)
            return
        # W^B changed while the robot was carrying (unseen interference): re-decide
        e2 = None if self.lots.surplus(b_obs) is not None else self.decide(b_obs)
        if e2 is not None and e2.kind == "move" and e2.cls == c:
            self._next("placed", "Place", "B", entry=e2, cls=c)
        elif self._still_needed(c, b_obs):
            self._next("returned", "Place", "A", cls=c)
        else:
            self._next("discarded", "Place", WASTE, cls=c)

    def _on_placed(self, done: Pending, world: World) -> None:
        entry = _entry(done)
        self.belief.placed()
        self.word.deliver(_prop(entry))
        self._last = entry
        self._record("move", done.cls, prop=entry.prop)

    def _on_returned(self, done: Pending, world: World) -> None:
        self.belief.returned()
        self._record("return_held", done.cls)

    def _on_discarded(self, done: Pending, world: World) -> None:
        self.belief.dropped()
        self._record("discard_held", done.cls)


#: what a blocked run adds when our return action is off (the user may switch it on)
_NO_RETURN = (
    " with Zhou et al.'s actions (deliver W^A→W^B, discard); our return action W^B→W^A "
    "is off (--return-action or 'actions: {return: true}')"
)


def _cls(x: Entry | Step | Pending) -> int:
    """The class a move or remove (entry, step, or the skills carrying it out) handles:
    the planner and `_next` always set it there."""
    assert x.cls is not None, f"{x!r} names no class"
    return x.cls


def _prop(e: Entry) -> str:
    """The proposition a move entry delivers (the planner always sets it)."""
    assert e.prop is not None, f"{e!r} names no proposition"
    return e.prop


def _entry(p: Pending) -> Entry:
    """The table entry a place or remove continuation carries out (set by its decision)."""
    assert p.entry is not None, f"{p.then} without its table entry"
    return p.entry


def _dest(p: Pending) -> str:
    """Where a removal puts the object (set when the removal was chosen)."""
    assert p.dest is not None, f"{p.then} without a destination"
    return p.dest


def _carry(p: Pending) -> dict[str, Any]:
    """What a follow-up skill of the same decision keeps knowing."""
    return {"b": p.b, "entry": p.entry, "cls": p.cls, "dest": p.dest, "note": p.note}
