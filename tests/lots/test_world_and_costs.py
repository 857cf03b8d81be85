"""The LocalWorld contract, event timing, per-action costs, peers as oracles, the benchmark."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from tamp.lots.controller import LotsController
from tamp.lots.product import ProductPlanner
from tamp.lots.run import run_task
from tamp.lots.task import Event, Proposition, Task
from tamp.lots.world import LocalWorld, SymbolicLotsWorld


def test_symbolic_world_implements_the_local_world_protocol(tower):
    w = SymbolicLotsWorld(tower)
    assert isinstance(w, LocalWorld)
    assert w.observe("A") == {"bottom": 1, "body": 2, "peak": 1} and w.observe("B") == {}
    assert w.pick("peak") and not w.pick.__self__.a["peak"]
    with pytest.raises(RuntimeError):
        w.pick("body")  # one object at a time
    w.return_held()
    assert w.actions_done == 1 and w.observe("A")["peak"] == 1


def test_holding_event_without_a_pick_happens_during_that_action(tower):
    """A 'holding' event scheduled for a removal or a wait is not lost."""
    w = SymbolicLotsWorld(
        tower, [Event(after=0, phase="holding", kind="add", cls="cube", side="A")]
    )
    w.wait()
    assert w.observe("A")["cube"] == 1
    assert [(n, phase) for n, phase, _ in w.log] == [(0, "holding")]


def test_per_action_costs_choose_the_cheaper_proposition():
    def task(c1, c2):
        props = (Proposition("p1", "big", c1), Proposition("p2", "small", c2))
        return Task("F p1 | F p2", props, {"big": 1, "small": 1})

    for (c1, c2), chosen in (((5.0, 1.0), "p2"), ((1.0, 5.0), "p1")):
        c = LotsController(task(c1, c2))
        moves = [s.prop for s in c.initial_plan.steps if s.kind == "move"]
        assert moves == [chosen]
        base = ProductPlanner(c.aut, c.lots, task(c1, c2), (1, 1))
        assert base.replan(c.aut.initial, (1, 1), (0, 0)).cost == c.initial_plan.cost == 1.0


@pytest.mark.parametrize("task_name", ["example1", "tower", "model_building"])
def test_tables_after_replanning_pass_the_verifier(task_name, request):
    """Peer oracle: `verification` checks every entry of the table rebuilt by Alg. 3."""
    vlots = pytest.importorskip("verification.lots")
    task = request.getfixturevalue(task_name)
    # the object the automaton wants last is put into W^B first: an unforeseen W^B state
    c0 = LotsController(task)
    last = [s for s in c0.initial_plan.steps if s.kind == "move"][-1]
    early = Event(after=0, kind="move", cls=c0.lots.classes[last.cls], src="A", dst="B")
    r = run_task(task, [early])
    assert r.satisfied and r.replans >= 1
    c = r.controller
    verdict = vlots.check_table(c.aut, c.table, c.lots, c.plan.cycle)
    assert verdict.holds, verdict


def test_benchmark_prints_a_table_and_a_json_line(capsys):
    path = Path(__file__).resolve().parents[2] / "benchmarks" / "lots_vs_product.py"
    spec = importlib.util.spec_from_file_location("lots_vs_product", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    assert bench.main(["--quick", "--n-max", "3"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert out[0].startswith("family")
    data = json.loads(out[-1])
    assert data["benchmark"] == "lots_vs_product" and len(data["rows"]) == 4
    for row in data["rows"]:
        assert row["plan_cost_ours"] == row["plan_cost_product"]
        assert row["w_b_states"] == 2 ** row["n"]
