"""The World contract of the LOTS workcell, event timing, per-action costs, peers, the benchmark."""

from __future__ import annotations

import importlib.util
import json
from dataclasses import replace
from pathlib import Path

import pytest

from tamp.errors import InputError
from tamp.lots.cell import skill, visible_counts
from tamp.lots.controller import LotsController
from tamp.lots.person import ScriptedPerson, actions_done
from tamp.lots.product import ProductPlanner
from tamp.lots.run import lots_world, run_task
from tamp.lots.task import Event, Proposition, Task
from tamp.verification import lots as vlots
from tamp.world.interface import Status, World


def execute(world, name, *args, person=None):
    """Start one skill and tick the world (and the person) until it ends."""
    h = world.start(skill(name, *args))
    while (st := world.poll(h)) is Status.RUNNING:
        world.step()
        if person is not None:
            person.act(world)
    return st


def test_symbolic_workcell_speaks_the_world_contract(tower):
    w = lots_world(tower)
    assert isinstance(w, World)
    assert visible_counts(w.observe(), "A") is None  # the camera looks at neither workspace
    assert execute(w, "LookAt", "A") is Status.SUCCESS
    assert visible_counts(w.observe(), "A") == {"body": 2, "bottom": 1, "peak": 1}
    assert visible_counts(w.observe(), "B") is None  # one workspace at a time
    assert execute(w, "LookAt", "B") is Status.SUCCESS
    assert visible_counts(w.observe(), "B") == {}
    assert execute(w, "Pick", "peak", "A") is Status.SUCCESS
    assert execute(w, "Pick", "body", "A") is Status.FAILURE  # one object at a time
    execute(w, "LookAt", "A")
    assert "peak" not in visible_counts(w.observe(), "A")
    assert execute(w, "Place", "A") is Status.SUCCESS  # put it back
    assert actions_done(w) == 1 and visible_counts(w.observe(), "A")["peak"] == 1
    with pytest.raises(RuntimeError):  # World protocol: one skill at a time
        w.start(skill("LookAt", "B"))
        w.start(skill("LookAt", "A"))


def test_holding_event_without_a_pick_happens_during_that_action(tower):
    """A 'holding' event scheduled for an action without a pick (a wait) is not lost."""
    w = lots_world(tower)
    person = ScriptedPerson([Event(after=0, phase="holding", kind="add", cls="cube", side="A")])
    person.act(w)
    execute(w, "Wait", "A", person=person)
    person.act(w)
    execute(w, "LookAt", "A")
    assert visible_counts(w.observe(), "A")["cube"] == 1
    assert [(n, phase) for n, phase, _ in person.log] == [(0, "holding")]


def test_person_slots_follow_the_robot_actions():
    """idle N once N actions ended; holding N once the hand holds during action N+1, or
    during action N+1 itself when it has no pick (a wait); each slot begins once."""
    p = ScriptedPerson()
    assert p.slots(0, False) == [(0, "idle")]
    assert p.slots(0, False) == []
    assert p.slots(0, True) == [(0, "holding")]  # picked
    assert p.slots(0, True) == []
    assert p.slots(1, False) == [(1, "idle")]  # placed
    assert p.slots(2, False) == [(1, "holding"), (2, "idle")]  # a wait: no pick


def test_impossible_scripted_event_names_the_file_and_field(tower):
    ev = Event(after=0, kind="remove", cls="peak", side="B", where="ev.yaml: events[0]")
    with pytest.raises(InputError) as err:
        ScriptedPerson([ev]).act(lots_world(tower))
    assert err.value.file == "ev.yaml" and err.value.field == "events[0]"
    lax = ScriptedPerson([ev], strict=False)
    lax.act(lots_world(tower))
    assert lax.log == [] and lax.pending_events() == 0


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
    # with our return action: the early object goes back to W^A and is delivered in order
    task = replace(request.getfixturevalue(task_name), returns=True)
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
