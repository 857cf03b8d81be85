"""Refining from a measured log (`tamp.refine.predict`): the same steps on the logged
durations, every phase a prediction; the log formats and their errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tamp.commands.main import main as tamp_main
from tamp.errors import InputError
from tamp.refine.architecture import default_architecture
from tamp.refine.predict import load_log, predicted_timeline, predicting
from tamp.refine.refinement import refine
from tamp.verification.gate import gate_program
from tamp.verification.refine import check_run
from tests.refine.helpers import task

ROWS = [
    ("R1.lower_arm", 0.0, 53.3),
    ("R1.approach", 53.3, 119.7),
    ("R1.pull_out", 119.7, 148.5),
    ("R1.raise_arm", 148.5, 151.9),
    ("R2.approach", 0.0, 28.0),
    ("R2.grip", 28.0, 61.3),
    ("R2.release", 148.5, 151.0),
]


def csv_log(tmp_path, rows=ROWS):
    p = tmp_path / "run.csv"
    p.write_text("event,start,end\n" + "".join(f"{e},{s},{t}\n" for e, s, t in rows))
    return p


def test_the_log_of_the_program_as_given_predicts_itself(tmp_path):
    log = load_log(csv_log(tmp_path), task(4))
    timeline = predicted_timeline(task(4), task(4), log)
    for e, s, t in ROWS:
        assert (timeline.record(e).start, timeline.record(e).end) == pytest.approx((s, t))
    assert timeline.task_time == pytest.approx(151.9)


def test_the_phases_predicted_from_a_log():
    """Step 2 runs R1's lowering (53.3 s) with its approach (66.4 s): the approach ends at
    66.4 s, the pull-out starts then (R2 gripped at 61.3 s): 66.4 + 28.8 + 3.4 = 98.6 s.
    The speed change ends the approach with the lowering (53.3 s), where R1 waits for the
    grip: 93.5 s. At 23 Hz (the queue model's rate: the log has none) the bases are 2.3
    times faster."""
    program = task(4)
    from tamp.refine.predict import Log

    log = Log({e: (s, t) for e, s, t in ROWS})
    out = refine(
        program,
        default_architecture(),
        predicting(program, log),
        gate=gate_program,
        check_run=check_run,
    )
    times = [round(p.task_time, 1) for p in out.phases]
    assert times[:3] == [151.9, 98.6, 93.5]
    # one search per behavior (its trigger sensor, its command load): all 23 Hz here, every
    # sensor at 200 Hz and every command of one load
    assert out.rates_found == {e: 23.0 for e in program.events()}
    assert out.rate_source == "queue model" and out.tuning is None
    # R2: approach 28.0 / 2.3, grip 33.3 (gripper, not scaled): 45.5 s; R1's approach keeps
    # its speed (it runs with the lowering, which the rate does not speed up): 53.3 s; the
    # pull-out then, 28.8 / 2.3, the lift 3.4 s after it
    assert out.phases[3].task_time == pytest.approx(53.3 + 28.8 / 2.3 + 3.4, abs=0.05)


def test_a_tamp_refine_json_document_is_a_log(tmp_path):
    doc = {
        "phases": [{"timeline": [{"event": e, "start": s, "end": t} for e, s, t in ROWS]}],
        "rates_found": {"R1.imu": 20.0},
        "manipulation_starts": [
            {"robot": "R1", "touch": [110.0, "folding_chair.latch_plate"]},
            {"robot": "R2", "touch": None},
        ],
    }
    p = tmp_path / "refine.json"
    p.write_text(json.dumps(doc))
    log = load_log(p, task(4))
    assert log.rates == {"R1.imu": 20.0}
    assert log.touches == {"R1": (110.0, "folding_chair.latch_plate")}
    assert log.spans["R2.grip"] == (28.0, 61.3)


@pytest.mark.parametrize(
    "rows,field,message",
    [
        (ROWS[:-1], "row 7", "no row for R2.release"),
        ([*ROWS[:-1], ("R2.release", 5.0, 4.0)], "row 8", "ends (4) before it starts (5)"),
        ([*ROWS[:-1], ("R2.release", "x", 4.0)], "row 8.start", "expected a number"),
    ],
)
def test_bad_logs_name_the_file_and_row(tmp_path, rows, field, message):
    with pytest.raises(InputError) as e:
        load_log(csv_log(tmp_path, rows), task(4))
    assert e.value.field == field and message in str(e.value)


def test_cli_from_log_predicts_and_bad_logs_exit_2(tmp_path, capsys):
    pytest.importorskip("pydrake", reason="tamp refine loads its scene through the sim extra")
    log = csv_log(tmp_path)
    assert tamp_main(["refine", "task4", "--from-log", str(log), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["predicted_from"] == str(log)
    assert [round(p["task_time"], 1) for p in doc["phases"]][:3] == [151.9, 98.6, 93.5]
    assert tamp_main(["refine", "task4", "--from-log", str(log)]) == 0
    assert "predicted from" in capsys.readouterr().out
    assert tamp_main(["refine", "task4", "--from-log", str(tmp_path / "none.csv")]) == 2
    bad = csv_log(tmp_path, ROWS[:-1])
    assert tamp_main(["refine", "task4", "--from-log", str(bad)]) == 2
    assert "no row for R2.release" in capsys.readouterr().err
    plot, log = tmp_path / "fig" / "phases.svg", csv_log(tmp_path)  # the good log again
    assert tamp_main(["refine", "task4", "--from-log", str(log), "--plot", str(plot)]) == 0
    assert plot.read_text().lstrip().startswith("<?xml") and "predicted" in plot.read_text()
    dot, timeline = tmp_path / "d" / "station.dot", tmp_path / "t" / "phases.png"
    args = ["--diagram", str(dot), "--timeline", str(timeline)]
    assert tamp_main(["refine", "task4", "--from-log", str(log), *args]) == 0
    assert dot.read_text().startswith("digraph") and "MultibodyPlant" in dot.read_text()
    assert timeline.read_bytes().startswith(b"\x89PNG")
    assert tamp_main(["refine", "task4", "--from-log", str(log), "--timeline", "t.txt"]) == 2
    capsys.readouterr()
    rec = str(tmp_path / "r.html")
    assert tamp_main(["refine", "task4", "--from-log", str(log), "--record", rec]) == 2
    assert tamp_main(["refine", "task4", "--from-log", str(log), "--tune-online"]) == 2


RESULT = Path(__file__).resolve().parents[2] / "benchmarks/results/refine_task4.json"


def test_the_log_of_the_simulated_task4_predicts_its_simulated_phases():
    """``tamp refine task4 --json`` (committed in benchmarks/results/refine_task4.json) is a
    log: refined from it without simulating, every phase lands within 2 % of the
    simulated one (the prediction knows the durations, not the physics)."""
    doc = json.loads(RESULT.read_text())
    program = task(4)
    out = refine(
        program,
        default_architecture(),
        predicting(program, load_log(RESULT, program)),
        gate=gate_program,
        check_run=check_run,
    )
    simulated = {p["name"]: p["task_time"] for p in doc["phases"]}
    for p in out.phases:
        assert p.task_time == pytest.approx(simulated[p.name], rel=0.02), p.name
    assert [c.describe() for c in out.parallelized] == doc["parallelized"]
