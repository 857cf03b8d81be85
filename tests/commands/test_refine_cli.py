"""``tamp refine``: the phases measured end to end, files written, bad input exit 2."""

from __future__ import annotations

import json

import pytest

from tamp.commands.main import main as tamp_main
from tamp.refine.loader import load_program
from tests.refine.helpers import task_dict, write
from tests.sim.refine.helpers import SHORT


@pytest.mark.slow  # a Drake simulation of the short Task 4 program
def test_refine_short_program_end_to_end(tmp_path, capsys):
    """The shortened Task 4: every phase simulated, the rate found online, files written."""
    gantt, out = tmp_path / "g" / "phases.svg", tmp_path / "refined.yaml"
    args = ["--json", "--timeline", str(gantt), "--refined", str(out)]
    code = tamp_main(["refine", str(SHORT), *args])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    names = [p["name"] for p in doc["phases"]]
    assert names == ["original", "parallelized", "speed-adjusted", "rate-refined"]
    times = [p["task_time"] for p in doc["phases"]]
    assert times[0] > times[1] >= times[2] > times[3] > 0
    assert doc["category"] == "II"
    assert 16 <= doc["rate_hz"] <= 28  # 3 Hz steps of the test architecture around 23 Hz
    assert doc["reduction"] == pytest.approx(1 - times[3] / times[0], abs=1e-3)
    assert doc["parallelized"] == ["R1: lower_arm runs in parallel with approach"]
    assert doc["verified"] is True
    assert all(p["run_satisfies_ordering"] for p in doc["phases"])  # measured orders too
    assert gantt.read_text().lstrip().startswith("<?xml") and "rate-refined" in gantt.read_text()
    refined = load_program(out)
    assert all(b.rate_hz == doc["rate_hz"] for _, _, b in refined.behaviors())
    assert refined.robot("R1").behavior("approach").parallel_with == "lower_arm"


def test_bad_program_exits_2_naming_the_field(tmp_path, capsys):
    data = task_dict(4)
    data["robots"][0]["behaviors"][1]["motion"] = {"distance": 0.0}
    bad = write(tmp_path, data)
    assert tamp_main(["refine", str(bad), "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["file"] == str(bad) and doc["field"].endswith("motion.distance")
    assert tamp_main(["refine", "task4", "--category", "IV"]) == 2
    assert tamp_main(["refine", "task4", "--gantt", str(tmp_path)]) == 2  # a directory


def test_a_bad_architecture_file_exits_2_naming_its_file_and_field(tmp_path, capsys):
    """The program's architecture file is read by tamp.schema: a sensor rate that is not
    positive is refused with the architecture file and the dotted field."""
    import yaml

    from tamp.scenarios import path

    arch = yaml.safe_load(path("refine/architecture_per_sensor.yaml").read_text())
    arch["sensor_rates_hz"]["odometry"] = 0
    (tmp_path / "arch.yaml").write_text(yaml.safe_dump(arch))
    data = task_dict(4)
    data["architecture"] = "arch.yaml"
    data["scene"] = str(path("refine/scenes/open_chair.yaml"))
    assert tamp_main(["refine", str(write(tmp_path, data)), "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["file"] == str(tmp_path / "arch.yaml")
    assert doc["field"] == "sensor_rates_hz.odometry"


def test_a_program_that_cannot_finish_exits_1(tmp_path, capsys):
    data = task_dict(4)
    data["robots"][0]["behaviors"][1]["event"] = {"sensor": "odometry", "reaches": 2.0}
    assert tamp_main(["refine", str(write(tmp_path, data))]) == 1
    assert "cannot finish" in capsys.readouterr().err
    data = task_dict(4)
    data["robots"][1]["behaviors"][1]["waits_for"] = ["R1.raise_arm"]  # a cycle
    assert tamp_main(["refine", str(write(tmp_path, data, "cycle.yaml"))]) == 1
    assert "cycle" in capsys.readouterr().err


def test_packaged_programs_resolve_from_any_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert load_program("task4").name == "task4"
    assert load_program("task2.yaml").scene == "flip_scale"


def _fake_simulate(misses):
    """The workcell's `simulate` replaced by the timeline model of the loop's tests: every
    behavior lasts its nominal time; runs of programs ``misses`` says True for leave the
    chair shut (hinge 0.2 rad, goal >= 0.35); a tuning run finds 23 Hz."""
    from tamp.refine.measure import Goal, Outcome, Run
    from tamp.refine.steps import RateSearch
    from tests.refine.test_refinement import timeline

    goal = Goal("folding_chair.hinge", 0.35, "the chair is open")

    def simulate(program, architecture, *, tune=False, max_sim_time=None, record=None, scene=None):
        run = Run(program, timeline(program), sim_time=100.0)
        run.outcome = Outcome({"folding_chair.hinge": 0.2 if misses(program) else 0.48}, (goal,))
        if tune:
            run.searches = {
                f"{r.name}.{s}": RateSearch(10.0, 1.0, 0.03, 200.0, found=23.0)
                for r in program.robots
                for s in ("imu", "odometry", "force")
            }
        return run

    return simulate


def test_no_accepted_program_meeting_the_goal_exits_1_with_the_reason(
    tmp_path, capsys, monkeypatch
):
    import tamp.sim.refine.simulate as workcell

    monkeypatch.setattr(workcell, "simulate", _fake_simulate(lambda p: True))
    out = tmp_path / "refined.yaml"
    assert tamp_main(["refine", "task4", "--refined", str(out)]) == 1
    captured = capsys.readouterr()
    assert "the original program does not meet the goal on the plant" in captured.err
    assert "folding_chair.hinge = 0.200 < 0.35" in captured.err
    assert "NOT refined" in captured.out
    assert not out.exists()  # no accepted program: nothing written
    assert tamp_main(["refine", "task4", "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    assert doc["goal_met"] is False and doc["refined_program"] is None
    assert [p["name"] for p in doc["phases"]] == ["original"]


def test_a_harmful_rate_is_backed_off_and_the_last_accepted_program_written(
    tmp_path, capsys, monkeypatch
):
    import tamp.sim.refine.simulate as workcell

    def too_fast(p):
        return any((b.rate_hz or 10.0) > 21.0 for _, _, b in p.behaviors())

    monkeypatch.setattr(workcell, "simulate", _fake_simulate(too_fast))
    out = tmp_path / "refined.yaml"
    assert tamp_main(["refine", "task4", "--json", "--refined", str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["rates_tried"] == [23.0, 22.0, 21.0] and doc["rate_hz"] == 21.0
    rate = [a for a in doc["attempts"] if a["phase"] == "rate-refined"]
    assert [a["accepted"] for a in rate] == [False, False, True]
    assert rate[0]["rejected"].startswith("goal not met")
    assert all(b.rate_hz == 21.0 for _, _, b in load_program(out).behaviors())
    assert doc["goal_met"] is True
    assert tamp_main(["refine", "task4"]) == 0
    text = capsys.readouterr().out
    assert "rate-refined    23 Hz per behavior (7 behaviors), base speed scaled" in text
    assert "NOT accepted: goal not met" in text
