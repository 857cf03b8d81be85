"""Behavior-tree node kinds and their tick/halt semantics (SMP-MRO §IV-C).

A tree is a plain object graph of `Node` objects with ``parent`` links; ticking is a
direct recursive call ``node.tick(ctx)`` (no generators, no visitors, no blackboard), so a
tick costs a method call and a few attribute stores per visited node.

The context ``ctx`` (a `TickContext`, in practice the `PaBtExecutor`) carries the observed
state of this tick, a per-tick cache of condition values, the `World` the actions run on,
and the *pre-emption list* that implements **halt before start**: when a reactive node is
about to tick a child other than its RUNNING one, it registers that RUNNING child; the first
Action that is about to call ``world.start`` halts every registered child first (cancelling
its skill), so no skill ever starts while another one runs. If the other child finishes
without starting anything (e.g. a guard condition still holds) nothing is halted. py_trees
and BehaviorTree.CPP start the new action first and halt the old one afterwards
(BehaviorTree.CPP issue #1031).

Statuses are the `Status` enum of `tamp.world.interface`; ``node.status`` holds the last
returned value (None = idle / halted) and ``node.tick_id`` the tick in which it was set,
which is what `GetFailedNode` (Alg. 2 line 8) and the DOT colours read.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator
from typing import Protocol

from tamp.world.actions import Action
from tamp.world.interface import Status, World
from tamp.world.predicates import Predicate
from tamp.world.state import WorldState

SUCCESS = Status.SUCCESS
FAILURE = Status.FAILURE
RUNNING = Status.RUNNING

_uids = itertools.count(1)
_pred_keys: dict[Predicate, int] = {}


def predicate_key(pred: Predicate) -> int:
    """A small int per distinct predicate: the key of the per-tick condition cache."""
    key = _pred_keys.get(pred)
    if key is None:
        key = _pred_keys[pred] = len(_pred_keys)
    return key


class TickContext(Protocol):
    """What nodes need from the executor during one tick.

    ``state`` and ``world`` are the tick's observation and world: set while a tick (or a
    halt, which needs only ``world``) runs, None between ticks.
    """

    state: WorldState | None
    world: World | None
    cache: dict[int, bool]
    tick_id: int
    preempt: list[Node]

    def start_action(self, node: ActionNode) -> bool: ...

    def action_finished(self, node: ActionNode, status: Status) -> None: ...

    def cancel_action(self, node: ActionNode) -> None: ...

    def note_priority_switch(self, node: PriorityFallback, old: int, new: int) -> None: ...


class Node:
    """Base node: children, parent link, last status and the tick that set it."""

    __slots__ = ("uid", "parent", "children", "status", "tick_id", "__weakref__")
    kind = "Node"

    def __init__(self, children: Iterable[Node] = ()) -> None:
        self.uid = next(_uids)
        self.parent: Node | None = None
        self.children: list[Node] = []
        self.status: Status | None = None
        self.tick_id = -1
        for c in children:
            self.add(c)

    # -- structure (edits happen only between ticks) -------------------------------------
    def add(self, child: Node) -> Node:
        return self.insert(len(self.children), child)

    def insert(self, index: int, child: Node) -> Node:
        if child.parent is not None:
            raise ValueError(f"{child.describe()} already has a parent")
        self.children.insert(index, child)
        child.parent = self
        self._shift_indices(index, +1)
        return child

    def remove(self, child: Node) -> int:
        index = self.index_of(child)
        if self._active_index() == index:
            raise ValueError("cannot remove the running child")
        del self.children[index]
        child.parent = None
        self._shift_indices(index, -1)
        return index

    def replace(self, old: Node, new: Node) -> None:
        """Put ``new`` where ``old`` was; the node state (cursor, running child) is kept."""
        index = self.index_of(old)
        if new.parent is not None:
            raise ValueError(f"{new.describe()} already has a parent")
        self.children[index] = new
        old.parent = None
        new.parent = self

    def index_of(self, child: Node) -> int:
        for i, c in enumerate(self.children):
            if c is child:
                return i
        raise ValueError(f"{child.describe()} is not a child of {self.describe()}")

    def _active_index(self) -> int:
        return -1

    def _shift_indices(self, index: int, delta: int) -> None:
        """Keep cursor / running-child indices pointing at the same child after an edit."""

    # -- execution -------------------------------------------------------------------------
    def tick(self, ctx: TickContext) -> Status:  # pragma: no cover - abstract
        raise NotImplementedError

    def halt(self, ctx: TickContext) -> None:
        """Stop whatever runs below this node and reset its state (status becomes idle)."""
        for c in self.children:
            if c.status is RUNNING:
                c.halt(ctx)
        self.status = None

    # -- inspection ------------------------------------------------------------------------
    def describe(self) -> str:
        return self.kind

    def walk(self) -> Iterator[Node]:
        """Depth-first, children in order (the order the tree ticks them)."""
        stack: list[Node] = [self]
        while stack:
            n = stack.pop()
            yield n
            stack.extend(reversed(n.children))

    def size(self) -> int:
        return sum(1 for _ in self.walk())

    def path(self) -> list[Node]:
        """This node and its ancestors, innermost first."""
        out: list[Node] = []
        n: Node | None = self
        while n is not None:
            out.append(n)
            n = n.parent
        return out

    def state_key(self, tick_id: int) -> tuple:
        """This node's execution state as a hashable value (children not included).

        Kind, description, child count, last status and whether tick ``tick_id`` set it,
        then the node's own state slots (cursor, running child, priorities, failures,
        whether a skill runs); identity and payload (uid, links, predicate, action) are
        left out. `PaBtExecutor.state_key` combines these over the tree.
        """
        values = []
        for slot in _state_slots(self.__class__):
            v = getattr(self, slot)
            if slot == "handle":
                v = v is not None
            elif v.__class__ is list:
                v = tuple(v)
            values.append(v)
        status = self.status
        return (
            self.__class__.__name__,
            self.describe(),
            len(self.children),
            None if status is None else status.value,
            self.tick_id == tick_id,
            tuple(values),
        )

    def __repr__(self) -> str:
        return f"<{self.describe()} #{self.uid}>"

    def __deepcopy__(self, memo: dict) -> Node:
        """Copy the subtree below this node, top-down, sharing the immutable payloads.

        Node slots hold immutable values (ints, floats, enums, predicates, actions) or lists
        of them, except ``children`` (copied recursively; a child already in ``memo`` is
        taken from there, which is how `PaBtExecutor.fork` shares finished subtrees) and
        ``parent`` (the copy of the parent if it is being copied too, else None: a copied
        subtree is detached).
        """
        cls = self.__class__
        new = cls.__new__(cls)
        memo[id(self)] = new
        for slot in _slots_of(cls):
            value = getattr(self, slot)
            if slot == "children":
                value = [memo[id(c)] if id(c) in memo else c.__deepcopy__(memo) for c in value]
            elif slot == "parent":
                value = None if value is None else memo.get(id(value))
            elif value.__class__ is list:
                value = value[:]
            setattr(new, slot, value)
        return new


_SLOTS: dict[type, tuple[str, ...]] = {}


def _slots_of(cls: type) -> tuple[str, ...]:
    slots = _SLOTS.get(cls)
    if slots is None:
        names: list[str] = []
        for klass in reversed(cls.__mro__):
            for slot in getattr(klass, "__slots__", ()):
                if slot != "__weakref__" and slot not in names:
                    names.append(slot)
        # parent before children, so children find their parent's copy in the memo
        names.sort(key=lambda n: (n == "children",))
        slots = _SLOTS[cls] = tuple(names)
    return slots


_NOT_STATE = frozenset({"uid", "parent", "children", "status", "tick_id", "key", "pred", "action"})
_STATE_SLOTS: dict[type, tuple[str, ...]] = {}


def _state_slots(cls: type) -> tuple[str, ...]:
    slots = _STATE_SLOTS.get(cls)
    if slots is None:
        slots = _STATE_SLOTS[cls] = tuple(s for s in _slots_of(cls) if s not in _NOT_STATE)
    return slots


class Condition(Node):
    """Leaf that checks a predicate on the observed state; SUCCESS or FAILURE, never RUNNING.

    ``expanded`` is True for the guard condition of a ReactiveFallback made by ExpandTree,
    so GetFailedNode does not expand the same condition twice (Alg. 2 lines 8-10).
    """

    __slots__ = ("pred", "key", "expanded")
    kind = "Condition"

    def __init__(self, pred: Predicate, *, expanded: bool = False) -> None:
        super().__init__()
        self.pred = pred
        self.key = predicate_key(pred)
        self.expanded = expanded

    def tick(self, ctx: TickContext) -> Status:
        cache = ctx.cache
        key = self.key
        value = cache.get(key)
        if value is None:
            assert ctx.state is not None  # conditions are ticked only within a tick
            value = cache[key] = self.pred.holds(ctx.state)
        st = SUCCESS if value else FAILURE
        self.status = st
        self.tick_id = ctx.tick_id
        return st

    def halt(self, ctx: TickContext) -> None:
        self.status = None

    def describe(self) -> str:
        return str(self.pred)

    def state_key(self, tick_id: int) -> tuple:
        """`Node.state_key` with the predicate's small int key in place of its text (the
        same information, without formatting a string: keys are taken once per explored
        state)."""
        status = self.status
        return (
            "Condition",
            self.key,
            None if status is None else status.value,
            self.tick_id == tick_id,
            self.expanded,
        )

    def __deepcopy__(self, memo: dict) -> Condition:
        """`Node.__deepcopy__` for a leaf, spelled out: a grown tree is mostly conditions,
        and the verification explorer copies the live part of it once per explored state."""
        new = Condition.__new__(Condition)
        memo[id(self)] = new
        new.uid = self.uid
        parent = self.parent
        new.parent = None if parent is None else memo.get(id(parent))
        new.children = []
        new.status = self.status
        new.tick_id = self.tick_id
        new.pred = self.pred
        new.key = self.key
        new.expanded = self.expanded
        return new


class ActionNode(Node):
    """Leaf that runs one ground action as a skill: start once, then poll until done.

    Halting a RUNNING action cancels its skill (``world.cancel``). ``failures`` counts the
    attempts that ended in FAILURE (bounded retries, see the executor).
    """

    __slots__ = ("action", "handle", "failures")
    kind = "Action"

    def __init__(self, action: Action) -> None:
        super().__init__()
        self.action = action
        self.handle: int | None = None
        self.failures = 0

    def tick(self, ctx: TickContext) -> Status:
        if self.handle is None and not ctx.start_action(self):
            st = FAILURE
        else:
            # within a tick, and start_action gave the skill its handle
            assert ctx.world is not None and self.handle is not None
            st = ctx.world.poll(self.handle)
            if st is not RUNNING:
                ctx.action_finished(self, st)
        self.status = st
        self.tick_id = ctx.tick_id
        return st

    def halt(self, ctx: TickContext) -> None:
        if self.handle is not None:
            ctx.cancel_action(self)
        self.status = None

    def describe(self) -> str:
        return str(self.action)


class _Ordered(Node):
    """Ticks children in order from a cursor (shared by Sequence and Fallback).

    A child returning ``_passes`` lets the next one run; any other status ends the tick
    with it, and the cursor stays on that child when it is RUNNING (or, with ``memory``,
    on any stop) and otherwise goes back to the first child. When every child passes the
    node returns ``_passes``.
    """

    __slots__ = ("cursor",)
    _passes: Status = SUCCESS
    memory: bool = False

    def __init__(self, children: Iterable[Node] = ()) -> None:
        self.cursor = 0
        super().__init__(children)

    def tick(self, ctx: TickContext) -> Status:
        children = self.children
        passes = self._passes
        n = len(children)
        i = self.cursor
        while i < n:
            st = children[i].tick(ctx)
            if st is passes:
                i += 1
                continue
            self.cursor = i if st is RUNNING or self.memory else 0
            self.status = st
            self.tick_id = ctx.tick_id
            return st
        self.cursor = 0
        self.status = passes
        self.tick_id = ctx.tick_id
        return passes

    def halt(self, ctx: TickContext) -> None:
        super().halt(ctx)
        self.cursor = 0

    def _active_index(self) -> int:
        return self.cursor if self.status is RUNNING else -1

    def _shift_indices(self, index: int, delta: int) -> None:
        # A RUNNING child keeps the cursor even when a child is inserted right before it;
        # a cursor on a child that did not run (memory after a failure) moves to the new
        # child, which then runs next.
        if index < self.cursor or (index == self.cursor and self.status is RUNNING):
            self.cursor += delta


class Sequence(_Ordered):
    """Ticks children in order; fails at the first failure.

    ``memory=False`` is BehaviorTree.CPP's Sequence (resumes a RUNNING child, restarts from
    the first child after a failure); ``memory=True`` is its SequenceWithMemory: a child
    that succeeded is not ticked again until the sequence succeeds or is halted, even after
    a failure. The root built from C_goal uses memory, so a goal reached earlier stays done
    when a later goal moves the same object again (Case 2).
    """

    __slots__ = ("memory",)
    kind = "Sequence"
    _passes = SUCCESS

    def __init__(self, children: Iterable[Node] = (), *, memory: bool = False) -> None:
        self.memory = memory
        super().__init__(children)

    def describe(self) -> str:
        return "SequenceWithMemory" if self.memory else "Sequence"


class Fallback(_Ordered):
    """Ticks children in order until one does not fail (BehaviorTree.CPP Fallback)."""

    __slots__ = ()
    kind = "Fallback"
    _passes = FAILURE


class _Reactive(Node):
    """Re-ticks every child from the first on each tick (shared by the two reactive nodes).

    A child returning ``_passes`` lets the next one run; any other status ends the tick with
    it; when every child passes the node returns ``_passes``. When an earlier child stops
    passing while a later one is RUNNING, the RUNNING child is halted *before* anything new
    starts (see the module docstring).
    """

    __slots__ = ("running",)
    _passes: Status = SUCCESS

    def __init__(self, children: Iterable[Node] = ()) -> None:
        self.running = -1
        super().__init__(children)

    def tick(self, ctx: TickContext) -> Status:
        children = self.children
        passes = self._passes
        r = self.running
        start = 0
        if r >= 0:
            # Children before the RUNNING one are re-checked with it registered for
            # pre-emption: whatever starts among them halts it first.
            preempt = ctx.preempt
            mark = len(preempt)
            preempt.append(children[r])
            for i in range(r):
                st = children[i].tick(ctx)
                if st is passes:
                    continue
                del preempt[mark:]
                if children[r].status is RUNNING:
                    children[r].halt(ctx)
                self.running = i if st is RUNNING else -1
                self.status = st
                self.tick_id = ctx.tick_id
                return st
            del preempt[mark:]
            start = r
        n = len(children)
        i = start
        while i < n:
            st = children[i].tick(ctx)
            if st is passes:
                i += 1
                continue
            self.running = i if st is RUNNING else -1
            self.status = st
            self.tick_id = ctx.tick_id
            return st
        self.running = -1
        self.status = passes
        self.tick_id = ctx.tick_id
        return passes

    def halt(self, ctx: TickContext) -> None:
        super().halt(ctx)
        self.running = -1

    def _active_index(self) -> int:
        return self.running

    def _shift_indices(self, index: int, delta: int) -> None:
        if self.running >= index and self.running >= 0:
            self.running += delta


class ReactiveSequence(_Reactive):
    """Succeeds when every child succeeds, re-checking earlier children (preconditions)."""

    __slots__ = ()
    kind = "ReactiveSequence"
    _passes = SUCCESS


class ReactiveFallback(_Reactive):
    """Succeeds with the first child that does not fail; used as RF(condition, actions).

    When the guard condition becomes true while an achieving action runs, the action is
    halted (its skill cancelled) and the node succeeds.
    """

    __slots__ = ()
    kind = "ReactiveFallback"
    _passes = FAILURE


class PriorityFallback(Node):
    """A Fallback over alternatives ordered by priority, held as data (§IV-C, Alg. 3 l. 17).

    Children are tried from the highest priority down (ties: insertion order), resuming a
    RUNNING child like a Fallback with memory. `set_priority` changes a priority between
    ticks; if another child then ranks strictly above the RUNNING one, the next tick halts
    the RUNNING child (cancelling its skill) and restarts from the top of the new order.
    """

    __slots__ = ("priorities", "order", "cursor", "running", "reordered")
    kind = "PriorityFallback"

    def __init__(self, children: Iterable[Node] = (), priorities: Iterable[float] = ()) -> None:
        self.priorities: list[float] = []
        self.order: list[int] = []
        self.cursor = 0
        self.running = -1
        self.reordered = False
        super().__init__()
        pri = list(priorities)
        for k, c in enumerate(children):
            self.add(c, pri[k] if k < len(pri) else 0.0)

    def add(self, child: Node, priority: float = 0.0) -> Node:  # type: ignore[override]
        self.priorities.append(float(priority))
        super().insert(len(self.children), child)
        self._sort()
        return child

    def insert(self, index: int, child: Node, priority: float = 0.0) -> Node:  # type: ignore[override]
        self.priorities.insert(index, float(priority))
        super().insert(index, child)
        self._sort()
        return child

    def remove(self, child: Node) -> int:
        index = super().remove(child)
        del self.priorities[index]
        self._sort()
        return index

    def set_priority(self, index: int, priority: float) -> None:
        """Change one child's priority (between ticks); takes effect on the next tick."""
        self.priorities[index] = float(priority)
        self._sort()
        self.reordered = True

    def _sort(self) -> None:
        pri = self.priorities
        self.order = sorted(range(len(pri)), key=lambda i: (-pri[i], i))
        if self.running >= 0:
            self.cursor = self.order.index(self.running)

    def tick(self, ctx: TickContext) -> Status:
        if self.reordered:
            self.reordered = False
            r = self.running
            if r >= 0 and self.priorities[self.order[0]] > self.priorities[r]:
                self.children[r].halt(ctx)
                ctx.note_priority_switch(self, r, self.order[0])
                self.running = -1
                self.cursor = 0
        children = self.children
        order = self.order
        n = len(order)
        k = self.cursor
        while k < n:
            st = children[order[k]].tick(ctx)
            if st is FAILURE:
                k += 1
                continue
            if st is RUNNING:
                self.cursor = k
                self.running = order[k]
            else:
                self.cursor = 0
                self.running = -1
            self.status = st
            self.tick_id = ctx.tick_id
            return st
        self.cursor = 0
        self.running = -1
        self.status = FAILURE
        self.tick_id = ctx.tick_id
        return FAILURE

    def halt(self, ctx: TickContext) -> None:
        super().halt(ctx)
        self.cursor = 0
        self.running = -1

    def _active_index(self) -> int:
        return self.running

    def _shift_indices(self, index: int, delta: int) -> None:
        if self.running >= index and self.running >= 0:
            self.running += delta

    def describe(self) -> str:
        return "PriorityFallback[" + ", ".join(f"{p:g}" for p in self.priorities) + "]"


CONTROL_KINDS = (Sequence, Fallback, ReactiveSequence, ReactiveFallback, PriorityFallback)


def guard_of(node: Node) -> Predicate | None:
    """The condition a subtree establishes: a Condition's predicate, or the guard of RF(c, …)."""
    if isinstance(node, Condition):
        return node.pred
    if isinstance(node, ReactiveFallback) and node.children:
        first = node.children[0]
        if isinstance(first, Condition):
            return first.pred
    return None


def actions_in(node: Node) -> list[Action]:
    return [n.action for n in node.walk() if isinstance(n, ActionNode)]
