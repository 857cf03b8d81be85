"""The safety monitor's parts without a workcell: depth points and distances, the limit checks,
the stop decisions, and the monitor with the 1 kHz command stream in a small diagram (the
point subtraction: test_safety_depth.py)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from tamp.sim.lots.catalogue import ARM, READY
from tamp.sim.lots.command import ArmCommandStream
from tamp.sim.lots.depth_safety import depth_points, distance_to_boxes
from tamp.sim.lots.safety import (
    Checks,
    GripperModel,
    SafetyMonitor,
    SafetyState,
    check_limits,
    next_stop,
)
from tamp.sim.lots.scenario import SafetySettings

K = (100.0, 100.0, 39.5, 29.5)  # fx, fy, cx, cy of an 80 x 60 image
Q9 = np.r_[READY, ARM.finger_max, ARM.finger_max]
ORDER = list(range(9))


def test_depth_pixels_become_world_points_through_depth_and_pose():
    depth = np.full((60, 80), np.inf, np.float32)  # nothing in range
    depth[29, 39] = 0.5  # near the principal point
    depth[0, 0] = 0.2
    X_WC = RigidTransform(RotationMatrix.MakeXRotation(math.pi), [0.1, 0.2, 0.6])
    pts, too_close = depth_points(depth, K, X_WC)
    assert too_close == 0 and pts.shape == (2, 3)
    p_C = np.array([(0 - 39.5) * 0.2 / 100, (0 - 29.5) * 0.2 / 100, 0.2])
    assert pts[0] == pytest.approx(X_WC @ p_C)
    # the camera looks down from 0.6 m: a point 0.5 m ahead lies at z = 0.1
    assert pts[1][2] == pytest.approx(0.1)
    depth[5, 5] = 0.0  # nearer than the near plane
    assert depth_points(depth, K, X_WC)[1] == 1
    assert len(depth_points(np.full((60, 80), np.inf), K, X_WC)[0]) == 0


def test_distance_to_boxes_outside_inside_and_rotated():
    box = (RigidTransform([1.0, 0.0, 0.0]), np.array([0.1, 0.2, 0.3]))
    pts = np.array([[1.5, 0.0, 0.0], [1.0, 0.0, 0.0], [1.4, 0.5, 0.0]])
    assert distance_to_boxes(pts[:1], [box]) == pytest.approx(0.4)
    assert distance_to_boxes(pts, [box]) == 0.0  # the second point is inside
    assert distance_to_boxes(pts[2:], [box]) == pytest.approx(math.hypot(0.3, 0.3))
    turned = (RigidTransform(RotationMatrix.MakeZRotation(math.pi / 2), [1, 0, 0]), box[1])
    assert distance_to_boxes(pts[:1], [turned]) == pytest.approx(0.3)  # half x is 0.2 now
    assert distance_to_boxes(np.zeros((0, 3)), [box]) == math.inf


def test_gripper_model_has_the_palm_and_pads_at_the_tcp():
    g = GripperModel()
    assert sorted(b.body for b in g.boxes) == ["finger_left", "finger_right", "hand"]
    g.set(Q9)
    # the TCP (0.487 m up at the ready pose) lies between the open pads, whose inner faces
    # are at the fingers' 4 cm openings; the pads reach 15 mm below the TCP
    tcp = np.array([[0.307, 0.0, 0.487]])
    assert distance_to_boxes(tcp, g.boxes_in_world()) == pytest.approx(0.04, abs=1e-6)
    below = tcp - [0, 0, 0.1]
    d = distance_to_boxes(below, g.boxes_in_world())
    assert d == pytest.approx(math.hypot(0.1 - 0.015, 0.04), abs=1e-3)


def test_limits_on_measured_and_commanded_speed_and_acceleration():
    zero = np.zeros(7)
    assert check_limits(zero, zero, zero, 0.01) == []
    fast = zero.copy()
    fast[0] = 2.3  # joint 1: 2.175 rad/s
    assert [c for c, _ in check_limits(fast, zero, None, 0.01)] == ["speed_limit"]
    assert "commanded joint1" in check_limits(zero, fast, fast, 0.01)[0][1]
    jerk = zero.copy()
    jerk[5] = 0.25  # joint 6: 20 rad/s^2 -> 0.25 rad/s in 10 ms is 25 rad/s^2
    (breach,) = check_limits(zero, jerk, zero, 0.01)
    assert breach[0] == "accel_limit" and "joint6" in breach[1]
    jerk[5] = 0.19  # 19 rad/s^2: within the limit
    assert check_limits(zero, jerk, zero, 0.01) == []


SETTINGS = SafetySettings(hand_distance=0.05, recovery=0.5)
HOLD = np.arange(9.0)


def test_hand_stop_begins_holds_and_ends_on_a_new_image():
    s = dataclasses.replace(SafetyState(), hand_distance=0.04)
    ok = Checks(1000.0)
    assert next_stop(s, 1.0, SETTINGS, ok, False, HOLD).stop is None  # stale distance
    s = next_stop(s, 1.0, SETTINGS, ok, True, HOLD)
    assert s.stop.cause == "hand_near" and s.hold is HOLD
    s = dataclasses.replace(s, hand_distance=0.06)
    assert next_stop(s, 1.1, SETTINGS, ok, False, HOLD).stop is not None  # no new image yet
    s = next_stop(s, 1.2, SETTINGS, ok, True, HOLD)
    assert s.stop is None and s.hold is None
    (stop,) = s.stops
    assert (stop.cause, stop.time, stop.duration) == ("hand_near", 1.0, pytest.approx(0.2))
    assert stop.to_json()["duration"] == 0.2


def test_emergency_stops_last_the_recovery_time_and_until_cleared():
    s = next_stop(SafetyState(), 2.0, SETTINGS, Checks(500.0), False, HOLD)
    assert s.stop.cause == "command_rate" and s.until == 2.5
    assert next_stop(s, 2.6, SETTINGS, Checks(500.0), False, HOLD).stop is not None
    s = next_stop(s, 2.7, SETTINGS, Checks(1000.0), False, HOLD)
    assert s.stop is None and s.stops[0].duration == pytest.approx(0.7)
    s = next_stop(s, 3.0, SETTINGS, Checks(1000.0, (("accel_limit", "x"),)), False, HOLD)
    assert s.stop.cause == "accel_limit"
    assert next_stop(s, 3.4, SETTINGS, Checks(1000.0), False, HOLD).stop is not None
    s = next_stop(s, 3.5, SETTINGS, Checks(1000.0), False, HOLD)
    assert [x.cause for x in s.stops] == ["command_rate", "accel_limit"]
    assert s.all_stops(4.0)[-1].duration == pytest.approx(0.5)
    s = next_stop(s, 4.0, SETTINGS, Checks(10.0), False, HOLD)
    assert s.all_stops(4.25)[-1].duration == pytest.approx(0.25)
    assert s.all_stops(4.25)[-1].detail == "10 Hz; still stopped at the end"


def _stream_and_monitor(command_period: float, target: np.ndarray, v_meas=None):
    """The stream (setpoints every 10 ms) feeding a monitor (its camera input left open: no
    person is present, so it never looks)."""
    b = DiagramBuilder()
    stream = b.AddSystem(ArmCommandStream(command_period, 0.01, [True] * 7 + [False] * 2, Q9))
    monitor = b.AddSystem(
        SafetyMonitor(
            SETTINGS,
            intrinsics=K,
            width=80,
            height=60,
            perception_period=0.02,
            actuator_order=ORDER,
        )
    )
    b.Connect(stream.desired_state_port, monitor.command_port)
    b.Connect(stream.count_port, monitor.count_port)
    b.ExportInput(stream.target_port, "target")
    b.ExportInput(monitor.arm_state_port, "arm_state")
    b.ExportOutput(monitor.desired_state_port, "desired_state")
    d = b.Build()
    sim = Simulator(d)
    ctx = sim.get_mutable_context()
    d.GetInputPort("target").FixValue(ctx, np.r_[target, np.zeros(9)])
    x = np.r_[Q9, np.zeros(9) if v_meas is None else v_meas]
    d.GetInputPort("arm_state").FixValue(ctx, x)
    sim.AdvanceTo(0.1)
    s = monitor.state(monitor.GetMyContextFromRoot(ctx))
    return s, d.GetOutputPort("desired_state").Eval(ctx)


def test_a_1khz_stream_passes_and_reaches_its_setpoint():
    target = Q9 + np.r_[0.001, np.zeros(8)]  # 0.1 rad/s for 10 ms: within every limit
    s, desired = _stream_and_monitor(0.001, target)
    assert s.stop is None and s.stops == ()
    assert s.command_rate == pytest.approx(1000.0) and s.min_rate == pytest.approx(1000.0)
    assert desired[:9] == pytest.approx(target) and desired[9:] == pytest.approx(0.0)


def test_watchdog_stops_a_500hz_stream():
    s, desired = _stream_and_monitor(0.002, Q9)
    assert s.stop.cause == "command_rate" and s.stop.time == pytest.approx(0.01)
    assert s.command_rate == pytest.approx(500.0)


def test_commanded_acceleration_breach_stops_and_holds_the_measured_pose():
    target = Q9 + np.r_[0.003, np.zeros(8)]  # 0 -> 0.3 rad/s in one 10 ms step: 30 rad/s^2
    s, desired = _stream_and_monitor(0.001, target)
    assert s.stop.cause == "accel_limit" and "joint1" in s.stop.detail
    assert desired[:9] == pytest.approx(Q9) and desired[9:] == pytest.approx(0.0)


def test_measured_speed_breach_stops():
    v = np.zeros(9)
    v[4] = 2.8  # joint 5: 2.61 rad/s
    s, _ = _stream_and_monitor(0.001, Q9, v_meas=v)
    assert s.stop.cause == "speed_limit" and "measured joint5" in s.stop.detail


def test_scenario_safety_section_defaults_and_errors(tmp_path):
    from tamp.errors import InputError
    from tamp.sim.lots.scenario import load_cell_scenario
    from tests.sim.lots.helpers import BASE, write_scenario

    s = load_cell_scenario(write_scenario(tmp_path, []))
    assert s.safety == SafetySettings() and s.control.command_period == 0.001
    assert (s.safety.hand_distance, s.safety.min_command_rate) == (0.05, 1000.0)
    s = load_cell_scenario(write_scenario(tmp_path, [], safety={"hand_distance": 0.08}))
    assert s.safety.hand_distance == 0.08
    bad = [
        ({"safety": {"hand_distanse": 0.05}}, "safety.hand_distanse"),
        ({"safety": {"hand_distance": 0}}, "safety.hand_distance"),
        ({"safety": {"min_command_rate": "fast"}}, "safety.min_command_rate"),
        ({"safety": {"image_period": 0.001}}, "safety.image_period"),  # below perception's
        ({"safety": {"enabled": "yes"}}, "safety.enabled"),
        ({"safety": {"check_period": 0.015}}, "safety.check_period"),  # 0.02 / 0.015
        ({"control": {**BASE["control"], "command_period": 0.05}}, "control.command_period"),
    ]
    for changes, field in bad:
        with pytest.raises(InputError) as err:
            load_cell_scenario(write_scenario(tmp_path, [], **changes))
        assert err.value.field == field, changes
        assert "cell.yaml" in str(err.value.file)
