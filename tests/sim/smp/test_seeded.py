"""Seeded SMP-MRO runs in Drake: reproducible per seed, friction grasps, camera perception."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tamp.commands.main import main
from tamp.sim.core.workcell import run_seeded

from .helpers import verified_runner, write_one_bottle

pytestmark = pytest.mark.slow

WALL = ("wall_time", "realtime_factor", "cpu_time", "cpu_realtime_factor")


def _cli(capsys, *args) -> dict:
    code = main(["simulate", "smp-mro", *args, "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code in (0, 1)
    for key in WALL:
        out.pop(key)
    return out


def test_same_seed_same_run_bit_for_bit_different_seed_differs(capsys):
    args = ("case3_perturbed", "--max-sim-time", "8")
    a = _cli(capsys, *args, "--seed", "7")
    b = _cli(capsys, *args, "--seed", "7")
    c = _cli(capsys, *args, "--seed", "8")
    assert a == b  # sim times, poses, actions, perturbation: identical
    assert a["seed"] == 7 and a["perturbation"]["seed"] == 7
    assert a["perturbation"]["size"] > 0 and a["grasp"] == "friction"
    assert c["perturbation"] != a["perturbation"]
    assert c["final_poses"] != a["final_poses"]
    assert a["status"] == "TIMEOUT" and a["cause"] == "timeout" and a["task_time"] == 8.0


def test_run_seeded_is_the_campaign_entry_point(tmp_path):
    path = write_one_bottle(
        tmp_path,
        "grasp: friction\nplant: {time_step: 0.005}\n"
        "perturbation: {objects: {xy: 0.02}, friction: [0.6, 0.9]}\n",
    )
    out = run_seeded("smp-mro", str(path), 3, verify=False)
    assert out["status"] == "SUCCESS" and out["cause"] is None and out["ok"] is True
    assert out["seed"] == 3 and 0.6 <= out["perturbation"]["friction"] <= 0.9
    assert out["task_time"] == out["sim_time"] > 5
    json.dumps(out)  # JSON-able as it is


def test_a_friction_grasp_slips_and_says_so(tmp_path):
    """With almost no friction the fingers cannot hold the bottle: it slips out while lifted
    or carried, the gripper detects it (the fingers close past its width), and the run's
    cause says which."""
    path = write_one_bottle(
        tmp_path,
        "grasp: friction\nplant: {time_step: 0.005}\nperturbation: {friction: [0.05, 0.05]}\n",
    )
    out = run_seeded("smp-mro", str(path), 0, verify=False, max_sim_time=20)
    assert out["status"] != "SUCCESS"
    assert out["failures"] and out["failures"][0]["action"] in ("Pick(O0)", "Place(O0, L0)")
    assert out["failures"][0]["cause"] in ("grasp_slipped", "grasp_missed")
    assert out["cause"] in ("grasp_slipped", "grasp_missed", "timeout")


def test_a_friction_grasp_lifts_carries_and_places(tmp_path):
    """The fingers' reference stays at the squeeze for as long as the bottle is held (every
    arm move starts it where it was), and the bottle does not move in the hand."""
    from tamp.sim.smp.robot import ROBOT
    from tamp.sim.smp.skills import FING, SQUEEZE

    path = write_one_bottle(tmp_path, "grasp: friction\nplant: {time_step: 0.005}\n")
    scenario, system, runner = verified_runner(path)
    assert system.welds == {}  # no weld constraint exists at all
    palm = system.plant.GetBodyByName(ROBOT.palm_body, system.robot)
    held = []  # (finger references, the bottle's height in the palm's frame) while carried

    def check(t: float) -> None:
        st = system.skills._st(system.skills.GetMyContextFromRoot(runner.root))
        if st.grasp.holding == "O0" and st.phase in ("lift", "drive", "preplace", "lower"):
            X_WG = system.plant.EvalBodyPoseInWorld(runner.plant_context, palm)
            X_WO = system.plant.EvalBodyPoseInWorld(runner.plant_context, system.bodies["O0"])
            z = X_WG.inverse().multiply(X_WO).translation()[2]
            held.append((tuple(st.segment.sample(t)[0][FING]), z))

    result = runner.run(on_chunk=check)
    assert result.status == "SUCCESS", result.reason
    assert len(held) > 50
    assert all(ref == (SQUEEZE, SQUEEZE) for ref, _ in held)
    heights = [z for _, z in held]
    assert max(heights) - min(heights) < 0.003  # no slip down the fingers (was 2-3 cm)
    assert result.final_poses["O0"].z == pytest.approx(0.1, abs=0.005)  # upright on the floor


def test_camera_estimates_are_within_a_centimetre_and_drive_the_skills(tmp_path):
    path = write_one_bottle(
        tmp_path, "grasp: friction\nplant: {time_step: 0.005}\nperception: camera\n"
    )
    scenario, system, runner = verified_runner(path)
    est = system.perception
    errors = []

    def check(t: float) -> None:
        s = est.state(est.GetMyContextFromRoot(runner.root))
        if "O0" in s.seen and s.following is None and t < 1.0:
            truth = runner.object_poses()["O0"]
            x, y, _, _ = s.estimates["O0"]
            errors.append(float(np.hypot(x - truth.x, y - truth.y)))

    result = runner.run(on_chunk=check)
    assert errors and max(errors) < 0.01
    assert result.status == "SUCCESS", result.reason
    assert result.perception == "camera"
    # the skill controller and the world-state estimator read the estimator's poses
    links = system.diagram.connection_map()
    for system_in in (system.skills, system.estimator):
        src, _ = links[(system_in, system_in.body_poses_port.get_index())]
        assert src is est
    frames = system.diagram.GetSubsystemByName("perception")
    ctx = frames.GetMyContextFromRoot(runner.root)
    assert frames.state(ctx).frames > 10


@pytest.mark.parametrize("perception", ["truth", "camera"])
def test_an_injected_friction_grasp_failure_is_seen_and_retried(tmp_path, perception):
    """``fail:`` with friction grasps: the hand does not close, the gripper's sensor says so
    (also with the camera, which cannot see under the gripper), the tree retries."""
    path = write_one_bottle(
        tmp_path,
        f"grasp: friction\nplant: {{time_step: 0.005}}\nperception: {perception}\n"
        'fail: ["Pick(O0)"]\n',
    )
    out = run_seeded("smp-mro", str(path), 0, verify=False)
    assert out["status"] == "SUCCESS", out["reason"]
    assert [f["cause"] for f in out["failures"]] == ["injected_failure"]
    assert [a["action"] for a in out["actions"] if a["status"] == "SUCCESS"][:2] == [
        "Pick(O0)",
        "Place(O0, L0)",
    ]


def test_a_goal_reached_with_the_obstacle_left_on_its_side_is_a_failure(capsys, tmp_path):
    """Case 3 with the camera, every object's friction 0.25 (the packaged draw is 0.5-0.9),
    seed 1: the robot sets O1 aside and picks O_a (the box a person put on l_1), which,
    held by too little friction, slips out of the fingers on the way to a free place and
    lies on its side; the robot puts O1 on l_1. O0 and O1 rest in their areas, so a
    goals-only judge called this a success; the run fails with cause ``disturbed``. (With
    the packaged friction all 50 seeds of the campaign succeed; the judge's "never picked,
    moved" branch is unit-tested in test_placement and test_appear. Until the estimator
    fused five views this was friction 0.2, seed 5; at 0.2 seeds 0-9 now end
    ``grasp_missed``, re-picking the fallen O_a.)"""
    packaged = Path(__file__).resolve().parents[3] / "tamp/scenarios/sim/case3_camera.yaml"
    text = packaged.read_text().replace("demonstration: ../case3.yaml", "demonstration: case3")
    path = tmp_path / "slippery.yaml"
    path.write_text(text.replace("friction: [0.5, 0.9]", "friction: [0.25, 0.25]"))
    out = _cli(capsys, str(path), "--seed", "1")
    assert out["perturbation"]["friction"] == 0.25
    assert out["goals"] == {"O0@L0": True, "O1@L1": True}
    executed = [a["action"] for a in out["actions"] if a["status"] == "SUCCESS"]
    assert "Pick(Oa)" in executed and executed[-1] == "Place(O1, L1)"
    assert "grasp_slipped" in [f["cause"] for f in out["failures"]]
    assert out["status"] == "FAILURE" and out["cause"] == "disturbed"
    (d,) = out["disturbed"]
    assert d["object"] == "Oa" and d["tilt_deg"] > 45 and d["moved"] is None
    assert d["reason"].startswith("Oa knocked over (tilt ")
    assert "on the plant Oa knocked over" in out["reason"]
