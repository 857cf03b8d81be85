"""Issue 17, LOTS completes what Theorem 1 promises: alternatives, objects already in W^B,
interference events that never happen (text and JSON, `tamp lots` and `tamp-verify lots`)."""

from __future__ import annotations

import itertools
import json

from hypothesis import example, given, settings
from hypothesis import strategies as st

from tamp.commands.main import main
from tamp.commands.verify import main as verify_main
from tamp.errors import InfeasibleError
from tamp.lots.cell import objects_of, side_counts
from tamp.lots.controller import LotsController
from tamp.lots.lots import Lots
from tamp.lots.person import actions_done
from tamp.lots.product import ProductPlanner
from tamp.lots.run import run_task
from tamp.lots.task import Event, Proposition, Task, load_events, load_task
from tamp.verification.lots import check_run_of

from .helpers import TWO_CLASSES, random_tasks, scenario, take_away, write_files

LATE = "version: 1\nevents:\n  - {after: 99, kind: remove, class: body, side: B}\n"


def test_unfired_event_is_reported_by_the_api(tmp_path):
    task = load_task(scenario("tower.yaml"))
    ev = tmp_path / "late.yaml"
    ev.write_text(LATE)
    events = load_events(ev, task)
    report = run_task(task, events)
    assert report.satisfied and len(report.actions) < 99
    assert report.unfired_events == events
    (item,) = report.to_json()["unfired_events"]
    assert item["after"] == 99 and item["phase"] == "idle"
    assert item["where"].endswith("late.yaml: events[0]")
    assert "removes body from W^B" in item["event"]
    assert item["message"].startswith("never happened: person removes body from W^B (dis_2)")
    checked = check_run_of(task, events)
    assert checked.holds and checked.unfired_events == events
    assert checked.to_json()["unfired_events"] == [item]
    # an event that fires is not listed
    assert (
        run_task(task, load_events(scenario("tower_interference.yaml"), task)).unfired_events == []
    )


