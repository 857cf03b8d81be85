"""``tamp simulate lots`` end to end: the tower task run by the LOTS controller inside the
Drake workcell, judged on the plant; and the inputs it refuses before simulating."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tamp.errors import InputError
from tamp.lots.task import load_task
from tamp.sim.lots.scenario import load_cell_scenario
from tamp.sim.lots.simulate import check_matches, with_network

ENV = {**os.environ, "DRAKE_ALLOW_NETWORK": "meshcat"}


def cli(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tamp.commands.main", "simulate", "lots", *args],
        capture_output=True,
        text=True,
        env=ENV,
        timeout=timeout,
    )


def test_task_and_scene_must_start_from_the_same_objects():
    check_matches(load_task("tower"), load_cell_scenario("tower"))
    with pytest.raises(InputError, match="W\\^A holds") as e:
        check_matches(load_task("model_building"), load_cell_scenario("tower"))
    assert e.value.field == "objects"


def test_every_network_ships_weights_and_unknown_ones_are_refused(monkeypatch):
    from tamp.sim.core.models import models_dir
    from tamp.sim.lots import simulate
    from tamp.sim.lots.scenario import DEFAULT_WEIGHTS, NETWORKS

    scene = load_cell_scenario("tower")
    assert with_network(scene, "hrgnet") is scene
    for net in NETWORKS:
        assert (models_dir() / DEFAULT_WEIGHTS[net]).is_file()
        assert with_network(scene, net).grasp.network == net
    with pytest.raises(InputError, match="unknown network") as e:
        with_network(scene, "yolo")
    assert e.value.field == "--grasp"
    # a network whose weights are not shipped is refused before anything is built
    monkeypatch.setattr(simulate, "DEFAULT_WEIGHTS", {"hrgnet": DEFAULT_WEIGHTS["hrgnet"]})
    with pytest.raises(InputError, match="no shipped weights") as e:
        with_network(scene, "ggcnn")
    assert e.value.field == "--grasp"


def test_cli_refuses_bad_interference_and_mismatched_scenes_with_exit_2(capsys):
    from tamp.commands.main import main

    def refused(*args: str) -> str:
        assert main(["simulate", "lots", *args]) == 2
        return capsys.readouterr().err

    assert "events[0].class" in refused(
        "tower", "--interference", "model_building_fig8"
    )  # no scissors in the tower task to move
    assert "objects: W^A holds" in refused("tower", "--cell", "model_building")
    assert "--grasp" in refused("tower", "--grasp", "yolo")
    assert "--max-sim-time" in refused("tower", "--max-sim-time", "-1")


def test_a_person_adding_more_than_the_shelf_holds_is_refused_naming_the_count(capsys, tmp_path):
    """Counts stay counts symbolically; in Drake each object the person adds is a free body
    on the staging shelf, so a script adding ten million is bad input (exit 2), not a hang."""
    from tamp.commands.main import main

    ev = tmp_path / "pour.yaml"
    ev.write_text(
        "version: 1\nevents:\n  - {after: 1, kind: add, class: body, side: A, count: 10000000}\n"
    )
    assert main(["simulate", "lots", "tower", "--interference", str(ev)]) == 2
    err = capsys.readouterr().err
    assert "pour.yaml: events[0].count" in err and "holds 10 objects" in err


@pytest.mark.slow
def test_a_task_in_the_tower_cell_through_the_cli(tmp_path):
    """The CLI end to end on the tower's cell: a one-delivery task (the bottom to W^B) while
    the person's hand first moves a body into W^B (dis_1). Measured on the plant, the robot
    sees the surplus body, discards it, and delivers the bottom; the JSON says so. The whole
    narratives of the paper are `make test-paper`'s (tests/sim/lots/test_narrative_*.py)."""
    task = tmp_path / "tower.yaml"  # named tower: the packaged tower cell is its default
    text = Path(load_task("tower").file).read_text()
    task.write_text(text.replace('formula: "F(p1 & F(p2 & F p3))"', 'formula: "F p1"'))
    events = tmp_path / "ev.yaml"
    events.write_text(
        "version: 1\nevents:\n  - {after: 0, kind: move, class: body, from: A, to: B}\n"
    )
    r = cli(
        str(task), "--interference", str(events), "--json", "--max-sim-time", "300", timeout=3000
    )
    assert r.returncode == 0, r.stderr[-2000:] + r.stdout[-2000:]
    out = json.loads(r.stdout)
    assert out["satisfied"] is True and out["status"] == "SUCCESS"
    # measured on the plant: the bottom in W^B, the moved body in the basket
    assert out["final_counts"]["B"] == {"bottom": 1}
    assert out["final_counts"]["A"] == {"body": 1, "peak": 1}
    assert out["final_counts"]["waste"] == {"body": 1} and out["elsewhere"] == []
    assert [a["outcome"] for a in out["person_actions"]] == ["done"]
    kinds = [a["kind"] for a in out["robot_actions"]]
    assert "remove" in kinds and kinds[-1] == "move"  # the surplus body out, then p1
    assert [a["prop"] for a in out["robot_actions"] if a["kind"] == "move"] == ["p1"]
    assert all(a["end"] > a["start"] for a in out["actions"])
    assert out["grasps"]["successes"] >= 2 and out["grasps"]["attempts"] >= 2
    assert out["frames_rendered"] > 0 and out["sim_time"] > 20 and out["wall_time"] > 0
    assert out["safety_stops"] == []  # the hand kept clear; limits and command rate kept
