"""`tamp-verify`: exit codes 0 holds / 1 violated / 2 bad input, text and JSON output."""

from __future__ import annotations

import json

import pytest

from tamp.commands.verify import main
from tamp.scenarios import path


def run(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def test_trace_word_holds_and_violated(capsys) -> None:
    rc, out, _ = run(capsys, "trace", "--formula", "GF p1 & GF p2", "--word", "p1; cycle{p1; p2}")
    assert rc == 0 and "holds" in out
    rc, out, _ = run(capsys, "trace", "--formula", "GF p1 & GF p2", "--word", "p1; cycle{p1}")
    assert rc == 1 and "counterexample" in out and "accepted:" in out


def test_trace_json_document(capsys) -> None:
    rc, out, _ = run(
        capsys, "trace", "--formula", "G !bad", "--word", "a; bad; a", "--finite", "--json"
    )
    assert rc == 1
    doc = json.loads(out)
    assert doc["holds"] is False
    assert isinstance(doc["states_explored"], int) and doc["states_explored"] > 0
    ce = doc["counterexample"]
    assert ce["position"] == 1
    assert ce["word"]["trace"] == [["a"], ["bad"], ["a"]]
    assert ["bad"] not in ce["accepting_word"]["trace"]
    rc, out, _ = run(capsys, "trace", "--formula", "G !bad", "--word", "a; a", "--finite", "--json")
    doc = json.loads(out)
    assert rc == 0 and doc["holds"] is True and doc["counterexample"] is None
    assert doc["checks"][0]["semantics"] == "finite"


def test_trace_file(capsys, tmp_path) -> None:
    f = tmp_path / "t.yaml"
    f.write_text("version: 1\ntrace: [[p1], [p2], [p3]]\n")
    rc, _, _ = run(
        capsys, "trace", "--formula", "F(p1 & F(p2 & F p3))", "--trace", str(f), "--finite"
    )
    assert rc == 0
    f.write_text("version: 1\ntrace: [[p2], [p1], [p3]]\ncycle: [[]]\n")
    rc, _, _ = run(capsys, "trace", "--formula", "F(p1 & F(p2 & F p3))", "--trace", str(f))
    assert rc == 1


@pytest.mark.parametrize(
    "argv",
    [
        ["trace", "--formula", "G (a &", "--word", "a; cycle{a}"],  # formula does not parse
        ["trace", "--formula", "G a", "--word", "a | b; cycle{a}"],  # letter does not parse
        ["trace", "--formula", "G a", "--word", "a"],  # finite word, infinite semantics
        ["trace", "--formula", "G a", "--word", "cycle{a}", "--finite"],
        ["trace", "--formula", "G a"],  # no trace at all
        ["plan", str(path("case2.yaml")), "--order", "G0,G9"],
        ["bt", str(path("case2.yaml")), "--property", "G !nonsense"],
        ["bt", str(path("case3.yaml")), "--appear", "Oa@nowhere"],
        ["lots", str(path("lots/tower_interference.yaml"))],  # an events file
    ],
)
def test_bad_input_exits_2(capsys, argv) -> None:
    rc, out, err = run(capsys, *argv)
    assert rc == 2
    assert "Traceback" not in err


def test_malformed_trace_file_exits_2(capsys, tmp_path) -> None:
    f = tmp_path / "bad.yaml"
    f.write_text("version: 1\ntrace: [[p1], 7]\n")
    rc, _, err = run(capsys, "trace", "--formula", "G p1", "--trace", str(f), "--finite")
    assert rc == 2 and "trace[1]" in err
    f.write_text("trace: [")
    rc, _, err = run(capsys, "trace", "--formula", "G p1", "--trace", str(f), "--finite")
    assert rc == 2 and "YAML" in err


def test_plan_default_and_corrupted_order(capsys) -> None:
    demo = str(path("case2.yaml"))
    rc, out, _ = run(capsys, "plan", demo, "--json")
    doc = json.loads(out)
    assert rc == 0 and doc["holds"] and len(doc["checks"]) == 2
    rc, out, _ = run(capsys, "plan", demo, "--order", "G2,G3,G0,G1", "--json")
    doc = json.loads(out)
    assert rc == 1 and doc["counterexample"]["position"] == 1


def test_bt_and_lots_commands(capsys) -> None:
    rc, out, _ = run(
        capsys,
        "bt",
        str(path("case3.yaml")),
        "--appear",
        "Oa@L1",
        "--max-failures",
        "0",
        "--property",
        'G !"IsGraspedObject(Oa)"',
        "--json",
    )
    doc = json.loads(out)
    assert rc == 1 and doc["states_explored"] > 10
    assert any("Pick(Oa)" in s for s in doc["counterexample"]["steps"])
    rc, out, _ = run(capsys, "bt", str(path("case1.yaml")), "--max-failures", "0")
    assert rc == 0 and out.count("holds") == 3
    rc, out, _ = run(capsys, "lots", str(path("lots/tower.yaml")), "--json")
    assert rc == 0 and json.loads(out)["holds"]


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["--order", ","], "--order"),
        (["--max-states", "0"], "--max-states"),
        (["--max-failures", "-1"], "--max-failures"),
    ],
)
def test_bt_bad_numbers_and_empty_order_exit_2(capsys, argv, option) -> None:
    rc, out, err = run(capsys, "bt", str(path("case1.yaml")), *argv)
    assert rc == 2 and out == "" and option in err and "internal error" not in err


