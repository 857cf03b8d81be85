"""The workcell in simulation: looks count what is in view, grasps hold by friction only,
perception never reads object poses, and the camera renders only when a view is asked for."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform

from tamp.sim.core.perception import CONFIRM_VIEWS
from tamp.sim.lots.driver import CellDriver
from tamp.sim.lots.scenario import load_cell_scenario
from tamp.sim.lots.skills import BLIND_DEPTH
from tamp.sim.lots.station import build_station
from tamp.world.interface import Status
from tests.sim.lots.helpers import write_scenario

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def building():
    """The packaged model-building scene (W^A: saw, 2 scissors, hammer; W^B empty)."""
    return build_station(load_cell_scenario("model_building"))


@pytest.fixture(scope="module")
def block_cell(tmp_path_factory):
    """One tower body (0.07 x 0.04 x 0.05 m) at the centre of W^A, long side along x."""
    path = write_scenario(
        tmp_path_factory.mktemp("cell"),
        [{"class": "body", "workspace": "A", "xy": [0.0, 0.0], "yaw": 0}],
    )
    return build_station(load_cell_scenario(path))


def test_diagram_is_named_and_exports_its_ports(building):
    d = building.diagram
    assert d.get_name() == "lots_cell_model_building"
    assert d.get_input_port(0).get_name() == "skill_command"
    assert d.GetInputPort("person_present").get_index() == 1
    for name in ("skill_status", "observation", "view_request", "arm_state", "safety_stopped"):
        assert d.HasOutputPort(name)


def test_controller_side_never_reads_object_poses(building):
    """Skills, perception and the safety monitor are fed by the camera, the arm's own state,
    the arm command stream and each other."""
    plant = building.plant
    allowed = {
        (building.camera.get_name(), p.get_name())
        for p in (
            building.camera.color_image_output_port(),
            building.camera.depth_image_32F_output_port(),
            building.camera.label_image_output_port(),
        )
    } | {
        (plant.get_name(), plant.get_state_output_port(building.cell.arm).get_name()),
        ("skills", "view_request"),
        ("skills", "desired_state"),
        ("perception", "observation"),
        ("safety", "stopped"),
        ("arm_command", "desired_state"),
        ("arm_command", "count"),
        ("safety_camera", building.camera.depth_image_32F_output_port().get_name()),
    }
    consumers = {
        building.skills.get_name(),
        building.perception.get_name(),
        building.safety.get_name(),
        building.command.get_name(),
    }
    fed = []
    for (sys_in, _), (sys_out, out_index) in building.diagram.connection_map().items():
        if sys_in.get_name() in consumers:
            fed.append((sys_out.get_name(), sys_out.get_output_port(out_index).get_name()))
    assert fed and set(fed) <= allowed
    # the wrist camera's images go to perception only
    cams = [k for k, v in building.diagram.connection_map().items() if v[0] is building.camera]
    assert {k[0].get_name() for k in cams} == {"perception"}
    # the safety monitor sees only its own depth camera's depth (class-agnostic: no labels)
    (safety_in,) = [
        (v[0].get_name(), v[0].get_output_port(v[1]).get_name())
        for k, v in building.diagram.connection_map().items()
        if k[0] is building.safety and v[0].get_name() == "safety_camera"
    ]
    assert safety_in == ("safety_camera", "depth_image_32f")
    # the arm's PD actuators get their targets through the safety monitor
    desired = plant.get_desired_state_input_port(building.cell.arm)
    src, _ = building.diagram.connection_map()[(plant, desired.get_index())]
    assert src is building.safety


def test_looks_count_one_workspace_at_a_time(building):
    d = CellDriver(building)
    a = d.run("LookAt(A)")
    assert a.status is Status.SUCCESS
    assert a.detail == "hammer=1,saw=1,scissors=2"
    assert d.observation().counts == {"hammer": 1, "saw": 1, "scissors": 2}
    b = d.run("LookAt(B)")
    assert b.status is Status.SUCCESS and d.observation().counts == {}
    assert d.observation().side == "B"
    assert d.stats().frames == 2 * CONFIRM_VIEWS  # a look's views, nothing else


def test_hidden_state_does_not_change_counts_but_visible_state_does(building):
    d = CellDriver(building)
    plant, pc = building.plant, d.plant_context()
    assert d.run("LookAt(B)").status is Status.SUCCESS
    before = d.observation().counts
    # a person moves the hammer inside W^A while the camera looks at W^B: nothing changes
    hammer = building.cell.bodies["hammer_0"]
    plant.SetFreeBodyPose(pc, hammer, RigidTransform([0.43, 0.16, 0.0]))
    assert d.run("LookAt(B)").detail == "" and d.observation().counts == before
    # the same person puts it into W^B: the next look at W^B sees it
    plant.SetFreeBodyPose(pc, hammer, RigidTransform([0.5, -0.25, 0.0]))
    assert d.run("LookAt(B)").detail == "hammer=1"
    assert d.run("LookAt(A)").detail == "saw=1,scissors=2"


def test_renders_only_when_asked(building):
    d = CellDriver(building)
    d.advance(1.0)
    assert d.stats().frames == 0
    d.run("LookAt(A)")
    d.advance(1.0)  # idle: the camera stays dark
    assert d.stats().frames == CONFIRM_VIEWS
    p = building.perception
    state = p.state(p.GetMyContextFromRoot(d.context))
    assert state.render_kinds == 2 * CONFIRM_VIEWS  # label + depth per view


def test_friction_grasp_lifts_the_block(block_cell):
    d = CellDriver(block_cell)
    body = block_cell.cell.bodies["body_0"]
    # close across the block's 4 cm side (fingers along world y at yaw 0)
    st = d.run("PickAt(A, 0.5, 0.25, 0)")
    assert st.status is Status.SUCCESS, d.skill_state().log
    z = body.EvalPoseInWorld(d.plant_context()).translation()[2]
    assert z > 0.08  # lifted with the hand (no weld: friction holds it)
    q = d.plant_context()
    fingers = block_cell.plant.GetPositions(q, block_cell.cell.arm)[7:]
    assert 0.035 < fingers.sum() < 0.042  # the fingers rest on the 4 cm block
    assert d.run("Place(B)").status is Status.SUCCESS
    xyz = body.EvalPoseInWorld(d.plant_context()).translation()
    assert abs(xyz[1] + 0.25) < 0.15 and xyz[2] < 0.005
    assert d.run("LookAt(B)").detail == "body=1"


@pytest.mark.parametrize("offset", [(0.06, 0.0), (0.0, 0.07)])
def test_offset_grasp_misses(block_cell, offset):
    d = CellDriver(block_cell)
    body = block_cell.cell.bodies["body_0"]
    st = d.run(f"PickAt(A, {0.5 + offset[0]}, {0.25 + offset[1]}, 0)")
    assert st.status is Status.FAILURE
    assert "missed" in st.detail and st.cause == "grasp_missed"  # the skill names its cause
    z = body.EvalPoseInWorld(d.plant_context()).translation()[2]
    assert z < 0.005  # still on the table


def test_a_retry_takes_another_grasp_than_the_one_that_missed(block_cell, monkeypatch):
    """The network's best grasp lies 6 cm beside the block: the fingers close on nothing;
    the retry's views propose that grasp again, and the pick takes the next one instead."""
    from tamp.sim.lots.grasping import GraspCandidate

    beside = GraspCandidate(0.56, 0.25, 0.05, 0.0, 0.06, 0.9, 0.2)
    on_block = GraspCandidate(0.50, 0.25, 0.05, 0.0, 0.06, 0.5, 0.2)
    monkeypatch.setattr(block_cell.planner, "candidates", lambda *a: [beside, on_block])
    d = CellDriver(block_cell)
    st = d.run("Pick(body)", timeout=120)
    log = [text for _, text in d.skill_state().log]
    assert st.status is Status.SUCCESS, log
    grasps = [t for t in log if t.startswith("grasp at (")]
    assert len(grasps) == 2 and grasps[0].startswith("grasp at (0.560")
    assert grasps[1].startswith("grasp at (0.500")
    assert any("closed on nothing" in t for t in log)
    assert d.run("Place(A)").status is Status.SUCCESS


