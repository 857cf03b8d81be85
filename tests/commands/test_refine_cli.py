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
    code = tamp_main(["refine", str(SHORT), "--json", "--gantt", str(gantt), "--out", str(out)])
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