def test_plan_empty_order_exits_2(capsys) -> None:
    rc, out, err = run(capsys, "plan", str(path("case1.yaml")), "--order", " , ")
    assert rc == 2 and "--order" in err


def test_bounded_bt_exploration_reports_no_spurious_violation(capsys) -> None:
    """At the bound the unexpanded states used to stutter forever, so `F goal` was reported
    VIOLATED by a path that merely stops where the exploration stopped. Now such
    a property is "unknown" (exit 4), never "holds"."""
    rc, out, _ = run(capsys, "bt", str(path("case1.yaml")), "--max-states", "5", "--json")
    doc = json.loads(out)
    assert rc == 4, out
    assert len(doc["checks"]) == 3
    for v in doc["checks"]:
        assert "BOUNDED" in v["subject"]
        assert v["status"] == "unknown" and v["counterexample"] is None
    # a bad prefix inside the explored states is still a violation at the bound
    rc, out, _ = run(
        capsys, "bt", str(path("case1.yaml")), "--max-states", "5", "--property", "G goal"
    )
    assert rc == 1 and "no continuation can satisfy" in out


def test_property_naming_an_unknown_object_or_area_is_bad_input(capsys):
    from tamp.commands.verify import main

    assert main(["bt", "case3.yaml", "--property", 'G !"IsObjectAt(O7, L1)"']) == 2
    assert "unknown object or area 'O7'" in capsys.readouterr().err
    assert main(["bt", "case3.yaml", "--property", "G (objects_in_L9 <= 1)"]) == 2
    assert "unknown area 'L9'" in capsys.readouterr().err
    # an object that only appears during the run is known
    assert main(["bt", "case3.yaml", "--property", 'F "IsObjectAt(Oa, free1)"']) == 0


def test_bounded_exploration_is_unknown_not_holds(capsys):
    import json

    from tamp.commands.verify import main
    from tamp.errors import EXIT_UNKNOWN

    assert main(["bt", "case3.yaml", "--max-states", "20", "--json"]) == EXIT_UNKNOWN
    doc = json.loads(capsys.readouterr().out)
    assert doc["status"] == "unknown" and doc["holds"] is False
    assert {c["status"] for c in doc["checks"]} == {"unknown"}
    assert "bounded at 20 states" in doc["notes"][0]
    # a real violation found within the bound is still a violation (exit 1)
    assert main(["bt", "case3.yaml", "--max-states", "60", "--property", "G !holding"]) == 1


def test_every_tree_state_budget_has_the_gates_default(capsys):
    """`tamp-verify bt --max-states`, `tamp plan --execute --verify-budget` and `tamp simulate
    smp-mro --verify-budget` bound one exploration: their help names its one default."""
    from tamp.commands.main import main as tamp
    from tamp.verification.bt import DEFAULT_MAX_STATES

    helps = []
    for entry, argv in (
        (main, ["bt", "-h"]),
        (tamp, ["plan", "-h"]),
        (tamp, ["simulate", "smp-mro", "-h"]),
    ):
        try:
            entry(argv)
        except SystemExit:
            pass
        helps.append(" ".join(capsys.readouterr().out.split()))
    for text in helps:
        assert f"(default {DEFAULT_MAX_STATES}" in text


def test_svg_draws_the_counterexample_on_its_automaton(capsys, tmp_path) -> None:
    """``--svg``: the trace's walk over the automaton, the step that kills every accepting
    continuation in red; the format follows the suffix."""
    svg, dot = tmp_path / "cex.svg", tmp_path / "cex.dot"
    argv = ("trace", "--formula", "G !bad", "--word", "a; bad; a", "--finite")
    rc, _, _ = run(capsys, *argv, "--svg", str(svg))
    assert rc == 1
    text = svg.read_text()
    assert "<svg" in text and "#d62728" in text and "no accepting" in text
    rc, _, _ = run(capsys, *argv, "--svg", str(dot))
    assert rc == 1 and dot.read_text().startswith("digraph trace")


def test_svg_of_a_violated_plan_and_a_wrong_suffix(capsys, tmp_path) -> None:
    out = tmp_path / "order.svg"
    rc, _, _ = run(capsys, "plan", "case2.yaml", "--order", "G2,G3,G0,G1", "--svg", str(out))
    assert rc == 1 and "<svg" in out.read_text()
    rc, _, err = run(capsys, "plan", "case2.yaml", "--svg", str(tmp_path / "order.txt"))
    assert rc == 2 and "--svg" in err and "suffix" in err
    assert not (tmp_path / "order.txt").exists()
