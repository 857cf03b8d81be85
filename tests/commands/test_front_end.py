"""The front end shared by every command: --version, JSON errors, packaged names, RG once."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tamp.commands.main import main as tamp_main
from tamp.commands.verify import main as verify_main
from tamp.demo import load_demonstration
from tamp.lots.task import load_events, load_task
from tamp.scenarios import resolve


@pytest.mark.parametrize("entry,prog", [(tamp_main, "tamp"), (verify_main, "tamp-verify")])
def test_version(entry, prog, capsys):
    assert entry(["--version"]) == 0
    out = capsys.readouterr().out.strip()
    assert out.startswith(prog + " ") and out.split()[1][0].isdigit()


def test_errors_are_json_under_json(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\narea_radius: -1\n")
    assert tamp_main(["plan", str(bad), "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["exit"] == 2 and doc["file"] == str(bad) and doc["field"]
    assert tamp_main(["plan", "case2.yaml", "--json", "--cost", "nonsense"]) == 2
    assert json.loads(capsys.readouterr().out)["exit"] == 2
    assert verify_main(["trace", "--formula", "G (", "--word", "a; cycle{a}", "--json"]) == 2
    assert json.loads(capsys.readouterr().out)["field"] == "--formula"


def test_without_json_errors_are_one_stderr_line(capsys):
    assert tamp_main(["plan", "no_such_file.yaml"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1 and "no_such_file.yaml" in captured.err


def test_packaged_names_resolve_from_any_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert load_demonstration("case3.yaml").goal_ids == ["G0", "G1"]
    task = load_task("tower.yaml")
    assert load_events("tower_interference.yaml", task)
    assert resolve("tower", "lots").name == "tower.yaml"
    assert resolve("no_such.yaml") == type(resolve("x"))("no_such.yaml")
    proc = subprocess.run(
        [sys.executable, "-m", "tamp.commands.main", "lots", "tower.yaml", "--json"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["satisfied"] is True


def test_case3_demonstration_carries_its_obstacle():
    demo = load_demonstration("case3.yaml")
    assert [str(a) for a in demo.appear] == ["Oa@L1"]


def test_rg_is_enumerated_once_per_plan(monkeypatch, tmp_path, capsys):
    from tamp.rg import graph

    built = []
    original = graph.ReachabilityGraph._to_networkx
    monkeypatch.setattr(
        graph.ReachabilityGraph,
        "_to_networkx",
        lambda self: built.append(1) or original(self),
    )
    enumerated = []
    original_masks = graph._masks
    monkeypatch.setattr(graph, "_masks", lambda *a: enumerated.append(1) or original_masks(*a))
    assert tamp_main(["plan", "case2.yaml", "--dot", str(tmp_path / "rg.dot")]) == 0
    assert (len(enumerated), len(built)) == (1, 1)  # stats, gate and DOT share one RG
    assert "7 states" in capsys.readouterr().out


def test_no_verify_warns(capsys):
    assert tamp_main(["plan", "case1.yaml", "--no-verify"]) == 0
    err = capsys.readouterr().err
    assert "warning: --no-verify" in err


def test_diagnostics_go_through_logging(capsys, caplog, monkeypatch):
    import logging

    from tamp.commands.output import progress

    caplog.set_level(logging.DEBUG, logger="tamp")
    # the CLI's "tamp" logger does not propagate to the root (where caplog listens)
    monkeypatch.setattr(logging.getLogger("tamp"), "propagate", True)
    progress("working")
    progress("quiet one", quiet=True)
    names = [(r.name, r.levelno, r.getMessage()) for r in caplog.records]
    assert ("tamp", logging.INFO, "working") in names
    assert ("tamp", logging.DEBUG, "quiet one") in names
    monkeypatch.setenv("TAMP_LOG", "no-such-level")
    assert tamp_main(["plan", "case1.yaml", "--no-verify"]) == 0  # a warning, no traceback