def test_unfired_event_is_reported_by_the_clis(tmp_path, capsys):
    ev = tmp_path / "late.yaml"
    ev.write_text(LATE)
    assert main(["lots", "tower.yaml", "--interference", str(ev)]) == 0
    out = capsys.readouterr().out
    assert "never happened: person removes body from W^B (dis_2) after action 99" in out
    assert "task satisfied (1 scripted event(s) never happened)" in out
    assert main(["lots", "tower.yaml", "--interference", str(ev), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [e["after"] for e in data["unfired_events"]] == [99]
    # the JSON says it in words too, and the run still counts as satisfied (exit 0): the
    # issue asks to say so, not to refuse the script
    assert data["satisfied"] and "after action 99" in data["unfired_events"][0]["message"]
    assert verify_main(["lots", "tower.yaml", "--interference", str(ev)]) == 0
    assert "never happened: person removes body" in capsys.readouterr().out
    assert verify_main(["lots", "tower.yaml", "--interference", str(ev), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["holds"] and [e["after"] for e in data["unfired_events"]] == [99]
    assert data["unfired_events"][0]["message"].startswith("never happened: person removes")
    assert main(["lots", "tower.yaml", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["unfired_events"] == []


# -- alternatives and objects already in W^B --------------------------------------------------

ALT = TWO_CLASSES.format(name="alt", formula="F p | F q")
TAKE_CUP = take_away("cup")
IN_B = """version: 1
name: inb
formula: "F p"
actions: {return: true}   # the cup in W^B goes back to W^A to be delivered (our extension)
propositions:
  p: {class: cup}
initial:
  A: {}
  B: {cup: 1}
"""


_files = write_files


def test_alternative_way_is_taken_when_the_planned_class_is_gone(tmp_path, capsys):
    f = _files(tmp_path, alt=ALT, take=TAKE_CUP)
    task = load_task(f["alt"])
    report = run_task(task)
    assert [a.key() for a in report.actions] == [("move", "p")]  # the cheaper way
    c = report.controller
    assert c.lots.goals == ((1, 0), (0, 1)) and c.lots.num_wb_states() == 4
    report = run_task(task, load_events(f["take"], task))
    assert report.satisfied and report.replans == 1
    assert [a.key() for a in report.actions] == [("move", "q")]
    assert report.counts()["B"] == {"mug": 1}
    assert check_run_of(task, load_events(f["take"], task)).holds  # every table gated
    assert main(["lots", str(f["alt"]), "--interference", str(f["take"])]) == 0
    out = capsys.readouterr().out
    assert "1. q: move mug W^A→W^B" in out and "task satisfied" in out


def test_object_of_a_needed_class_already_in_wb_is_removed_and_delivered(tmp_path, capsys):
    f = _files(tmp_path, inb=IN_B)
    task = load_task(f["inb"])
    report = run_task(task)
    assert report.satisfied
    assert [a.key() for a in report.actions] == [("remove", "cup"), ("move", "p")]
    assert report.actions[0].dest == "A"  # back to W^A: the delivery needs it
    assert check_run_of(task).holds
    assert main(["lots", str(f["inb"]), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["satisfied"] and data["final"]["B"] == {"cup": 1}
    assert [a["text"] for a in data["actions"]] == ["remove cup W^B→W^A", "p: move cup W^A→W^B"]


# -- oracle: the product baseline (Lemma 2) over small random tasks with alternatives ---------

ALTERNATIVES = (
    "F {0} | F {1}",
    "F({0} & F {2}) | F {1}",
    "(F {0} & F {2}) | F({1} & F {2})",
    "F {0} | F({1} & F {2})",
    "(F {0} | F {1}) & F {2}",
)


def random_task():
    return random_tasks(ALTERNATIVES)


takeaway = st.tuples(st.sampled_from(("A", "B")), st.integers(0, 2), st.integers(1, 2))


def brute_force_ends(task, aut) -> set:
    """Minimal W^B counts of accepted words ``d_1 … d_k · ∅^ω`` (k ≤ 3 deliveries, within the
    objects that exist): the ends of every accepting way of these F-type tasks, by brute
    force with Spot's lasso acceptance (independent of `round_goals`)."""
    idx = {cls: i for i, cls in enumerate(task.classes)}
    avail = [task.initial_a.get(cls, 0) + task.initial_b.get(cls, 0) for cls in task.classes]
    ends = set()
    for k in range(4):
        for word in itertools.product(task.propositions, repeat=k):
            counts = [0] * len(avail)
            for p in word:
                counts[idx[p.cls]] += 1
            if all(x <= n for x, n in zip(counts, avail, strict=True)) and aut.accepts_lasso(
                [frozenset({p.name}) for p in word], [frozenset()]
            ):
                ends.add(tuple(counts))
    return {e for e in ends if not any(f != e and all(map(int.__le__, f, e)) for f in ends)}


@settings(max_examples=60, deadline=None)
@given(task=random_task(), when=st.integers(0, 2), takes=st.lists(takeaway, max_size=3))
@example(  # a plain way beside a redelivering one with a smaller end (found by this test)
    task=Task(
        "(F p0 & F p2) | F(p1 & F p2)",
        (Proposition("p0", "cup"), Proposition("p1", "mug"), Proposition("p2", "mug")),
        {"cup": 1, "mug": 0, "jar": 0},
        {"cup": 1, "mug": 1, "jar": 0},
    ),
    when=0,
    takes=[],
)
def test_lots_completes_whenever_the_product_planner_can(task, when, takes):
    """After a person takes objects away (W^A or W^B, any class), LOTS finishes the task
    whenever the product baseline finds a plan from that situation (automaton state reached by
    the robot's letters, true counts in W^A and W^B)."""
    try:
        LotsController(task)
    except InfeasibleError:
        return  # no accepting way with these objects at all
    seen: dict = {}

    def policy(n, phase, world):
        if n != when or phase != "idle" or seen:
            return
        for side, k, count in takes:
            cls = task.classes[k % len(task.classes)]
            have = len(objects_of(world.state, cls, side))
            if have:
                yield Event(after=n, kind="remove", cls=cls, side=side, count=min(count, have))
        seen.update(side_counts(world.state), done=actions_done(world))

    r = run_task(task, policy=policy, max_waits=2)
    if not seen:  # the run ended before the person acted: nothing taken away
        assert r.satisfied, r.reason
        return
    c = r.controller
    # automaton states the robot's letters lead to (deliveries {p}, everything else ∅)
    qs = {c.aut.initial}
    for a in r.actions[: seen["done"]]:
        letter = frozenset({a.prop}) if a.kind == "move" else frozenset()
        qs = {n for q in qs for n in c.aut.successors(q, letter)}
    ends = brute_force_ends(task, c.aut)
    assert ends <= set(c.lots.goals)  # every accepting way is a goal of LOTS
    # (ways that deliver an object twice or choose inside GF: tests/lots/test_ways.py)
    a_now, b_now = c.lots.vector(seen["A"]), c.lots.vector(seen["B"])
    totals = tuple(x + y for x, y in zip(a_now, b_now, strict=True))
    oracle = Lots(c.lots.classes, c.lots.prop_class, c.lots.final, tuple(sorted(ends)))
    product = ProductPlanner(c.aut, oracle, task, totals)
    feasible = any(product.replan(q, a_now, b_now) is not None for q in sorted(qs))
    if feasible:
        assert r.satisfied, (r.reason, [a.text() for a in r.actions], seen)
    if r.satisfied:
        assert c.lots.is_goal(c.lots.vector(r.counts()["B"]))
