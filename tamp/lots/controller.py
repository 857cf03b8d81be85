"""The reactive LOTS controller: Zhou et al. Alg. 1 on a world seen one workspace at a time.

Each cycle the robot looks at W^A (where it picks), infers W^B from what it believes the
whole workspace holds (Alg. 1 lines 6-11), looks the W^B state up in the table ``T``
(line 12) and acts; an unknown W^B state runs the tree update (Alg. 3) and rebuilds ``T``
(lines 15-21); a state that cannot lead to completion makes it wait (line 23). Before
placing, the camera sees W^B: if a person changed it meanwhile (unseen, dis_1/dis_2), the robot
re-decides on what it sees — it places the object if ``T`` still wants it, puts it back in
W^A if the rest of the task needs it, and otherwise drops it into the waste basket (the
surplus scissors of Fig. 8, the tower body of Fig. 10).

When the task can no longer be completed (Assumption 1 broken: every hammer taken away, a
W^B state no run can finish from), the robot waits a bounded number of times and then
raises `InfeasibleError` with the reason; it never loops forever.

Every table the controller builds (the initial one, Alg. 1 line 3, and each rebuilt after an
unforeseen W^B state, line 20) is described by a :class:`Build` — the plan, the table and the
pair ``(q, s^B)`` it starts from — and handed to the optional ``check`` (the verification
gate) *before* it is used: a check that raises stops the controller before the robot acts.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from tamp.errors import InfeasibleError
from tamp.lots.automaton import Automaton, Letter
from tamp.lots.lots import Counts, Lots
from tamp.lots.planner import Entry, Plan, Planner, Table, Tree, initial_lasso
from tamp.lots.task import Task
from tamp.lots.world import LocalWorld


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
        self.b[self.held] += 1
        self.held = None

    def returned(self) -> None:
        self.held = None

    def dropped(self) -> None:
        self.total[self.held] -= 1
        self.held = None

    def removed(self, i: int, dest: str) -> None:
        self.b[i] -= 1
        if dest != "A":
            self.total[i] -= 1


@dataclass
class Outcome:
    """Result of a controller run (what ``tamp lots --json`` prints, plus history)."""

    satisfied: bool
    actions: list[ActionRecord]
    replans: int
    final_b: Counts
    reason: str = ""
    tables: list[tuple[str, list[dict]]] = field(default_factory=list)


class LotsController:
    """Alg. 1 for one task; independent of how observations are produced (`LocalWorld`).

    ``mode``: tree update variant (``bfs`` deterministic, ``random`` as in Alg. 3, seeded by
    ``seed``). ``max_waits``: consecutive waits after which the task is declared infeasible
    (at least 1). ``check``: called with the controller after every table it builds, before
    the table is used (``self.build`` is then the new one); it raises to stop the robot.
    """

    def __init__(
        self,
        task: Task,
        *,
        mode: str = "bfs",
        seed: int = 0,
        max_waits: int = 3,
        automaton: Automaton | None = None,
        check: Callable[[LotsController], Any] | None = None,
    ):
        self.task = task
        self.aut = automaton or Automaton(task.formula, task.props, file=task.file)
        steps, cycle, final = initial_lasso(self.aut, task)
        idx = {c: i for i, c in enumerate(task.classes)}
        self.lots = Lots(task.classes, {p.name: idx[p.cls] for p in task.propositions}, final)
        self.planner = Planner(self.aut, self.lots, task)
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
        self.replans = 0
        self.belief = Belief(self.lots.vector(task.initial_a), b0)
        self._last: Entry | None = None  # the entry whose action was executed last
        self.check = check
        if check is not None:
            check(self)

    @property
    def build(self) -> Build:
        """The table in use (``self.table``), its plan and where that plan starts."""
        start = self.plan.start
        history = tuple(self.tree.letters_to(start)) if start in self.tree else ()
        return Build(self.tables[-1][0], self.plan, self.table, history)

    # ------------------------------------------------------------------ Alg. 1 lines 12-24
    def decide(self, b: Counts) -> Entry | None:
        """Table hit, or tree update + new table (Alg. 3, Alg. 2); None: cannot complete.

        While W^B is where the current run expects it, the run's next entry is used (a run may
        pass one W^B state twice); otherwise ``T[b]`` (one dict lookup).
        """
        if self._last is not None:
            e = self.table.next_after(self._last, b)
            if e is not None:
                return e
        e = self.table.get(b)
        if e is not None:
            return e
        found = self.tree.update(b)
        if found is None:
            return None
        _, plan = found
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
        """Does the rest of the task (from W^B state ``b``) deliver class ``i`` again?"""
        return self.lots.final[i] > b[i]

    def default_limit(self, events: int = 0) -> int:
        """Bound on robot actions: one round, plus a few actions per human event."""
        n = sum(1 for s in self.initial_plan.steps if s.kind != "idle")
        return 2 * n + 6 + events * (2 * n + 4) + self.max_waits

    # ------------------------------------------------------------------ the loop
    def run(
        self,
        world: LocalWorld,
        *,
        max_actions: int | None = None,
        record_into: list[ActionRecord] | None = None,
    ) -> Outcome:
        """Run Alg. 1 until the round is complete; `InfeasibleError` when it cannot be.

        ``record_into``: a list that receives the actions as they happen (kept when the run
        ends in `InfeasibleError`).
        """
        lots, names = self.lots, self.lots.classes
        limit = max_actions if max_actions is not None else self.default_limit(8)
        actions: list[ActionRecord] = record_into if record_into is not None else []
        waits = 0
        looks = 0  # consecutive cycles that only looked (guard against oscillation)

        def record(kind: str, i: int | None = None, prop=None, dest=None, note="") -> None:
            actions.append(
                ActionRecord(
                    len(actions) + 1,
                    kind,
                    names[i] if i is not None else None,
                    prop,
                    dest,
                    tuple(self.belief.b),
                    note,
                )
            )

        def look_b() -> Counts:
            return self.belief.on_b(lots.vector(world.observe("B")))

        while True:
            if len(actions) >= limit:
                raise InfeasibleError(f"task not completed within {limit} robot actions")
            a_obs = lots.vector(world.observe("A"))
            b = self.belief.on_a(a_obs)  # Alg. 1 lines 5-11
            looks += 1
            if looks > 8:  # observations keep disagreeing: let an action slot pass
                world.wait()
                record("wait", note="observations of W^A and W^B disagree")
                looks = 0
                continue
            i = lots.surplus(b)
            if i is not None:  # more in W^B than one round needs (Lemma 1): remove it
                b_obs = look_b()
                j = lots.surplus(b_obs)
                if j is not None:
                    world.remove_from_b(names[j], "waste")
                    self.belief.removed(j, "waste")
                    record("remove", j, dest="waste", note="surplus")
                    waits = looks = 0
                continue
            entry = self.decide(b)
            missing = entry is not None and entry.kind == "move" and a_obs[entry.cls] == 0
            if entry is None or missing:
                if looks == 1:  # the W^A inference may be stale: look at W^B first
                    if look_b() != b:
                        continue
                if entry is None:
                    reason = (
                        f"W^B state {lots.format(b)} cannot lead to completion of "
                        f"{self.task.formula!r} (tree update exhausted {len(self.tree)} pairs)"
                    )
                else:
                    reason = f"no {names[entry.cls]} left in W^A for {entry.prop}"
                world.wait()
                record("wait", note=reason)
                looks = 0
                waits += 1
                if waits >= self.max_waits:
                    raise InfeasibleError(f"{reason} (waited {waits} times)")
                continue
            if entry.kind == "done":
                b_obs = look_b()
                if b_obs == b:
                    return self._outcome(True, actions, b_obs)
                if looks > 4:
                    world.wait()
                    record("wait", note="W^B keeps changing")
                    looks = 0
                continue
            if entry.kind == "remove":
                if look_b() != b:
                    continue
                dest = "A" if self._needs_later(entry) else "waste"
                world.remove_from_b(names[entry.cls], dest)
                self.belief.removed(entry.cls, dest)
                self._last = entry
                record("remove", entry.cls, dest=dest)
                waits = looks = 0
                continue
            # move: pick in W^A, carry to W^B, look before placing
            c = entry.cls
            world.pick(names[c])
            self.belief.picked(c)
            b_obs = look_b()
            waits = looks = 0
            if b_obs == b:
                world.place()
                self.belief.placed()
                self._last = entry
                record("move", c, prop=entry.prop)
                continue
            # W^B changed while the robot was carrying (unseen interference): re-decide
            e2 = None if lots.surplus(b_obs) is not None else self.decide(b_obs)
            if e2 is not None and e2.kind == "move" and e2.cls == c:
                world.place()
                self.belief.placed()
                self._last = e2
                record("move", c, prop=e2.prop)
            elif self._still_needed(c, b_obs):
                world.return_held()
                self.belief.returned()
                record("return_held", c)
            else:
                world.discard_held()
                self.belief.dropped()
                record("discard_held", c)

    def _needs_later(self, entry: Entry) -> bool:
        """Keep a removed object (back to W^A) when the rest of the plan delivers its class."""
        rest = self.table.run[entry.index + 1 :]
        return any(e.kind == "move" and e.cls == entry.cls for e in rest)

    def _outcome(self, ok: bool, actions: list[ActionRecord], b: Counts) -> Outcome:
        return Outcome(ok, actions, self.replans, b, tables=self.tables)
