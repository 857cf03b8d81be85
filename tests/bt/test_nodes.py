"""Node semantics: sequences, fallbacks, reactive switching with halt before start, priorities."""

from __future__ import annotations

import copy

import pytest

from tamp.bt.nodes import (
    ActionNode,
    Condition,
    Fallback,
    PriorityFallback,
    ReactiveFallback,
    ReactiveSequence,
    Sequence,
)
from tamp.world.interface import Status

from .helpers import Ctx, Flag, act, calls, flag_world, set_flags

S, F, R = Status.SUCCESS, Status.FAILURE, Status.RUNNING


def test_sequence_memory_keeps_finished_children_after_a_failure() -> None:
    w = flag_world(a=True, b=False)
    ctx = Ctx(w)
    mem = Sequence([Condition(Flag("a")), Condition(Flag("b"))], memory=True)
    plain = Sequence([Condition(Flag("a")), Condition(Flag("b"))])
    assert ctx.tick(mem) is F and ctx.tick(plain) is F
    set_flags(w, a=False, b=True)
    # With memory, "a" is done and not re-checked; without memory it is checked again.
    assert ctx.tick(mem) is S
    assert ctx.tick(plain) is F


def test_fallback_resumes_running_child_and_does_not_recheck_earlier_ones() -> None:
    w = flag_world(a=False)
    ctx = Ctx(w)
    fb = Fallback([Condition(Flag("a")), ActionNode(act("Do"))])
    assert ctx.tick(fb) is R
    set_flags(w, a=True)
    assert ctx.tick(fb) is R  # not reactive: the running action continues
    assert calls(w) == [("start", "Do")]


def test_reactive_fallback_halts_running_action_when_guard_becomes_true() -> None:
    w = flag_world(done=False)
    ctx = Ctx(w)
    rf = ReactiveFallback([Condition(Flag("done")), ActionNode(act("Do"))])
    assert ctx.tick(rf) is R
    set_flags(w, done=True)
    assert ctx.tick(rf) is S
    assert calls(w) == [("start", "Do"), ("cancel", "Do")]
    assert rf.children[1].status is None and rf.running == -1


def test_reactive_sequence_halts_before_starting_the_new_child() -> None:
    """RS(RF(close, MoveTo), Pick): Pick runs; 'close' breaks -> Pick cancelled, then MoveTo."""
    w = flag_world(close=True)
    ctx = Ctx(w)
    rs = ReactiveSequence(
        [
            ReactiveFallback([Condition(Flag("close")), ActionNode(act("MoveTo"))]),
            ActionNode(act("Pick")),
        ]
    )
    assert ctx.tick(rs) is R
    set_flags(w, close=False)
    assert ctx.tick(rs) is R  # the world raises if MoveTo started while Pick runs
    assert calls(w) == [("start", "Pick"), ("cancel", "Pick"), ("start", "MoveTo")]
    assert rs.running == 0
    assert ctx.ex.stats.implicit_preemptions == 0


def test_reactive_sequence_keeps_running_child_when_earlier_subtree_still_succeeds() -> None:
    w = flag_world(close=True)
    ctx = Ctx(w)
    rs = ReactiveSequence(
        [
            ReactiveFallback([Condition(Flag("close")), ActionNode(act("MoveTo"))]),
            ActionNode(act("Pick")),
        ]
    )
    for _ in range(3):
        assert ctx.tick(rs) is R
    assert calls(w) == [("start", "Pick")]  # no spurious halt/restart


def test_reactive_sequence_failure_of_precondition_cancels_action() -> None:
    w = flag_world(pre=True)
    ctx = Ctx(w)
    rs = ReactiveSequence([Condition(Flag("pre")), ActionNode(act("Do"))])
    assert ctx.tick(rs) is R
    set_flags(w, pre=False)
    assert ctx.tick(rs) is F
    assert calls(w) == [("start", "Do"), ("cancel", "Do")]


def test_py_trees_starts_the_new_action_before_stopping_the_old_one() -> None:
    """The peer's order (observed in py_trees 2.6), which ours avoids: the same tree in
    py_trees."""
    py_trees = pytest.importorskip("py_trees")
    log: list[str] = []
    flags = {"close": True}

    class Act(py_trees.behaviour.Behaviour):
        def initialise(self) -> None:
            log.append(f"start {self.name}")

        def update(self):
            return py_trees.common.Status.RUNNING

        def terminate(self, new_status) -> None:
            if new_status == py_trees.common.Status.INVALID:
                log.append(f"cancel {self.name}")

    class Cond(py_trees.behaviour.Behaviour):
        def update(self):
            ok = flags[self.name]
            return py_trees.common.Status.SUCCESS if ok else py_trees.common.Status.FAILURE

    guard = py_trees.composites.Selector(
        "rf", memory=False, children=[Cond("close"), Act("MoveTo")]
    )
    root = py_trees.composites.Sequence("rs", memory=False, children=[guard, Act("Pick")])
    root.tick_once()
    flags["close"] = False
    root.tick_once()
    assert log == ["start Pick", "start MoveTo", "cancel Pick"]


