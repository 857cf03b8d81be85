"""Issue 17, LOTS completes what Theorem 1 promises: alternatives, objects already in W^B,
interference events that never happen (text and JSON, `tamp lots` and `tamp-verify lots`)."""

from __future__ import annotations

import json

from tamp.commands.main import main
from tamp.commands.verify import main as verify_main
from tamp.lots.run import run_task
from tamp.lots.task import load_events, load_task
from verification.lots import check_run_of

from .helpers import scenario

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
    assert verify_main(["lots", "tower.yaml", "--interference", str(ev)]) == 0
    assert "never happened: person removes body" in capsys.readouterr().out
    assert verify_main(["lots", "tower.yaml", "--interference", str(ev), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["holds"] and [e["after"] for e in data["unfired_events"]] == [99]
    assert main(["lots", "tower.yaml", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["unfired_events"] == []


# -- alternatives and objects already in W^B --------------------------------------------------

ALT = """version: 1
name: alt
formula: "F p | F q"
propositions:
  p: {class: cup}
  q: {class: mug, cost: 2.0}
initial:
  A: {cup: 1, mug: 1}
"""
TAKE_CUP = "version: 1\nevents:\n  - {after: 0, kind: remove, class: cup, side: A}\n"
IN_B = """version: 1
name: inb
formula: "F p"
propositions:
  p: {class: cup}
initial:
  A: {}
  B: {cup: 1}
"""


def _files(tmp_path, **texts):
    out = {}
    for name, text in texts.items():
        out[name] = tmp_path / f"{name}.yaml"
        out[name].write_text(text)
    return out


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
