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