def test_priority_fallback_tries_highest_priority_first_and_switches_on_change() -> None:
    w = flag_world()
    ctx = Ctx(w)
    pf = PriorityFallback([ActionNode(act("A")), ActionNode(act("B"))], [0.2, 0.8])
    assert [pf.children[i].action.name for i in pf.order] == ["B", "A"]
    assert ctx.tick(pf) is R
    assert ctx.tick(pf) is R
    assert calls(w) == [("start", "B")]
    ctx.ex.set_priority(pf, 0, 0.9)  # between ticks
    assert ctx.tick(pf) is R
    assert calls(w) == [("start", "B"), ("cancel", "B"), ("start", "A")]
    assert pf.running == 0
    assert any(e.kind == "priority" and "child 1 -> child 0" in e.why for e in ctx.ex.log)


def test_priority_fallback_falls_back_in_priority_order() -> None:
    w = flag_world({"B": F})
    ctx = Ctx(w)
    pf = PriorityFallback([ActionNode(act("A")), ActionNode(act("B"))], [0.2, 0.8])
    assert ctx.tick(pf) is R
    assert calls(w) == [("start", "B"), ("start", "A")]


def test_priority_change_that_keeps_the_running_child_first_does_not_restart_it() -> None:
    w = flag_world()
    ctx = Ctx(w)
    pf = PriorityFallback([ActionNode(act("A")), ActionNode(act("B"))], [0.9, 0.1])
    ctx.tick(pf)
    ctx.ex.set_priority(pf, 1, 0.5)
    ctx.tick(pf)
    assert calls(w) == [("start", "A")]


def test_edits_between_ticks_keep_running_index_and_parent_links() -> None:
    w = flag_world(a=True)
    ctx = Ctx(w)
    action = ActionNode(act("Do"))
    rs = ReactiveSequence([Condition(Flag("a")), action])
    assert ctx.tick(rs) is R and rs.running == 1
    extra = Condition(Flag("a"))
    rs.insert(0, extra)
    assert rs.running == 2 and rs.children[2] is action and extra.parent is rs
    assert ctx.tick(rs) is R
    assert calls(w) == [("start", "Do")]  # still the same skill, not restarted
    with pytest.raises(ValueError):
        rs.remove(action)  # the running child cannot be removed
    rs.remove(extra)
    assert rs.running == 1 and extra.parent is None
    for n in rs.walk():
        for c in n.children:
            assert c.parent is n


def test_memory_sequence_insert_at_cursor_runs_the_inserted_child_next() -> None:
    w = flag_world(a=True, b=False)
    ctx = Ctx(w)
    seq = Sequence([Condition(Flag("a")), Condition(Flag("b"))], memory=True)
    assert ctx.tick(seq) is F and seq.cursor == 1
    seq.insert(1, ActionNode(act("Fix")))
    assert seq.cursor == 1
    assert ctx.tick(seq) is R
    assert calls(w) == [("start", "Fix")]


@pytest.mark.parametrize("kind", [Sequence, Fallback])
def test_insert_before_the_running_child_keeps_it_running(kind) -> None:
    """The cursor used to move onto the inserted child: the node then returned without the
    RUNNING child, whose skill was never cancelled, and `_active_index` named the wrong one."""
    w = flag_world(a=kind is Sequence)
    ctx = Ctx(w)
    action = ActionNode(act("Do"))
    node = kind([action])
    assert ctx.tick(node) is R
    node.insert(0, Condition(Flag("a")))
    assert node.children[node._active_index()] is action
    with pytest.raises(ValueError):
        node.remove(action)
    assert ctx.tick(node) is R and action.status is R
    assert calls(w) == [("start", "Do")]  # resumed, not restarted, not abandoned


def test_deepcopy_keeps_state_and_shares_immutable_payloads() -> None:
    w = flag_world(a=True)
    ctx = Ctx(w)
    action = ActionNode(act("Do"))
    root = Sequence([Condition(Flag("a")), action], memory=True)
    ctx.tick(root)
    clone = copy.deepcopy(root)
    c_action = clone.children[1]
    assert c_action.handle == action.handle and c_action.status is R
    assert c_action.action is action.action  # shared, not copied
    assert c_action.parent is clone and clone.cursor == root.cursor
    assert c_action is not action


def test_condition_is_evaluated_once_per_tick() -> None:
    calls = []

    class Counting(Flag):
        def holds(self, state) -> bool:
            calls.append(1)
            return True

    w = flag_world()
    ctx = Ctx(w)
    pred = Counting("x")
    root = Sequence([Condition(pred), Condition(pred), Condition(pred)])
    assert ctx.tick(root) is S
    assert len(calls) == 1


def test_nested_reactive_switch_cancels_the_deep_running_skill_first() -> None:
    """RS(RF(c1, A1), RS(RF(c2, A2), A3)): A3 runs deep inside; c1 breaks -> A3 is
    cancelled before A1 starts; then c1 holds again and c2 breaks -> A1 was done, A2 runs."""
    w = flag_world(c1=True, c2=True)
    ctx = Ctx(w)
    inner = ReactiveSequence(
        [ReactiveFallback([Condition(Flag("c2")), ActionNode(act("A2"))]), ActionNode(act("A3"))]
    )
    root = ReactiveSequence(
        [ReactiveFallback([Condition(Flag("c1")), ActionNode(act("A1"))]), inner]
    )
    assert ctx.tick(root) is R
    set_flags(w, c1=False)
    assert ctx.tick(root) is R
    assert calls(w) == [("start", "A3"), ("cancel", "A3"), ("start", "A1")]
    assert inner.running == -1 and root.running == 0
    set_flags(w, c1=True, c2=False)
    assert ctx.tick(root) is R
    assert calls(w)[3:] == [("cancel", "A1"), ("start", "A2")]
    assert ctx.ex.stats.implicit_preemptions == 0
