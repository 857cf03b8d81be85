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
