"""`tamp simulate smp-mro`: JSON output with sim times and plant poses, Meshcat recording."""

from __future__ import annotations

import json

import pytest

from tamp.commands.main import main

from .helpers import write_one_bottle


@pytest.mark.slow
def test_json_output_and_recording(tmp_path, capsys):
    path = write_one_bottle(tmp_path)
    html = tmp_path / "out" / "run.html"
    code = main(["simulate", "smp-mro", str(path), "--record", str(html), "--json"])
    out = capsys.readouterr().out
    assert code == 0, out
    data = json.loads(out)
    assert data["ok"] and data["status"] == "SUCCESS"
    assert data["order"] == ["G0"]
    assert data["verified"] == {"order": True, "tree": True}
    done = [a for a in data["actions"] if a["status"] == "SUCCESS"]
    assert [a["action"] for a in done][-2:] == ["Pick(O0)", "Place(O0, L0)"]
    for a in data["actions"]:
        assert a["end"] >= a["start"]
    starts = [a["start"] for a in data["actions"]]
    assert starts == sorted(starts)
    pose = data["final_poses"]["O0"]
    assert abs(pose["x"] - 1.0) < 0.15 and abs(pose["y"] - 0.7) < 0.15
    assert data["sim_time"] >= done[-1]["end"]
    assert data["realtime_factor"] > 0 and data["wall_time"] > 0
    text = html.read_text()
    assert data["recording"] == str(html)
    assert "<html" in text.lower() and "meshcat" in text.lower()
    assert len(text) > 100_000  # the animation is embedded, not linked


@pytest.mark.slow
def test_human_readable_output(tmp_path, capsys):
    path = write_one_bottle(tmp_path)
    code = main(["simulate", "smp-mro", str(path), "--no-verify"])
    out = capsys.readouterr().out
    assert code == 0
    assert "Place(O0, L0)" in out and "real-time factor" in out
    assert "O0@L0: inside" in out
    # the MoveTo the tree halted once the robot was close is reported as done, not cancelled
    assert "MoveTo(O0)" in out and "done (halted)" in out and "CANCELLED" not in out
    assert out.rstrip().splitlines()[-1].startswith("SUCCESS: ") and "warning" not in out


def test_bad_options_exit_2_before_simulating(tmp_path, capsys):
    """Checked before Drake builds anything: a time limit <= 0 used to give a TIMEOUT (exit
    1), a directory as the recording an internal error after the whole run."""
    path = write_one_bottle(tmp_path)
    for argv, option in (
        (["--max-sim-time", "0"], "--max-sim-time"),
        (["--max-sim-time", "nan"], "--max-sim-time"),
        (["--rate", "-1"], "--rate"),
        (["--record", str(tmp_path)], "--record"),
    ):
        code = main(["simulate", "smp-mro", str(path), *argv])
        err = capsys.readouterr().err
        assert code == 2 and option in err and "internal error" not in err, (argv, err)
