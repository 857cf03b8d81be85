"""`tamp lots`: JSON fields, DOT output, exit codes 0 / 1 / 2."""

from __future__ import annotations

import json

import pytest

from tamp.commands.main import main

from .helpers import scenario


def run_json(capsys, *argv):
    code = main(["lots", *argv, "--json"])
    out = capsys.readouterr().out
    return code, json.loads(out) if out.strip() else None


def test_json_has_the_promised_fields(capsys, tmp_path):
    dot = tmp_path / "aut.dot"
    code, data = run_json(
        capsys,
        str(scenario("tower.yaml")),
        "--interference",
        str(scenario("tower_interference.yaml")),
        "--dot",
        str(dot),
    )
    assert code == 0
    assert data["automaton"]["states"] == 4 and len(data["automaton"]["edges"]) == 10
    assert data["w_b_states"] == 8
    assert [a["kind"] for a in data["actions"]] == [
        "move",
        "discard_held",
        "return_held",
        "move",
        "move",
        "move",
    ]
    assert data["replans"] == 0
    assert data["final"]["B"] == {"body": 1, "bottom": 1, "peak": 1}
    assert data["final"]["A"] == {"toy_car": 1}
    assert data["satisfied"] is True
    assert data["plan"]["prefix"][:3] == [["p1"], ["p2"], ["p3"]]
    assert dot.read_text().startswith("digraph automaton")


def test_packaged_names_resolve(capsys):
    code, data = run_json(capsys, "example1.yaml", "--interference", "example1_interference.yaml")
    assert code == 0 and data["replans"] == 1 and data["w_b_states"] == 12


def test_human_readable_output(capsys):
    assert main(["lots", "model_building.yaml", "--interference", "model_building_fig8.yaml"]) == 0
    out = capsys.readouterr().out
    assert "drop held scissors into the waste basket" in out
    assert "W^B states (Lemma 1): 8" in out


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def test_infeasible_exits_1_with_the_reason(capsys, tmp_path):
    ev = write(
        tmp_path,
        "ev.yaml",
        "version: 1\nevents:\n  - {after: 0, kind: remove, class: hammer, side: A}\n",
    )
    code = main(["lots", "model_building.yaml", "--interference", ev, "--json"])
    captured = capsys.readouterr()
    assert code == 1
    assert json.loads(captured.out)["satisfied"] is False
    assert "no hammer left" in captured.err


TASK = """version: 1
formula: "F(p1 & F p2)"
propositions:
  p1: {class: cup}
  p2: {class: plate}
initial:
  A: {cup: 1, plate: 1}
"""


@pytest.mark.parametrize(
    "task, where",
    [
        (TASK.replace("F p2", "F p3"), "formula"),
        (TASK.replace('"F(p1 & F p2)"', '"F(p1 & "'), "formula"),
        (TASK.replace("cup: 1,", "cup: -1,"), "initial.A.cup"),
        (TASK.replace("cup: 1,", "cup: one,"), "initial.A.cup"),
        (TASK + "colour: red\n", "colour"),
        (TASK.replace("version: 1", "version: 2"), "version"),
        (TASK.replace("  p2: {class: plate}\n", "  p2: {klass: plate}\n"), "propositions.p2"),
        (TASK.replace('formula: "F(p1 & F p2)"\n', ""), "formula"),
    ],
)
def test_bad_task_exits_2_naming_the_field(capsys, tmp_path, task, where):
    code = main(["lots", write(tmp_path, "task.yaml", task)])
    err = capsys.readouterr().err
    assert code == 2
    assert "task.yaml" in err and where in err


@pytest.mark.parametrize(
    "events, where",
    [
        ("  - {after: -1, kind: add, class: cup, side: A}\n", "events[0].after"),
        ("  - {after: 0, kind: teleport, class: cup, side: A}\n", "events[0].kind"),
        ("  - {after: 0, kind: move, class: cup, from: A, to: A}\n", "events[0].to"),
        ("  - {after: 0, kind: move, class: spoon, from: A, to: B}\n", "events[0].class"),
        ("  - {after: 0, kind: add, class: cup, side: C}\n", "events[0].side"),
        ("  - {after: 0, kind: remove, class: cup, side: B}\n", "events[0]"),  # none there
        ("  - {after: 0, kind: add, class: cup, side: A, when: now}\n", "events[0].when"),
    ],
)
def test_bad_interference_exits_2(capsys, tmp_path, events, where):
    task = write(tmp_path, "task.yaml", TASK)
    ev = write(tmp_path, "ev.yaml", "version: 1\nevents:\n" + events)
    code = main(["lots", task, "--interference", ev])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "ev.yaml" in err and where in err


def test_formula_without_executable_run_is_infeasible(capsys, tmp_path):
    task = write(tmp_path, "task.yaml", TASK.replace("plate: 1", "plate: 0"))
    assert main(["lots", task]) == 1
    assert "no accepting run" in capsys.readouterr().err


