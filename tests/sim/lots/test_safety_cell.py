"""The safety monitor in the workcell: something near the gripper stops the arm, which holds and
resumes when it leaves (the skill takes longer by the stop); a slow command stream stops the
arm. A tower body stands in for the person's hand here: the monitor is class-agnostic, and
with a person present from the start it has learnt no static scene, so the block is foreign
(the scripted person's hand at full speed: test_safety_speed.py)."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform

from tamp.sim.core.perception import CONFIRM_VIEWS
from tamp.sim.lots.catalogue import ARM
from tamp.sim.lots.driver import CellDriver
from tamp.sim.lots.scenario import load_cell_scenario
from tamp.sim.lots.station import build_station
from tamp.world.interface import Status

from .helpers import BASE, write_scenario

pytestmark = pytest.mark.slow
BLOCK = [{"id": "hand", "class": "body", "workspace": "A", "xy": [0.0, 0.0], "yaw": 0}]
#: a scripted top grasp 8 cm beside the block (W^A's centre is (0.5, 0.25)), on the side the
#: camera looks at: the pads pass within 5 cm of the block on the way down
PICK = "PickAt(A, 0.42, 0.25, 0)"


def _driver(path) -> CellDriver:
    cell = build_station(load_cell_scenario(path))
    d = CellDriver(cell)
    cell.diagram.GetInputPort("person_present").FixValue(d.context, [1.0])
    return d


def _tcp_z(d: CellDriver) -> float:
    plant = d.cell.plant
    tcp = plant.GetFrameByName(ARM.tcp_frame, d.cell.cell.arm)
    return float(tcp.CalcPoseInWorld(d.plant_context()).translation()[2])


def _run(d: CellDriver, handle: int, until: float) -> Status:
    st = Status.RUNNING
    while st is Status.RUNNING and d.context.get_time() < until:
        st = d.poll(handle)
    return st


def _safety(d: CellDriver):
    m = d.cell.safety
    return m.state(m.GetMyContextFromRoot(d.context))


def test_hand_near_the_gripper_stops_the_arm_until_it_leaves(tmp_path):
    d = _driver(write_scenario(tmp_path, BLOCK))
    h = d.start(PICK)
    while _safety(d).stop is None:
        assert d.poll(h) is Status.RUNNING and d.context.get_time() < 10.0
    s = _safety(d)
    assert s.stop.cause == "hand_near" and s.hand_distance < 0.05
    t_stop, z_stop = s.stop.time, _tcp_z(d)
    assert z_stop > 0.06  # stopped on the way down, above the block's top (5 cm)
    _run(d, h, t_stop + 0.3)  # braked (the PD pulls back to the pose at the stop)
    z_held = _tcp_z(d)
    assert abs(z_held - z_stop) < 0.01
    _run(d, h, t_stop + 1.5)  # the hand stays: the arm holds, the skill waits
    assert d.status().status is Status.RUNNING
    assert abs(_tcp_z(d) - z_held) < 1e-3
    assert _safety(d).stop is not None and _safety(d).frames >= 10  # watched every 0.1 s
    # the hand leaves (into W^B): the next image clears the stop and the grasp goes on
    plant = d.cell.plant
    block = d.cell.cell.bodies["hand"]
    plant.SetFreeBodyPose(d.plant_context(), block, RigidTransform([0.5, -0.25, 0.0]))
    end = _run(d, h, 30.0)
    assert end is not Status.RUNNING
    (stop,) = _safety(d).stops
    assert stop.cause == "hand_near" and stop.time == pytest.approx(t_stop)
    assert 1.5 <= stop.duration <= 1.5 + 0.25
    t_held = d.context.get_time()

    # the same grasp without the hand takes shorter by the stop's duration
    free = _driver(write_scenario(tmp_path, BLOCK))
    free.cell.plant.SetFreeBodyPose(free.plant_context(), block, RigidTransform([0.5, -0.25, 0]))
    h2 = free.start(PICK)
    assert _run(free, h2, 30.0) is end
    assert _safety(free).stops == ()
    assert t_held - free.context.get_time() == pytest.approx(stop.duration, abs=0.15)


def test_a_slow_command_stream_is_an_emergency_stop(tmp_path):
    control = {**BASE["control"], "command_period": 0.002}  # 500 Hz
    d = _driver(write_scenario(tmp_path, BLOCK, control=control))
    z0 = _tcp_z(d)
    h = d.start("LookAt(B)")
    assert _run(d, h, 2.0) is Status.RUNNING  # never gets anywhere
    s = _safety(d)
    assert s.stop.cause == "command_rate" and s.stop.time == pytest.approx(0.01)
    assert s.command_rate == pytest.approx(500.0)
    assert abs(_tcp_z(d) - z0) < 1e-3
    assert np.isfinite(s.min_rate)


def test_without_a_person_the_monitor_learns_the_scene_at_perceptions_views(tmp_path):
    """Without a person it takes a frame only when perception renders (no frames of its own)
    and learns what it sees as the static scene; its frames are depth-only at 80 x 45."""
    cell = build_station(load_cell_scenario(write_scenario(tmp_path, BLOCK)))
    assert cell.safety.size == (80, 45)
    d = CellDriver(cell)
    assert d.run("LookAt(A)").status is Status.SUCCESS
    assert d.run("LookAt(B)").status is Status.SUCCESS
    s = _safety(d)
    views = 2 * CONFIRM_VIEWS  # two looks
    assert d.stats().frames == views and s.frames == 0 and s.shared == views
    looks = cell.safety.looks
    assert [own for _, own, _ in looks] == [False] * views
    assert s.background is not None and len(s.background) >= 10  # the block (1 cm voxels)
    assert s.hand_distance == np.inf
    # a full-size depth render alone costs ~15 ms of CPU; a look at 80 x 45 a few ms
    assert max(cpu for _, _, cpu in looks) < 0.012
    assert s.stops == () and s.stop is None
    assert s.command_rate == pytest.approx(1000.0) and s.min_rate == pytest.approx(1000.0)
