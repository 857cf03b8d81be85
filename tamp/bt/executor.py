"""The PA-BT executor of SMP-MRO Alg. 2: build from C_goal, tick, grow between ticks.

``PaBtExecutor(c_goal, domain, free_areas=...)`` builds the initial tree (Alg. 2 l. 1-3: a
SequenceWithMemory of the goal conditions, so a goal reached earlier stays done when a
later goal moves the same object again). ``tick(world)`` observes the world, ticks the tree
once, and when the tree fails grows it before returning (l. 8-10):

- GetFailedNode: breadth-first, the first Condition that failed in this tick and has not
  been expanded yet; it is replaced by its expansion (`expand`, Alg. 3, a method this
  class inherits from `tamp.bt.expand.TreeGrowth`).
- No such condition but an action failed in this tick (a skill failure): the tree is
  ticked again next time, which restarts that action, at most ``max_retries`` times per
  action node. A failed alternative's priority in its PriorityFallback is multiplied by
  ``failure_decay``, so another achieving action may rank first on the next attempt.
- Otherwise, or when growth is impossible (no template, unresolvable conflict, more than
  ``max_expansions`` expansions (default `default_max_expansions`: it scales with the
  goals), the same action started again from the same state after
  it had already succeeded from it ``max_repeats`` times — a livelock), the executor stops
  with FAILURE and ``reason`` says why. It never loops.

``tick`` returns RUNNING while work remains (also right after a growth step), SUCCESS when
the root succeeded, FAILURE when stopped. The executor keeps no reference to the world
between ticks: it is a plain object graph that ``copy.deepcopy`` copies cheaply (the
predicates and actions are shared), as Drake's abstract state requires.
"""

from __future__ import annotations

import copy
from collections import Counter, deque
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import asdict, dataclass, field

from tamp.bt.expand import (
    ExpansionError,
    PriorityFn,
    TreeGrowth,
    success_rate_priority,
)
from tamp.bt.free_area import choose_free_area
from tamp.bt.nodes import (
    FAILURE,
    RUNNING,
    SUCCESS,
    ActionNode,
    Condition,
    Node,
    PriorityFallback,
    guard_of,
)
from tamp.bt.nodes import (
    Sequence as SequenceNode,
)
from tamp.world.actions import Action, Domain, default_domain
from tamp.world.geometry import Area
from tamp.world.interface import Status, World
from tamp.world.predicates import IsObjectAt, Predicate
from tamp.world.state import WorldState


@dataclass
class GrowthEvent:
    """One logged tree edit or executor decision."""

    tick: int
    kind: str  # expand | recovery | conflict | retry | priority | preempt | stop
    condition: str
    why: str
    detail: str = ""
    subtree: int | None = None  # uid of the subtree root involved

    def to_json(self) -> dict:
        return asdict(self)

    def __str__(self) -> str:
        text = f"[tick {self.tick}] {self.kind} {self.condition}: {self.why}"
        return text + (f" -> {self.detail}" if self.detail else "")


@dataclass
class ActionRecord:
    """An action attempt: when it started, how it ended (None while it runs)."""

    action: Action
    started: int
    ended: int | None = None
    status: str | None = None  # SUCCESS | FAILURE | CANCELLED

    def to_json(self) -> dict:
        return {
            "action": self.action.name,
            "args": list(self.action.args),
            "started": self.started,
            "ended": self.ended,
            "status": self.status,
        }


@dataclass
class ExecutorStats:
    ticks: int = 0
    expansions: int = 0
    recoveries: int = 0
    conflicts: int = 0
    conflict_moves: int = 0
    retries: int = 0
    implicit_preemptions: int = 0
    free_areas_found: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class ExecutorSnapshot:
    """A point of an executor's run to continue from (`resume`, `PaBtExecutor.restore`).

    `PaBtExecutor.snapshot` makes one by copying. Wrapping an executor directly,
    ``ExecutorSnapshot(ex)``, is the copy-free form for an executor that is not ticked any
    more (what the verification explorer does with each new state).
    """

    executor: PaBtExecutor = field(repr=False)

    def resume(self) -> PaBtExecutor:
        """A new executor continuing from this point (the snapshot stays usable)."""
        return copy.deepcopy(self.executor)

    def fork(self) -> PaBtExecutor:
        """Like `resume`, sharing the finished goal subtrees with the snapshot
        (`PaBtExecutor.fork`): what the verification explorer continues from."""
        return self.executor.fork()


