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


# -- hostile inputs: long demonstrations, domains that cannot achieve the goals ---------------


@pytest.mark.parametrize("steps", [300, pytest.param(5000, marks=pytest.mark.slow)])
def test_a_long_chain_of_one_object_plans_and_verifies(capsys, tmp_path, steps) -> None:
    """N steps of one object: N goals and N-1 constraints used to be refused by the gate's
    automaton size guard as bad input (exit 2); the encoding is checked directly now."""
    from tamp.demo import load_demonstration
    from tamp.rg import plan
    from tamp.verification.gate import gate_order
    from tests.demo.generate import write_demo

    demo_file = write_demo(tmp_path / f"chain{steps}.yaml", steps, "one")
    code, out, err = _run(capsys, "plan", str(demo_file), "--json")
    assert code == 0, err
    assert "warning" not in err and len(json.loads(out)["order"]) == steps
    report = gate_order(plan(load_demonstration(str(demo_file))))
    assert report.holds and [v.subject.split(" ")[0] for v in report.verdicts] == ["order", "RG"]
    assert report.verdicts[1].states_explored == steps + 1


def _demo_with_domain(tmp_path, actions: str):
    from tamp.scenarios import path

    (tmp_path / "domain.yaml").write_text(f"version: 1\nrobot: youbot\nactions:\n{actions}")
    text = path("case1.yaml").read_text()
    text = text.replace("  start: [0, 0, 0]", "  start: [0, 0, 0]\n  domain: domain.yaml")
    demo = tmp_path / "demo.yaml"
    demo.write_text(text)
    return str(demo)


MOVE = """  - {name: MoveTo, params: {target: place}, eff: ["IsRobotCloseTo(target)"]}\n"""
PICK = """  - name: Pick
    params: {o: object}
    con: ["IsHandFree()", "IsRobotCloseTo(o)"]
    eff: ["IsGraspedObject(o)"]\n"""
PLACE = """  - name: Place
    params: {o: object, l: area}
    con: ["IsGraspedObject(o)", "IsRobotCloseTo(l)", "IsAreaFree(l)"]
    eff: ["IsHandFree()", "IsObjectAt(o, l)"]\n"""


@pytest.mark.parametrize("execute", [[], ["--execute"]])
def test_a_domain_without_place_is_infeasible_for_that_reason(capsys, tmp_path, execute) -> None:
    """Used to exit 1 from the tree gate with an LTL counterexample ("violates F goal …");
    the cause a user needs is that no action template achieves IsObjectAt(O, L)."""
    demo = _demo_with_domain(tmp_path, MOVE + PICK)
    code, out, err = _run(capsys, "plan", demo, *execute)
    assert code == 1 and out == ""
    assert "IsObjectAt(O2, L2)" in err and "has IsObjectAt among its effects" in err
    assert "(templates: MoveTo, Pick)" in err
    assert "counterexample" not in err and "F goal" not in err and "Fgoal" not in err


def test_a_domain_whose_place_can_never_run_is_infeasible(capsys, tmp_path) -> None:
    demo = _demo_with_domain(tmp_path, MOVE + PLACE)
    code, _, err = _run(capsys, "plan", demo)
    assert code == 1
    assert "Place needs IsGraspedObject(o)" in err and "counterexample" not in err


def test_a_complete_custom_domain_still_plans(capsys, tmp_path) -> None:
    demo = _demo_with_domain(tmp_path, MOVE + PICK + PLACE)
    code, out, _ = _run(capsys, "plan", demo)
    assert code == 0 and "G2 -> G1 -> G0" in out


@pytest.mark.parametrize("budget", ["0", "-3"])
def test_a_verify_budget_below_one_is_bad_input(capsys, budget) -> None:
    code, out, err = _run(capsys, "plan", "case1.yaml", "--execute", "--verify-budget", budget)
    assert code == 2 and out == "" and "--verify-budget" in err and "must be >= 1" in err


def test_a_tree_beyond_the_verify_budget_is_unknown_exit_1(capsys) -> None:
    """The gate neither passes nor calls unsafe a tree it could not cover: it names the
    budget and how to raise it, once."""
    code, out, err = _run(capsys, "plan", "case1.yaml", "--execute", "--verify-budget", "5")
    assert code == 1 and out == ""
    assert "verification unknown" in err and "budget of 5 states" in err
    assert "raise it with --verify-budget N" in err and err.count("verification unknown") == 1


def test_dot_format_follows_the_suffix(capsys, tmp_path):
    """``--dot rg.svg`` is an SVG picture (rendered by Graphviz), ``rg.dot`` the DOT text,
    any other suffix bad input naming the flag, refused before planning."""
    svg, png, dot = tmp_path / "rg.svg", tmp_path / "rg.png", tmp_path / "rg.dot"
    for path in (svg, png, dot):
        code, _, _ = _run(capsys, "plan", "case2.yaml", "--dot", str(path))
        assert code == 0
    assert "<svg" in svg.read_text()
    assert png.read_bytes().startswith(b"\x89PNG")
    assert dot.read_text().lstrip().startswith(("digraph", "strict digraph"))
    code, _, err = _run(capsys, "plan", "case2.yaml", "--dot", str(tmp_path / "rg.jpg"))
    assert code == 2 and "--dot" in err and ".jpg" in err
    code, _, err = _run(capsys, "plan", "case2.yaml", "--execute", "--bt-dot", "bt.txt")
    assert code == 2 and "--bt-dot" in err