def test_closed_loop_pick_with_hrgnet(building):
    """Pick(scissors): several views while descending, a network grasp, a friction lift."""
    building.planner.record = True
    building.planner.history.clear()
    d = CellDriver(building)
    st = d.run("Pick(scissors)", timeout=90)
    log = [text for _, text in d.skill_state().log]
    grasp = next(i for i, t in enumerate(log) if t.startswith("grasp at"))
    views = [t for t in log[:grasp] if t.startswith("view ")]
    # the look pose, then views taken while descending (Fig. 6): the hand keeps going down
    # between views, commits once the fused grasp is confident, and stops at the preset height
    descent = building.scenario.grasp.descent
    heights = [float(t.split(" at ")[1].split(" m")[0]) for t in views if " at " in t]
    first = heights[
        : next((i for i in range(1, len(heights)) if heights[i] > heights[i - 1]), None)
    ]
    assert first[0] == pytest.approx(0.47, abs=0.015)
    assert len(first) >= 1 + descent.min_views
    assert all(b < a for a, b in zip(first, first[1:], strict=False))
    assert min(first) >= descent.preset_height - 0.015
    assert any(t.endswith("confident") for t in views)
    # the closed final approach views on below it, down to where the gripper hides the target
    low = [float(t.split(" at ")[1].split(" m")[0]) for t in log[grasp:] if t.startswith("view ")]
    assert low and all(BLIND_DEPTH - 0.01 <= h <= descent.preset_height + 0.015 for h in low)
    assert len(building.planner.history) >= 1 + descent.min_views
    assert st.status is Status.SUCCESS, log
    held = [
        uid
        for uid, b in building.cell.bodies.items()
        if b.EvalPoseInWorld(d.plant_context()).translation()[2] > 0.05
    ]
    assert len(held) == 1 and held[0].startswith("scissors")
    assert d.skill_state().grasp_successes == 1