def default_max_expansions(goals: int) -> int:
    """The expansion cap that scales with the task: 20 per goal, at least 200.

    A goal needs a handful of expansions (its condition, the action's preconditions, a
    recovery or two); a fixed cap stopped feasible tasks of more than about 66 goals.
    """
    return max(200, 20 * goals)


class PaBtExecutor(TreeGrowth):
    """Grows and ticks a behavior tree for C_goal against any `World` (Alg. 2)."""

    def __init__(
        self,
        c_goal: Sequence[Predicate],
        domain: Domain | None = None,
        *,
        free_areas: Iterable[str | Area] = (),
        priority: PriorityFn = success_rate_priority,
        max_expansions: int | None = None,
        max_retries: int = 3,
        max_repeats: int = 2,
        max_fruitless: int = 50,
        failure_decay: float = 0.5,
        record_attempts: bool = True,
    ) -> None:
        if not c_goal:
            raise ValueError("C_goal is empty: nothing to execute")
        self.domain = domain or default_domain()
        self.priority = priority
        self.max_expansions = (
            max_expansions if max_expansions is not None else default_max_expansions(len(c_goal))
        )
        self.max_retries = max_retries
        self.max_repeats = max_repeats
        self.max_fruitless = max_fruitless
        self.failure_decay = failure_decay
        self.record_attempts = record_attempts
        self.c_goal = list(c_goal)
        self.free_areas: list[str] = []
        self.extra_areas: dict[str, Area] = {}
        for a in free_areas:
            if isinstance(a, Area):
                self.free_areas.append(a.name)
                self.extra_areas[a.name] = a
            else:
                self.free_areas.append(str(a))
        self.goal_areas = sorted({c.area for c in self.c_goal if isinstance(c, IsObjectAt)})
        self.reserved: list[str] = []
        self.put_down_hint: dict[str, str] = {}
        # Alg. 2 l. 1-3: T <- Sequence(c for c in C_goal), with memory.
        self.root: Node = SequenceNode([Condition(c) for c in self.c_goal], memory=True)
        # Tick context (read by the nodes).
        self.state: WorldState | None = None
        self.world: World | None = None
        self.cache: dict[int, bool] = {}
        self.tick_id = 0
        self.preempt: list[Node] = []
        self.running: ActionNode | None = None
        self.ticking = False
        # Results.
        self.log: list[GrowthEvent] = []
        self.attempts: list[ActionRecord] = []
        self.stats = ExecutorStats()
        self.result: Status | None = None
        self.reason = ""
        self._abort: str | None = None
        self._completed_from: Counter = Counter()
        self._start_key: tuple | None = None
        self._pending_areas: list[Area] = []
        self._fruitless = 0
        #: goal conditions a fork shares untouched with the executor it came from, with
        #: their parent there (`fork`); empty for every other executor
        self._borrowed: list[tuple[Condition, Node]] = []

    # -- Alg. 2 main loop body -------------------------------------------------------------
    def tick(self, world: World) -> Status:
        """Tick the tree once against ``world``; grow it if it failed (between ticks)."""
        if self.result is not None:
            return self.result
        if self._borrowed:
            try:
                return self._tick(world)
            finally:
                self._return_borrowed()
        return self._tick(world)

    def _tick(self, world: World) -> Status:
        self.tick_id += 1
        self.stats.ticks += 1
        state = world.observe()
        if self.extra_areas:
            state = self._with_extra_areas(world, state)
        self.state = state
        self.world = world
        self.cache.clear()
        self.ticking = True
        try:
            st = self.root.tick(self)
        finally:
            self.ticking = False
            self.world = None
            del self.preempt[:]
        if self._abort is not None:
            return self._stop(self._abort, world)
        self._forget_passed_goals()
        if st is SUCCESS:
            self.result = SUCCESS
            self.reason = "every goal condition reached"
            return SUCCESS
        if st is FAILURE:
            # Grow on the state after this tick's effects (a skill may have just finished).
            state = world.observe()
            if self.extra_areas:
                state = self._with_extra_areas(world, state)
            return self._grow(state, world)
        return RUNNING

    def run(self, world: World, *, max_ticks: int = 10_000, step=None) -> Status:
        """Tick until SUCCESS or FAILURE (``step()`` is called before each tick if given)."""
        for _ in range(max_ticks):
            if step is not None:
                step()
            st = self.tick(world)
            if st is not RUNNING:
                return st
        return self._stop(f"no result after {max_ticks} ticks", world)

    def halt(self, world: World) -> None:
        """Stop everything (cancels a running skill)."""
        self.world = world
        try:
            self.root.halt(self)
        finally:
            self.world = None

    # -- growth (Alg. 2 l. 8-10) -----------------------------------------------------------
    def failed_condition(self) -> Condition | None:
        """GetFailedNode: breadth-first, the first unexpanded Condition that failed this tick."""
        queue: deque[Node] = deque([self.root])
        tick = self.tick_id
        while queue:
            n = queue.popleft()
            if n.tick_id != tick:
                continue
            if type(n) is Condition:
                if n.status is FAILURE and not n.expanded:
                    return n
                continue
            queue.extend(n.children)
        return None

    def ticked_nodes(self) -> Iterator[Node]:
        """The nodes ticked in the last tick, depth-first in tick order.

        A node is ticked only through its parent in the same tick, so a subtree whose root
        was not ticked holds no node that was: it is skipped whole (the finished goal
        subtrees of a long run cost nothing here).
        """
        tick = self.tick_id
        stack: list[Node] = [self.root]
        while stack:
            n = stack.pop()
            if n.tick_id != tick:
                continue
            yield n
            stack.extend(reversed(n.children))

    def _grow(self, state: WorldState, world: World) -> Status:
        if self._borrowed:  # growth edits the conditions this tick reached: own them first
            self._return_borrowed()
        self._fruitless += 1
        if self._fruitless > self.max_fruitless:
            return self._stop(
                f"the tree failed {self._fruitless} times in a row without any action "
                "succeeding in between",
                world,
            )
        node = self.failed_condition()
        if node is not None and node.pred.holds(state):
            return RUNNING  # it failed on an older observation; tick again
        if node is not None:
            try:
                self.state = state
                self.expand(node, why=f"{node.pred} failed")
            except ExpansionError as exc:
                return self._stop(str(exc), world)
            if self.stats.expansions > self.max_expansions:
                return self._stop(
                    f"more than {self.max_expansions} expansions; the tree stops growing "
                    "(the max_expansions cap: raise it with --max-expansions)",
                    world,
                )
            self._register_new_areas(world)
            return RUNNING
        failed = [n for n in self.ticked_nodes() if type(n) is ActionNode and n.status is FAILURE]
        if failed:
            for n in failed:
                if n.failures > self.max_retries:
                    return self._stop(
                        f"{n.action} failed {n.failures} times (max_retries={self.max_retries})",
                        world,
                    )
            names = ", ".join(str(n.action) for n in failed)
            self.stats.retries += 1
            self.log_event("retry", names, "skill failed", "ticked again", failed[0])
            return RUNNING
        guards = [
            str(n.pred) for n in self.ticked_nodes() if type(n) is Condition and n.status is FAILURE
        ]
        return self._stop(
            "the tree failed and no failed condition can be grown further"
            + (f" (failed: {', '.join(guards)})" if guards else ""),
            world,
        )

    def _stop(self, reason: str, world: World | None) -> Status:
        if world is not None and self.running is not None:
            self.halt(world)
        self.result = FAILURE
        self.reason = reason
        self.log_event("stop", "", reason)
        return FAILURE

    # -- services used by the nodes (TickContext) ------------------------------------------
    def start_action(self, node: ActionNode) -> bool:
        """Halt whatever must stop first (halt before start), then ``world.start``."""
        if self.preempt:
            pending = list(self.preempt)
            del self.preempt[:]
            for other in pending:
                other.halt(self)
        if self.running is not None and self.running is not node:
            # Not reachable through the reactive nodes; kept as a safety net and counted.
            self.stats.implicit_preemptions += 1
            self.log_event("preempt", str(self.running.action), "implicit", str(node.action))
            self.running.halt(self)
        key = (node.uid, _fingerprint(self.state), _cursor(self.root))
        if self._completed_from.get(key, 0) >= self.max_repeats:
            self._abort = (
                f"livelock: {node.action} would start again from a state it already "
                f"succeeded from {self._completed_from[key]} times"
            )
            return False
        assert self.world is not None  # actions start only within a tick
        node.handle = self.world.start(node.action)
        self.running = node
        self._start_key = key
        if self.record_attempts:
            self.attempts.append(ActionRecord(node.action, self.tick_id))
        return True

    def action_finished(self, node: ActionNode, status: Status) -> None:
        node.handle = None
        if self.running is node:
            self.running = None
        rec = self._open_record(node.action) if self.record_attempts else None
        if rec is not None:
            rec.ended = self.tick_id
            rec.status = status.value
        if status is FAILURE:
            node.failures += 1
            self._demote(node)
            return
        if self._start_key is not None:
            done = self._completed_from
            done[self._start_key] = done.get(self._start_key, 0) + 1
        self._fruitless = 0
        # The rest of this tick must see the action's effects: observe again.
        world = self.world
        if world is not None:
            state = world.observe()
            if state is not self.state:
                if self.extra_areas:
                    state = self._with_extra_areas(world, state)
                self.state = state
                self.cache.clear()

    def cancel_action(self, node: ActionNode) -> None:
        if node.handle is not None and self.world is not None:
            self.world.cancel(node.handle)
        node.handle = None
        if self.running is node:
            self.running = None
        rec = self._open_record(node.action)
        if rec is not None:
            rec.ended = self.tick_id
            rec.status = "CANCELLED"

    def note_priority_switch(self, node: PriorityFallback, old: int, new: int) -> None:
        self.log_event("priority", node.describe(), f"child {old} -> child {new}", "", node)

    def _demote(self, node: ActionNode) -> None:
        """A failed alternative loses priority (× ``failure_decay``) in its PriorityFallback,
        so after a failure the next attempt starts with the alternative that now ranks
        first (§IV-C3: "making the priority of actions variable")."""
        child: Node = node
        parent = node.parent
        while parent is not None and not isinstance(parent, PriorityFallback):
            child, parent = parent, parent.parent
        if parent is None or len(parent.children) < 2:
            return
        index = parent.index_of(child)
        new = parent.priorities[index] * self.failure_decay
        parent.set_priority(index, new)
        self.log_event("priority", str(node.action), "failed", f"priority {new:g}", parent)

    def set_priority(self, node: PriorityFallback, index: int, priority: float) -> None:
        """Change an alternative's priority between ticks (logged)."""
        node.set_priority(index, priority)
        self.log_event("priority", node.describe(), f"child {index} := {priority:g}", "", node)

    # -- services used by ExpandTree -------------------------------------------------------
    def reserve_free_area(self, state: WorldState, *, freeing: str | None) -> Area | None:
        area = choose_free_area(
            state,
            candidates=self.free_areas,
            goal_areas=self.goal_areas,
            freeing=freeing,
            reserved=self.reserved,
            auto_index=len(self.stats.free_areas_found) + 1,
        )
        if area is None:
            return None
        self.reserved.append(area.name)
        if area.name not in state.areas:
            self.extra_areas[area.name] = area
            self._pending_areas.append(area)
            self.stats.free_areas_found.append(area.name)
            # Later expansions in this growth step must see the new area.
            self.state = self.state.with_area(area) if self.state is not None else None
        return area

    def count_expansion(self) -> None:
        self.stats.expansions += 1

    def count_conflict(self, moves: int) -> None:
        self.stats.conflicts += 1
        self.stats.conflict_moves += moves

    def log_event(
        self,
        kind: str,
        condition: Predicate | str | None,
        why: str,
        detail: str = "",
        subtree: Node | None = None,
    ) -> None:
        if kind == "recovery":
            self.stats.recoveries += 1
        self.log.append(
            GrowthEvent(
                self.tick_id,
                kind,
                "" if condition is None else str(condition),
                why,
                detail,
                None if subtree is None else subtree.uid,
            )
        )

    # -- inspection ------------------------------------------------------------------------
    @property
    def executed(self) -> list[Action]:
        """Actions that finished with SUCCESS, in order."""
        return [r.action for r in self.attempts if r.status == "SUCCESS"]

    def size(self) -> int:
        return self.root.size()

    def goals_done(self) -> int:
        """How many goal conditions the root has passed (its memory cursor)."""
        root = self.root
        if self.result is SUCCESS:
            return len(self.c_goal)
        return root.cursor if isinstance(root, SequenceNode) else 0

    def describe(self) -> str:
        """Indented text view of the tree with last statuses."""
        lines: list[str] = []

        def rec(n: Node, depth: int) -> None:
            st = "" if n.status is None else f"  [{n.status.value}@{n.tick_id}]"
            lines.append("  " * depth + n.describe() + st)
            for c in n.children:
                rec(c, depth + 1)

        rec(self.root, 0)
        return "\n".join(lines)

    def to_dot(self) -> str:
        from tamp.bt.export import to_dot

        return to_dot(self.root)

    def to_btcpp_xml(self) -> str:
        from tamp.bt.export import to_btcpp_xml

        return to_btcpp_xml(self.root)

    # -- snapshots (what verification explores with) ----------------------------------------
    def snapshot(self, *, history: bool = True) -> ExecutorSnapshot:
        """This point of the run, to `restore` later (any number of times).

        ``history=False`` leaves out the report-only history (growth log, finished action
        records): it never influences a tick, and long explorations keep snapshots small.
        """
        twin = copy.deepcopy(self)
        if not history:
            twin.forget_history()
        return ExecutorSnapshot(twin)

    def restore(self, snapshot: ExecutorSnapshot) -> None:
        """Continue from ``snapshot``: the tree and every counter become a copy of it."""
        twin = snapshot.resume()
        self.__dict__.clear()
        self.__dict__.update(twin.__dict__)

    def forget_history(self) -> None:
        """Drop the report-only history (growth log, finished action records)."""
        self.log = []
        self.attempts = [r for r in self.attempts if r.status is None]

    def finished_goals(self) -> int:
        """How many leading children of the root are finished for good: the goal subtrees
        before the root's cursor while the executor runs (0 once it stopped).

        The root is a SequenceWithMemory (Alg. 2 l. 1-3) and is never reset while the
        executor runs (only its success or `_stop` resets it, and both end the run), so a
        child left of its cursor is never ticked again: from the tick after the one that
        passed it, its nodes keep a tick id older than every later tick, which hides them
        from GetFailedNode, from the failed-action and guard lists of `_grow`, and from
        conflict search (which only looks at ReactiveSequence ancestors of a new subtree,
        and the root is not one). Tree edits happen only at or after the cursor.
        """
        root = self.root
        if self.result is not None or not isinstance(root, SequenceNode) or not root.memory:
            return 0
        return root.cursor

    def live_key(self) -> tuple:
        """`state_key` restricted to what can still influence a tick: equal live keys,
        ticked against equal worlds, do the same thing from now on.

        Left out, because they never act again (see `finished_goals`): the finished goal
        subtrees and the livelock records of nodes no longer in the live tree. Node ids
        become positions in the live tree (two branches that grew the same subtree with
        different ids are the same state). A stopped executor does nothing more: its key is
        its result. This is the state hashing that makes the verification of a tree grown
        from per-goal subtrees scale with the goals (`tamp.verification.bt.explore`).
        """
        if self.result is not None:
            return ("stopped", self.result.value)
        tick = self.tick_id
        root = self.root
        done = self.finished_goals()
        position: dict[int, int] = {}
        nodes: list[int | tuple] = [
            (root.__class__.__name__, len(root.children), root.state_key(tick))
        ]
        for child in root.children[done:]:
            if type(child) is Condition:  # most of them: the goals not reached yet
                nodes.append(child.key if _untouched(child) else child.state_key(tick))
                continue
            for n in child.walk():
                position[n.uid] = len(nodes)
                nodes.append(n.state_key(tick))
        livelock = frozenset(
            (position[uid], fp, cursor, count)
            for (uid, fp, cursor), count in self._completed_from.items()
            if uid in position
        )
        start = self._start_key
        if self.running is None or start is None or start[0] not in position:
            start = None
        else:
            start = (position[start[0]], *start[1:])
        return (
            done,
            tuple(nodes),
            None if self.running is None else position.get(self.running.uid),
            livelock,
            start,
            self._fruitless,
            self.stats.expansions,
            tuple(self.reserved),
            tuple(sorted(self.extra_areas)),
            tuple(sorted(self.put_down_hint.items())),
        )

    def fork(self) -> PaBtExecutor:
        """A copy that continues the run from here, sharing with this executor (the lender)
        what it would otherwise copy for nothing: a copy costs the live part of the tree,
        not the whole grown tree.

        - The finished goal subtrees (`finished_goals`): neither executor ticks or edits them
          again.
        - The goal conditions after the cursor that are untouched since the executor built
          them: the fork makes the ones a tick reaches its own (`_return_borrowed`) before
          anything reads their parent or edits them, and leaves the lender's untouched.

        Shared nodes keep their parent links into the lender: ``copy.deepcopy`` of a fork
        gives a whole tree of its own (export that, or the lender, not the fork itself).
        What the verification explorer continues each state from.
        """
        memo: dict = {}
        children = self.root.children
        done = self.finished_goals()
        for child in children[:done]:
            memo[id(child)] = child
        borrowed = []
        for child in children[done + 1 :]:
            if _untouched(child):
                memo[id(child)] = child
                borrowed.append((child, child.parent))
        twin = copy.deepcopy(self, memo)
        twin._borrowed = borrowed
        return twin

    def _return_borrowed(self) -> None:
        """After a tick of a fork (and before it grows): the goal conditions it borrowed
        untouched (`fork`) and this tick reached are made its own, and the lender's are
        untouched again.

        The root ticks its children in order and growth edits only ticked nodes, so the
        touched ones are a prefix of the borrowed list: the first untouched one ends it.
        A touched condition still in this tree is replaced by a copy of its new values; one
        that growth replaced is only reset.
        """
        borrowed = self._borrowed
        k = 0
        root = self.root
        for node, owner in borrowed:
            if node.tick_id == -1 and node.parent is owner:
                break
            k += 1
            if node.parent is owner:
                mine = node.__deepcopy__({id(owner): root})
                root.children[root.index_of(node)] = mine
            node.status = None
            node.tick_id = -1
            node.parent = owner
        if k:
            self._borrowed = borrowed[k:]

    def state_key(self) -> tuple:
        """A hashable value of everything that decides what this executor does next.

        The tree (per node: kind, description, child count, last status and whether this
        tick set it, running skill, cursors, priorities, failure counts; no uids or tick
        numbers), the result, the running action, and the growth bookkeeping (livelock and
        fruitless-growth counters, expansions, reserved and found free areas). Executors
        with equal keys, ticked against equal worlds, do the same thing.
        """
        tick = self.tick_id
        return (
            tuple(n.state_key(tick) for n in self.root.walk()),
            None if self.result is None else self.result.value,
            None if self.running is None else self.running.describe(),
            frozenset(self._completed_from.items()),
            self._fruitless,
            self.stats.expansions,
            tuple(self.reserved),
            tuple(sorted(self.extra_areas)),
        )

    def __deepcopy__(self, memo: dict) -> PaBtExecutor:
        """Copy the tree and the executor's mutable bookkeeping; share what never changes
        (domain, predicates, actions, logged events, the last observed state)."""
        new = PaBtExecutor.__new__(PaBtExecutor)
        memo[id(self)] = new
        for k, v in self.__dict__.items():
            if k in self._SHARED:
                setattr(new, k, v)
            elif k in self._SHALLOW:
                setattr(new, k, copy.copy(v))
        new.root = copy.deepcopy(self.root, memo)
        for mine, theirs in zip(new.root.children, self.root.children, strict=True):
            if mine is not theirs:  # copied (a fork's lent children had their parent elsewhere)
                mine.parent = new.root
        new._borrowed = []
        new.running = None if self.running is None else memo[id(self.running)]
        new.preempt = [memo.get(id(n), n) for n in self.preempt]
        new.attempts = [copy.copy(r) for r in self.attempts]
        new.stats = copy.copy(self.stats)
        new.stats.free_areas_found = list(self.stats.free_areas_found)
        return new

    _SHARED = frozenset(
        {
            "domain", "priority", "state", "world", "c_goal", "max_expansions", "max_retries",
            "max_repeats", "max_fruitless", "failure_decay", "record_attempts", "tick_id",
            "result", "reason", "_abort", "_start_key", "_fruitless", "goal_areas", "ticking",
        }
    )  # fmt: skip
    _SHALLOW = frozenset(
        {
            "free_areas", "extra_areas", "reserved", "put_down_hint", "cache", "log",
            "_completed_from", "_pending_areas",
        }
    )  # fmt: skip

    # -- helpers ---------------------------------------------------------------------------
    def _forget_passed_goals(self) -> None:
        """Drop the livelock records of goals the root has passed: their key holds the
        root's cursor at the start, and the cursor only grows while the executor runs, so
        they can never match again. The bookkeeping of a long run stays one goal's size."""
        done = self._completed_from
        cursor = _cursor(self.root)
        # records are added in the order of the ticks, so the first has the oldest cursor
        if done and next(iter(done))[2] < cursor:
            self._completed_from = Counter({k: n for k, n in done.items() if k[2] >= cursor})

    def _open_record(self, action: Action) -> ActionRecord | None:
        for rec in reversed(self.attempts):
            if rec.status is None and rec.action == action:
                return rec
        return None

    def _with_extra_areas(self, world: World, state: WorldState) -> WorldState:
        self._register_new_areas(world)
        for name, area in self.extra_areas.items():
            if name not in state.areas:
                state = state.with_area(area)
        return state

    def _register_new_areas(self, world: World) -> None:
        """Areas found by the ring search are announced to worlds that accept them."""
        if not self._pending_areas:
            return
        add = getattr(world, "add_area", None)
        if add is not None:
            for area in self._pending_areas:
                add(area)
        self._pending_areas.clear()


def _fingerprint(state: WorldState | None) -> tuple:
    """A hashable value of the state (robot pose, held object, object positions)."""
    if not isinstance(state, WorldState):
        return (id(state),)
    return (state.robot, state.held, tuple(sorted((k, o.pos) for k, o in state.objects.items())))


def _untouched(node: Node) -> bool:
    """A goal condition as the executor built it: never ticked, never expanded."""
    return node.__class__ is Condition and node.tick_id == -1 and node.status is None


def _cursor(root: Node) -> int:
    return root.cursor if isinstance(root, SequenceNode) else 0


__all__ = [
    "ActionRecord",
    "ExecutorSnapshot",
    "ExecutorStats",
    "GrowthEvent",
    "PaBtExecutor",
    "guard_of",
]