@pytest.mark.parametrize("seed", ["0", "5"])
def test_random_tree_variant_gives_the_same_run(capsys, seed):
    argv = ["example1.yaml", "--interference", "example1_interference.yaml"]
    _, bfs = run_json(capsys, *argv)
    code, rnd = run_json(capsys, *argv, "--tree", "random", "--seed", seed)
    assert code == 0 and rnd["satisfied"]
    assert [a["text"] for a in rnd["actions"]] == [a["text"] for a in bfs["actions"]]


def test_max_waits_must_be_positive(capsys):
    assert main(["lots", "tower.yaml", "--max-waits", "0"]) == 2
    assert "--max-waits" in capsys.readouterr().err


def test_unwritable_dot_exits_2(capsys, tmp_path):
    for target in (tmp_path, tmp_path / "missing" / "a.dot"):
        assert main(["lots", "tower.yaml", "--dot", str(target)]) == 2
        err = capsys.readouterr().err
        assert "--dot" in err and "internal error" not in err


def test_dot_draws_the_automaton_in_the_format_of_its_suffix(capsys, tmp_path):
    svg = tmp_path / "aut.svg"
    assert main(["lots", "tower.yaml", "--dot", str(svg)]) == 0
    assert "<svg" in svg.read_text()
    capsys.readouterr()
    assert main(["lots", "tower.yaml", "--dot", str(tmp_path / "aut.gif")]) == 2
    err = capsys.readouterr().err
    assert "--dot" in err and "suffix" in err


GF40_TASK = (
    "version: 1\nname: gf40\nformula: "
    + '"'
    + " & ".join(f"GF p{i}" for i in range(1, 41))
    + '"\npropositions:\n'
    + "".join(f"  p{i}: {{class: c{i}}}\n" for i in range(1, 41))
    + "initial:\n  A: {"
    + ", ".join(f"c{i}: 1" for i in range(1, 41))
    + "}\n  B: {}\n"
)


@pytest.mark.parametrize("command", ["tamp", "tamp-verify"])
def test_a_formula_too_large_to_translate_exits_2_at_once(capsys, tmp_path, command):
    """40 GF conjuncts used to hang both commands in Spot; the size guard refuses them."""
    import time

    from tamp.commands.verify import main as verify_main

    task = write(tmp_path, "gf40.yaml", GF40_TASK)
    t = time.perf_counter()
    code = main(["lots", task]) if command == "tamp" else verify_main(["lots", task])
    assert time.perf_counter() - t < 2.0
    err = capsys.readouterr().err
    assert code == 2
    assert "gf40.yaml: formula: 'GF p1 & GF p2" in err
    assert "40 temporal conjuncts (limit 16" in err


def test_verify_lots_checks_every_table_of_the_run_with_interference(capsys):
    from tamp.commands.verify import main as verify_main

    code = verify_main(
        ["lots", "example1.yaml", "--interference", "example1_interference.yaml", "--json"]
    )
    doc = json.loads(capsys.readouterr().out)
    assert code == 0 and doc["holds"] is True
    subjects = [v["subject"] for v in doc["checks"]]
    assert len(subjects) == 4
    assert subjects[0] == "LOTS planned run"
    assert subjects[2] == "LOTS planned run (replan 1 at W^B hammer^0 screw^0 screwdriver^1)"
    assert verify_main(["lots", "example1.yaml"]) == 0  # no interference: the initial table
    assert capsys.readouterr().out.count("holds") == 2


# -- Zhou et al.'s action set by default; the return action W^B -> W^A is ours, opt-in -------

ONE_HAMMER = """version: 1
formula: "{formula}"
propositions:
  p1: {{class: hammer}}
  p2: {{class: hammer}}
initial:
  A: {{hammer: 1}}
{extra}"""


@pytest.mark.parametrize("formula", ["F(p1 & F p2)", "GF p1 & GF p2"])
def test_one_hammer_delivered_twice_needs_the_return_action(capsys, tmp_path, formula):
    """Both propositions move a hammer from W^A to W^B and there is one hammer: with the
    paper's actions (Def. 3) no run exists (exit 1, the reason names the return action);
    with our return action switched on, by flag or task field, the task is satisfied."""
    task = write(tmp_path, "t.yaml", ONE_HAMMER.format(formula=formula, extra=""))
    assert main(["lots", task]) == 1
    err = capsys.readouterr().err
    assert "no accepting run" in err and "--return-action" in err
    code, data = run_json(capsys, task, "--return-action")
    assert code == 0 and data["satisfied"] and data["returns"] and data["word_accepted"]
    assert ("remove", "hammer") in [(a["kind"], a["class"]) for a in data["actions"]]
    on = ONE_HAMMER.format(formula=formula, extra="actions: {return: true}\n")
    code, data = run_json(capsys, write(tmp_path, "on.yaml", on))
    assert code == 0 and data["satisfied"]