def test_start_poll_cancel(building):
    d = CellDriver(building)
    h = d.start("LookAt(B)")
    for _ in range(10):  # 0.5 s: the arm is on its way
        assert d.poll(h) is Status.RUNNING
    with pytest.raises(RuntimeError):
        d.start("LookAt(A)")
    v = building.plant.GetVelocities(d.plant_context(), building.cell.arm)[:7]
    assert np.max(np.abs(v)) > 0.2  # cancelled at speed
    d.cancel(h)
    assert d.poll(h) is Status.FAILURE and d.status().detail == "cancelled"
    d.advance(0.5)
    v = building.plant.GetVelocities(d.plant_context(), building.cell.arm)[:7]
    assert np.max(np.abs(v)) < 0.02  # stopped where it was
    monitor = building.safety
    safety = monitor.state(monitor.GetMyContextFromRoot(d.context))
    # braked within the joints' limits: the safety monitor saw no breach
    assert safety.stop is None and safety.stops == (), safety.all_stops(d.context.get_time())
    assert d.run("Discard()").detail == "nothing held"
    fly = d.run("Fly(A)")
    assert fly.status is Status.FAILURE and fly.cause == "task_failed"


def test_skills_speak_the_lots_arm_domain(building):
    """``Wait(l)``: a look at W^l and the domain's 2 s hold; ``Place(waste)`` is ``Discard()``."""
    d = CellDriver(building)
    t0 = d.context.get_time()
    st = d.run("Wait(A)")
    assert st.status is Status.SUCCESS and st.detail == "waited"
    assert d.context.get_time() - t0 >= 2.0 + 0.2  # the move over W^A, then the hold
    assert d.run("Place(waste)").detail == "nothing held"  # the Discard branch
    assert d.run("Place(floor)").status is Status.FAILURE


def test_a_perturbed_cell_adds_depth_noise_and_a_drawn_grasp_failure_is_retried():
    """``tower_perturbed`` at seed 116: depth noise between the camera and its readers, the
    seed's friction on the objects, and the first pick attempt drawn to fail (the hand stays
    open): the skill sees the object still on the table, names the cause, and tries again."""
    from tamp.sim.lots.scenario import perturbed

    scenario, applied = perturbed(load_cell_scenario("tower_perturbed"), 116)
    assert applied.skill_failures["Pick"] == [1]
    cell = build_station(scenario)
    conn = cell.diagram.connection_map()
    readers = {
        k[0].get_name(): v[0].get_name()
        for k, v in conn.items()
        if "depth" in k[0].get_input_port(k[1]).get_name()
    }
    assert readers == {
        "perception": "depth_noise",
        "safety": "safety_camera",  # the monitor's own camera, noise-free
        "depth_noise": "wrist_camera",
    }
    d = CellDriver(cell)
    st = d.run("Pick(bottom)", timeout=120)
    log = [text for _, text in d.skill_state().log]
    assert st.status is Status.SUCCESS, log
    assert any("drawn to fail" in t for t in log)
    assert any("injected" not in t and "did not close" in t for t in log)
    s = d.skill_state()
    assert s.picks_tried == 2 and s.grasp_successes == 1
