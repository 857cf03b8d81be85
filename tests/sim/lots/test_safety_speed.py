"""The scripted person's hand at full speed against the descending gripper: the monitor, seeing
only its own 80 x 45 depth camera at 100 Hz, stops the arm before the gripper reaches the hand.

The cell's plant with the person's hand (``lots_person_hand.sdf`` on its PD-driven prismatic
joints) and no objects; the arm descends at the skills' TCP speed (0.35 m/s) while the hand
comes up from below at the person's speed (1.2 m/s, head-on: closing at 1.55 m/s) and stops
2 cm under where the fingertips are at that moment: without a monitor the fingers hit the
palm 57 ms later. The plant's poses only judge the run (the distance between the gripper's
collision boxes and the palm's box); the monitor never reads them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from tamp.sim.lots.catalogue import PERSON
from tamp.sim.lots.depth_safety import distance_to_boxes, safety_camera_config
from tamp.sim.lots.plant import add_cell_plant
from tamp.sim.lots.safety import GripperModel, SafetyMonitor
from tamp.sim.lots.scenario import SafetySettings, load_cell_scenario
from tamp.sim.lots.station import add_wrist_camera

from .helpers import write_scenario

pytestmark = pytest.mark.slow  # renders 100 depth frames a second
TCP_SPEED = 0.35
HAND_SPEED = PERSON.speed
PAD_BELOW = 0.015  # the pads' tips under the TCP
PALM_TOP = 0.025  # the palm's top over the hand body's origin
GAP_AT_STOP = 0.02  # fingertips over the palm when the hand stops
T_STOP = 0.1  # when the hand stops (s)
T_END = 0.35


def _straight_down(q9: np.ndarray) -> np.ndarray:
    """Joint speeds that move the TCP straight down at TCP_SPEED (the arm's Jacobian)."""
    g = GripperModel()
    g.set(q9)
    world = g.plant.world_frame()
    J = g.plant.CalcJacobianTranslationalVelocity(
        g.context, JacobianWrtVariable.kV, g.tcp, [0, 0, 0], world, world
    )
    qd = np.zeros(9)
    qd[:7] = np.linalg.pinv(J[:, :7]) @ [0.0, 0.0, -TCP_SPEED]
    return qd


def _run(tmp_path, monitored: bool) -> tuple[float, float, object]:
    """(the smallest gripper-palm distance, the hand's speed entering the band, monitor
    state) of one run; the plant's poses are read only here, to judge."""
    scenario = load_cell_scenario(write_scenario(tmp_path, []))
    b = DiagramBuilder()
    cell = add_cell_plant(b, scenario, staged=())
    plant = cell.plant
    assert list(cell.actuator_order) == list(range(9))
    q0 = cell.q0.copy()
    qd = _straight_down(q0)
    arm_path = PiecewisePolynomial.FirstOrderHold([0.0, T_END], np.c_[q0, q0 + qd * T_END])
    arm_source = b.AddSystem(TrajectorySource(arm_path, output_derivative_order=1))
    # the hand: straight up at full speed, stopping at T_STOP
    gripper = GripperModel()
    gripper.set(q0)
    tcp = gripper.tcp_pose().translation()
    tips_at_stop = tcp[2] - PAD_BELOW - TCP_SPEED * T_STOP
    top = tips_at_stop - GAP_AT_STOP - PALM_TOP  # the hand body's height at its stop
    start = top - HAND_SPEED * T_STOP
    xy = tcp[:2]
    hand_path = PiecewisePolynomial.FirstOrderHold(
        [0.0, T_STOP, T_END], np.c_[[*xy, start], [*xy, top], [*xy, top]]
    )
    hand_source = b.AddSystem(TrajectorySource(hand_path, output_derivative_order=1))
    b.Connect(hand_source.get_output_port(), plant.get_desired_state_input_port(cell.hand))
    monitor = None
    if monitored:
        cam = scenario.camera
        config = safety_camera_config(cam.width, cam.height, cam.fov_y_deg, cam.near, cam.far)
        camera, intrinsics = add_wrist_camera(b, plant, cell.scene_graph, cell.arm, config)
        monitor = b.AddSystem(
            SafetyMonitor(
                SafetySettings(min_command_rate=0.0),  # no command stream here
                intrinsics=intrinsics,
                width=config.width,
                height=config.height,
                perception_period=scenario.control.perception_period,
                actuator_order=cell.actuator_order,
            )
        )
        b.Connect(arm_source.get_output_port(), monitor.command_port)
        b.Connect(plant.get_state_output_port(cell.arm), monitor.arm_state_port)
        b.Connect(camera.depth_image_32F_output_port(), monitor.depth_port)
        b.Connect(monitor.desired_state_port, plant.get_desired_state_input_port(cell.arm))
    else:
        b.Connect(arm_source.get_output_port(), plant.get_desired_state_input_port(cell.arm))
    diagram = b.Build()
    sim = Simulator(diagram)
    ctx = sim.get_mutable_context()
    pc = plant.GetMyContextFromRoot(ctx)
    plant.SetPositions(pc, cell.arm, q0)
    plant.SetVelocities(pc, cell.arm, qd)  # already at speed
    plant.SetPositions(pc, cell.hand, [*xy, start])
    plant.SetVelocities(pc, cell.hand, [0.0, 0.0, HAND_SPEED])  # already at full speed
    if monitor is not None:
        mc = monitor.GetMyContextFromRoot(ctx)
        monitor.count_port.FixValue(mc, [0.0])
        monitor.present_port.FixValue(mc, [1.0])  # the person is in the cell
    sim.Initialize()
    palm = plant.GetBodyByName(PERSON.hand_body, cell.hand)
    judge = GripperModel()
    half = np.array([0.045, 0.0425, 0.0125])
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    grid = np.array(
        [[x, y, 1.0] for x in np.linspace(-1, 1, 9) for y in np.linspace(-1, 1, 9)]
    )  # the palm's top face, densely
    local = np.vstack([corners, grid]) * half + [0.0, 0.0, 0.0125]
    closest, entry_speed = math.inf, math.nan
    t = 0.0
    while t < T_END - 1e-9:
        t += 0.002
        sim.AdvanceTo(t)
        judge.set(plant.GetPositions(pc, cell.arm))
        X_WH = plant.EvalBodyPoseInWorld(pc, palm)
        d = distance_to_boxes(
            local @ X_WH.rotation().matrix().T + X_WH.translation(), judge.boxes_in_world()
        )
        if d < 0.05 and math.isnan(entry_speed):
            entry_speed = float(plant.GetVelocities(pc, cell.hand)[2])
        closest = min(closest, d)
    state = None if monitor is None else monitor.state(monitor.GetMyContextFromRoot(ctx))
    return closest, entry_speed, state


def test_without_a_monitor_the_gripper_hits_the_hand(tmp_path):
    closest, entry_speed, _ = _run(tmp_path, monitored=False)
    assert entry_speed > 1.1  # full speed into the band
    assert closest <= 0.0


def test_the_monitor_stops_the_arm_before_the_hand_at_full_speed(tmp_path):
    closest, entry_speed, s = _run(tmp_path, monitored=True)
    assert entry_speed > 1.1
    assert s.stop is not None and s.stop.cause == "hand_near"
    assert s.frames >= 10  # 100 Hz while the person is present
    assert closest > 0.0, f"the gripper came within {closest:.4f} m of the hand"
    # caught within one frame of entering the band: at most (1.2 + 0.35) m/s x 10 ms deeper
    # (plus a pixel's footprint), the nearest foreign point measured at the stop
    seen = float(s.stop.detail.split()[1])
    assert 0.05 - 1.55 * 0.01 - 0.006 <= seen < 0.05
