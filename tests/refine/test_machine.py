"""The state machine a robot runs: events on delivered data, commands at P (no Drake)."""

from __future__ import annotations

import math

import pytest

from tamp.refine.machine import ARM, Machine
from tamp.refine.queues import Delivery, Message
from tests.refine.helpers import task


def sample(sensor, value, created, delivered=None):
    return Delivery(Message(sensor, created, 0, value), delivered or created, 0.0)


def test_events_fire_only_on_delivered_samples_taken_after_the_start():
    m = Machine(task(4), "R1")
    s = m.step(m.initial(), 0.0, {}, {})
    assert "lower_arm" in s.started and s.started["lower_arm"] == 0.0
    # a stale sample (created before the start) below the threshold does not fire it
    s = m.step(s, 0.1, {"imu": sample("imu", -0.5, -0.05)}, {})
    assert "lower_arm" not in s.fired
    # a fresh one does, at the tick it arrives, and the next behavior starts
    s = m.step(s, 5.0, {"imu": sample("imu", -0.41, 4.9)}, {})
    assert s.fired["lower_arm"] == 5.0 and s.started["approach"] == 5.0
    # the arm holds where the IMU said it was, not where the setpoints ran ahead
    assert s.setpoints[ARM] == pytest.approx(-0.41)


def test_commands_leave_at_rate_p_and_each_moves_one_step():
    p = task(4)
    m = Machine(p, "R1")
    s = m.initial()
    numbers = []
    for k in range(101):  # 1 s of 10 ms ticks
        s = m.step(s, k * 0.01, {}, {})
        numbers.append(s.command.number)
    assert numbers[-1] == 11  # t = 0, 0.1, ..., 1.0 at 10 Hz
    lower = p.robot("R1").behavior("lower_arm")
    assert s.setpoints[ARM] == pytest.approx(-11 * lower.motion.speed / 10.0)
    # the supervisor's rate overrides the program's; the step per command is kept
    s2 = m.initial()
    for k in range(101):
        s2 = m.step(s2, k * 0.01, {}, {}, override=25.0)
    assert s2.command.number == 26
    assert s2.setpoints[ARM] == pytest.approx(-26 * lower.motion.speed / 10.0)


def test_a_tick_that_changes_nothing_returns_the_state_itself():
    """Between commands, with no event and no start, the step is the state it was given (the
    workcell's system then leaves its state alone); a due command or a fresh sample that
    fires an event gives a new state."""
    m = Machine(task(4), "R1")
    s = m.step(m.initial(), 0.0, {}, {})  # lower_arm starts, the first command leaves
    assert s.command.number == 1
    for k in range(1, 10):  # 10 Hz: nothing due before 0.1 s
        assert m.step(s, k * 0.01, {"imu": sample("imu", -0.1, k * 0.01)}, {}) is s
    due = m.step(s, 0.1, {}, {})
    assert due is not s and due.command.number == 2
    fired = m.step(s, 0.05, {"imu": sample("imu", -0.41, 0.04)}, {})
    assert fired is not s and fired.fired["lower_arm"] == 0.05


def test_waits_for_the_other_robot_and_odometry_progress():
    m = Machine(task(4), "R1")
    s = m.initial()
    s = m.step(s, 0.0, {}, {})
    s = m.step(s, 1.0, {"imu": sample("imu", -0.45, 0.9)}, {})
    start = task(4).robot("R1").start  # facing +x
    x, y, _ = start
    s = m.step(s, 1.01, {"odometry": sample("odometry", start, 1.0)}, {})
    assert s.refs["approach"] == start  # no odometry delivered yet: the start pose
    t0 = s.started["approach"]
    s = m.step(s, 19.0, {"odometry": sample("odometry", (x + 0.68, y, 0.0), 18.9)}, {})
    assert "approach" not in s.fired  # 0.68 m from the start: not yet 0.69
    s = m.step(s, 20.0, {"odometry": sample("odometry", (x + 0.70, y, 0.0), 19.9)}, {})
    assert s.fired["approach"] == 20.0 and t0 == 1.0
    # pull_out waits for R2.grip
    s = m.step(s, 21.0, {}, {})
    assert "pull_out" not in s.started
    s = m.step(s, 22.0, {}, {"R2.approach": 3.0, "R2.grip": 21.5})
    assert s.started["pull_out"] == 22.0


def test_progress_is_along_the_start_heading():
    from tamp.refine.machine import progress

    b = task(4).robot("R1").behavior("approach")
    assert progress(b, (0.0, 0.0, math.pi / 2), (0.3, 0.5, math.pi / 2)) == pytest.approx(0.5)
