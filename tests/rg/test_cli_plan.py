"""`tamp plan` end to end: JSON contract, DOT output that Graphviz renders, exit codes."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest

from tamp.commands.main import main


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_plan_json_contract_case2(capsys) -> None:
    code, out, _ = _run(capsys, "plan", "case2.yaml", "--json")
    assert code == 0
    data = json.loads(out)
    assert {"goals", "initial", "constraints", "rg", "order", "cost"} <= set(data)
    assert data["order"] == ["G1", "G0", "G3", "G2"]
    assert sorted(map(tuple, data["constraints"])) == [
        ("G0", "G2"),
        ("G0", "G3"),
        ("G1", "G2"),
        ("G1", "G3"),
    ]
    assert data["rg"] == {"states": 7, "edges": 8, "alg1_nodes": 13}
    g2 = next(g for g in data["goals"] if g["id"] == "G2")
    assert g2["object"] == "O0" and g2["position"] == pytest.approx([1.0, 1.0, 0.0])
    assert data["initial"]["O1"] == pytest.approx([1.0, 1.0, 0.0])
    assert data["cost"] > 0


def test_plan_human_output_lists_order_and_constraints(capsys) -> None:
    code, out, _ = _run(capsys, "plan", "case1.yaml", "--cost", "time")
    assert code == 0
    assert "G2 -> G1 -> G0" in out and "8 states" in out


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz not installed")
def test_dot_renders_with_graphviz(capsys, tmp_path) -> None:
    dot_file = tmp_path / "rg.dot"
    code, _, _ = _run(capsys, "plan", "case2.yaml", "--dot", str(dot_file))
    assert code == 0
    text = dot_file.read_text()
    assert text.count("->") == 8 and "firebrick" in text
    png = tmp_path / "rg.png"
    subprocess.run(["dot", "-Tpng", str(dot_file), "-o", str(png)], check=True)
    assert png.stat().st_size > 1000


def test_bad_input_exits_2_naming_file_and_field(capsys, tmp_path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nframe: {robot_position: [0, 0]}\narea_radius: 0.1\n")
    code, out, err = _run(capsys, "plan", str(bad))
    assert code == 2 and out == ""
    assert str(bad) in err and "frame.robot_position" in err and "Traceback" not in err


def test_missing_file_and_unknown_option_exit_2(capsys) -> None:
    assert _run(capsys, "plan", "/nonexistent/demo.yaml")[0] == 2
    assert _run(capsys, "plan", "case1.yaml", "--cost", "fastest")[0] == 2


def test_console_script_exit_status() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "tamp.commands.main", "plan", "case1.yaml", "--json"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["order"] == ["G2", "G1", "G0"]


def test_unwritable_outputs_exit_2_before_planning(capsys, tmp_path) -> None:
    """A directory or a missing directory as an output file is bad input, not exit 3."""
    for argv in (
        ["--dot", str(tmp_path)],
        ["--dot", str(tmp_path / "missing" / "rg.dot")],
        ["--execute", "--bt-xml", str(tmp_path)],
        ["--execute", "--bt-dot", str(tmp_path / "missing" / "bt.dot")],
    ):
        code, out, err = _run(capsys, "plan", "case1.yaml", *argv)
        assert code == 2 and out == "", argv
        assert argv[-2] in err and "internal error" not in err, err
    assert list(tmp_path.iterdir()) == []


def test_tree_exports_need_execute(capsys, tmp_path) -> None:
    """--bt-xml/--bt-dot without --execute used to be ignored silently (no file written)."""
    code, _, err = _run(capsys, "plan", "case1.yaml", "--bt-xml", str(tmp_path / "t.xml"))
    assert code == 2 and "--bt-xml" in err and "--execute" in err
    assert not (tmp_path / "t.xml").exists()