@pytest.mark.parametrize(
    "extra, field",
    [
        ("actions: {return: maybe}\n", "actions.return"),
        ("actions: {teleport: true}\n", "actions"),
        ("actions: [return]\n", "actions"),
    ],
)
def test_bad_actions_field_is_bad_input(capsys, tmp_path, extra, field):
    task = write(tmp_path, "t.yaml", ONE_HAMMER.format(formula="F p1", extra=extra))
    assert main(["lots", task]) == 2
    assert field in capsys.readouterr().err


FALSE_SUCCESS = """version: 1
formula: "F(p1 & F(p2 & F p3))"
propositions:
  p1: {class: block}
  p2: {class: block}
  p3: {class: cap}
initial:
  A: {block: 2, cap: 1}
  B: {block: 1}
"""


def test_a_block_that_started_in_wb_is_no_delivery(capsys, tmp_path):
    """A person adds a block to W^A before the first action (dis_2): the robot must still
    deliver two blocks and the cap — the block that started in W^B is not p1's delivery —
    and the JSON carries the run's word and the automaton's verdict on it."""
    task = write(tmp_path, "t.yaml", FALSE_SUCCESS)
    ev = write(
        tmp_path,
        "ev.yaml",
        "version: 1\nevents:\n  - {after: 0, kind: add, class: block, side: A}\n",
    )
    code, data = run_json(capsys, task, "--interference", ev)
    assert code == 0 and data["satisfied"]
    moves = [a["prop"] for a in data["actions"] if a["kind"] == "move"]
    assert moves == ["p1", "p2", "p3"]
    assert data["word"]["trace"] == [["p1"], ["p2"], ["p3"]]
    assert data["word_accepted"] is True and data["word_verdict"]["holds"] is True
    assert data["final"]["B"] == {"block": 3, "cap": 1}
    assert data["final_w_b"] == {"block": 3, "cap": 1}  # the plan in use, after the replan
    assert data["replans"] >= 1


POUR = """version: 1
events:
  - {after: 1, kind: add, class: body, side: B, count: 10000000}
  - {after: 2, kind: move, class: body, from: B, to: A, count: 9999999}
  - {after: 3, kind: remove, class: body, side: A, count: 5000000}
"""


def test_counts_stay_counts_when_a_person_pours_ten_million_bodies(capsys, tmp_path):
    """A person pours 10^7 tower bodies into W^B, moves all but one back to W^A and takes
    half of those away: objects of a class are a pile with a count, never 10^7 objects (this
    run took minutes when every body was one), and the final counts are exact integers."""
    ev = write(tmp_path, "pour.yaml", POUR)
    code, data = run_json(capsys, "tower", "--interference", ev)
    assert code == 0 and data["satisfied"] and data["word_accepted"]
    # the robot discarded the body it carried (W^B had bodies enough), W^B ends as the tower
    assert data["final"]["B"] == {"body": 1, "bottom": 1, "peak": 1}
    assert data["final"]["A"] == {"body": 1 + 9_999_999 - 5_000_000}
    assert data["final"]["waste"] == {"body": 1}


def test_ten_million_objects_in_the_task_file_plan_like_two(capsys, tmp_path):
    """W^A starting with 10^7 bodies: the ways of the task (its round ends) are searched up
    to the number of deliveries a way can need, so the run is the packaged tower's."""
    text = scenario("tower.yaml").read_text().replace("body: 2", "body: 10000000")
    task = write(tmp_path, "t.yaml", text)
    code, data = run_json(capsys, task)
    _, small = run_json(capsys, "tower")
    assert code == 0 and data["satisfied"]
    assert [a["prop"] for a in data["actions"]] == [a["prop"] for a in small["actions"]]
    assert data["final"]["A"] == {"body": 10_000_000 - 1}


@pytest.mark.parametrize(
    ("line", "why"),
    [
        ("{after: 0, kind: remove, class: body, side: A, count: 3}", "only 2 body in W^A"),
        ("{after: 0, kind: move, class: peak, from: A, to: B, count: 2}", "only 1 peak in W^A"),
    ],
)
def test_taking_more_than_a_pile_holds_is_bad_input(capsys, tmp_path, line, why):
    ev = write(tmp_path, "ev.yaml", f"version: 1\nevents:\n  - {line}\n")
    assert main(["lots", "tower", "--interference", ev]) == 2
    assert why in capsys.readouterr().err


def test_no_verify_skips_the_table_gate_with_a_warning(capsys):
    assert main(["lots", "tower.yaml", "--no-verify"]) == 0
    assert "--no-verify" in capsys.readouterr().err
