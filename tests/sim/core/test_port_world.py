"""`PortWorld`: the World protocol over the BtExecutor's ports (no simulation needed)."""

from __future__ import annotations

import pytest

from tamp.sim.core.executor import ExecutorState, PortWorld
from tamp.sim.core.messages import SkillStatus
from tamp.world import Area, Point, Pose, WorldState, default_domain
from tamp.world.interface import Status, World

STATE = WorldState(robot=Pose.at(0.0, 0.0), areas={"L0": Area("L0", Point(1.0, 0.0), 0.15)})


def world(s: ExecutorState, status: SkillStatus, t: float = 0.0) -> PortWorld:
    return PortWorld(s, STATE, status, t)


def test_is_a_world():
    assert isinstance(world(ExecutorState(b""), SkillStatus()), World)


def test_start_poll_sticky_and_one_skill_at_a_time():
    s = ExecutorState(b"")
    pick = default_domain().action("Pick", "O0")
    w = world(s, SkillStatus())  # the controller still reports the previous command
    h = w.start(pick)
    assert s.command.id == h and s.command.name == "Pick" and s.command.args == ("O0",)
    assert w.poll(h) is Status.RUNNING
    with pytest.raises(RuntimeError):
        w.start(default_domain().action("MoveTo", "L0"))
    assert world(s, SkillStatus(h, Status.RUNNING), 1.0).poll(h) is Status.RUNNING
    assert world(s, SkillStatus(h, Status.SUCCESS), 2.0).poll(h) is Status.SUCCESS
    assert s.log[-1].status == "SUCCESS" and s.log[-1].end == 2.0
    # sticky: the result stays even when the status port has moved on
    assert world(s, SkillStatus(h + 5, Status.RUNNING), 3.0).poll(h) is Status.SUCCESS
    h2 = world(s, SkillStatus(h, Status.SUCCESS), 3.0).start(pick)
    assert h2 == h + 1


def test_cancel_marks_the_command_and_the_log():
    s = ExecutorState(b"")
    w = world(s, SkillStatus())
    h = w.start(default_domain().action("MoveTo", "L0"))
    world(s, SkillStatus(h, Status.RUNNING), 0.5).cancel(h)
    assert s.command.cancel and s.command.id == h
    assert s.log[-1].status == "CANCELLED"
    assert world(s, SkillStatus(h, Status.RUNNING), 0.6).poll(h) is Status.FAILURE


def test_cancel_after_the_skill_ended_records_its_result():
    s = ExecutorState(b"")
    h = world(s, SkillStatus()).start(default_domain().action("MoveTo", "L0"))
    world(s, SkillStatus(h, Status.SUCCESS), 1.0).cancel(h)
    assert not s.command.cancel
    assert s.log[-1].status == "SUCCESS"


def test_areas_found_at_run_time_travel_with_the_command():
    s = ExecutorState(b"")
    w = world(s, SkillStatus())
    w.add_area(Area("free_auto1", Point(2.0, 2.0), 0.15))
    assert "free_auto1" in w.observe().areas
    w.start(default_domain().action("MoveTo", "free_auto1"))
    assert [a.name for a in s.command.areas] == ["free_auto1"]


def test_a_skill_halted_at_its_goal_is_halted_not_cancelled():
    """The reactive tree halts ``MoveTo(L0)`` once ``IsRobotCloseTo(L0)`` holds; the
    action table says HALTED (goal reached), not CANCELLED, for a MoveTo that did its job."""
    s = ExecutorState(b"")
    near = WorldState(robot=Pose.at(0.5, 0.0), areas=STATE.areas)  # 0.5 m < reach 0.9 m
    h = world(s, SkillStatus()).start(default_domain().action("MoveTo", "L0"))
    PortWorld(s, near, SkillStatus(h, Status.RUNNING), 0.7).cancel(h)
    rec = s.log[-1]
    assert s.command.cancel and s.command.id == h  # the controller is still told to stop
    assert (rec.status, rec.end, rec.detail) == ("HALTED", 0.7, "goal reached: IsRobotCloseTo(L0)")
    assert rec.outcome == "done (halted)"
    assert rec.to_json()["status"] == "HALTED"
    assert world(s, SkillStatus(h, Status.RUNNING), 0.8).poll(h) is Status.FAILURE
    # the same skill halted short of its goal stays CANCELLED
    s2 = ExecutorState(b"")
    h2 = world(s2, SkillStatus()).start(default_domain().action("MoveTo", "L0"))
    world(s2, SkillStatus(h2, Status.RUNNING), 0.5).cancel(h2)
    assert s2.log[-1].outcome == "CANCELLED" and s2.log[-1].detail == ""


def test_the_state_keeps_what_a_run_changes():
    """Areas found at run time and the current action live in the state; copies (Drake's
    contexts) do not share them."""
    s = ExecutorState(b"")
    w = world(s, SkillStatus())
    w.add_area(Area("free_auto1", Point(2.0, 2.0), 0.15))
    w.start(default_domain().action("MoveTo", "free_auto1"))
    fresh = ExecutorState(b"")
    assert fresh.extra_areas == {} and fresh.action is None
    import copy

    c = copy.deepcopy(s)
    c.extra_areas["free_auto2"] = Area("free_auto2", Point(3.0, 2.0), 0.15)
    assert "free_auto2" not in s.extra_areas and c.action is s.action
