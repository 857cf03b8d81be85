"""The --execute helpers of `tamp plan`: argument parsing, JSON output, exit status."""

from __future__ import annotations

import argparse
import json

import pytest

from tamp import scenarios
from tamp.commands.execute_args import add_execute_arguments, run_execute
from tamp.demo import load_demonstration
from tamp.errors import InputError
from tamp.rg import plan
from tamp.world import Point
from tamp.world.events import AtTick, parse_appear, parse_fail


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="tamp plan")
    p.add_argument("demo")
    p.add_argument("--json", action="store_true")
    add_execute_arguments(p)
    return p


def _run(argv: list[str], capsys) -> tuple[int, str, str]:
    args = _parser().parse_args(argv)
    demo = load_demonstration(scenarios.resolve(args.demo))
    code = run_execute(args, demo, plan(demo), verify=False)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_execute_case3_json(tmp_path, capsys) -> None:
    xml, dot = tmp_path / "bt.xml", tmp_path / "bt.dot"
    code, out, _ = _run(
        ["case3.yaml", "--execute", "--appear", "Oa@2.2,0.8,0.1", "--json",
         "--bt-xml", str(xml), "--bt-dot", str(dot)],
        capsys,
    )  # fmt: skip
    assert code == 0
    doc = json.loads(out)
    assert doc["reached"] is True and doc["order"] == ["G0", "G1"]
    assert {"action": "Place", "args": ["O1", "free2"]} in doc["executed"]
    assert doc["executed"][-1] == {"action": "Place", "args": ["O1", "L1"]}
    assert doc["conflicts"] == 1 and doc["recoveries"] == 1 and doc["expansions"] > 0
    free1 = next(
        a for a in load_demonstration(scenarios.path("case3.yaml")).free_areas if a.name == "free1"
    )
    assert doc["final_world"]["objects"]["Oa"][:2] == [round(free1.pos.x, 4), round(free1.pos.y, 4)]
    assert xml.read_text().startswith("<?xml") and "digraph" in dot.read_text()


def test_execute_text_and_failure_exit_status(capsys) -> None:
    code, out, err = _run(["case1.yaml", "--execute", "--fail", "Pick(O1)x9"], capsys)
    assert code == 1
    assert "Pick(O1) failed" in out and "goal not reached" in err
    code, out, _ = _run(["case1.yaml", "--execute"], capsys)
    assert code == 0 and "SUCCESS" in out and "Place(O0, L0)" in out


@pytest.mark.parametrize("text", ["Oa", "Oa@1,2,x", "Oa@1", "@1,2,3", "Oa@1,2,3@-1"])
def test_bad_appear_is_input_error(text: str) -> None:
    with pytest.raises(InputError, match="--appear"):
        parse_appear(text)


def test_appear_forms() -> None:
    a = parse_appear("Oa@2.2,0.8,0.1")
    assert (a.obj, a.place, a.when) == ("Oa", Point(2.2, 0.8, 0.1), None)
    b = parse_appear("Ob@-1,2@7")
    assert (b.place, b.when) == (Point(-1.0, 2.0, 0.0), AtTick(7))


@pytest.mark.parametrize("text", ["Fly(O1)", "Place(O1)", "Pick(O1)x0", "Pick(("])
def test_bad_failure_is_input_error(text: str, capsys) -> None:
    with pytest.raises(InputError, match="--fail"):
        _run(["case1.yaml", "--execute", "--fail", text], capsys)


def test_failure_forms() -> None:
    assert parse_fail("Pick(O1)").args == ("O1",)
    f = parse_fail("Place(O1, L1)x2")
    assert f.args == ("O1", "L1") and f.times == 2
    assert parse_fail("MoveTo").args is None


def test_execute_uses_the_demonstrations_domain(tmp_path, capsys) -> None:
    """`robot.domain` of the demonstration drives --execute (it used to run youBot's
    templates whatever the file said, unlike `tamp-verify bt` and the simulation)."""
    from tamp.world.actions import DOMAINS_DIR

    text = (DOMAINS_DIR / "youbot.yaml").read_text()
    assert "name: Pick" in text
    domain = tmp_path / "grasping.yaml"
    domain.write_text(text.replace("name: Pick", "name: Grasp"))
    demo = tmp_path / "demo.yaml"
    source = scenarios.path("case1.yaml").read_text()
    assert "robot:\n  start: [0, 0, 0]\n" in source
    demo.write_text(
        source.replace(
            "robot:\n  start: [0, 0, 0]\n", f"robot:\n  start: [0, 0, 0]\n  domain: {domain}\n"
        )
    )
    code, out, _ = _run([str(demo), "--execute", "--fail", "Grasp(O2)", "--json"], capsys)
    assert code == 0, out
    doc = json.loads(out)
    names = [a["action"] for a in doc["executed"]]
    assert "Grasp" in names and "Pick" not in names
    assert doc["retries"] >= 1  # the scripted Grasp failure was matched and retried


def test_fail_on_an_unknown_object_is_bad_input(capsys) -> None:
    """`--fail Pick(O9)` used to be accepted and never to fire (no such object)."""
    with pytest.raises(InputError, match="unknown object 'O9'"):
        _run(["case1.yaml", "--execute", "--fail", "Pick(O9)"], capsys)
    # an object that appears during execution may fail too
    code, out, _ = _run(
        ["case3.yaml", "--execute", "--appear", "Oa@2.2,0.8,0.1", "--fail", "Pick(Oa)"], capsys
    )
    assert code == 0 and "retry Pick(Oa): skill failed" in out
