"""benchmarks/grasp_experiments.py without simulating: its seeded scenes (clutter touching,
the moving target's path inside W^A and clear of the rest), the paired bootstrap and the
tables (an interval holding zero is not significant), the committed result file, and its
``--detector`` / ``--approach`` options (a resume never mixes them)."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest

from tamp.sim.lots.catalogue import CLASSES
from tamp.sim.lots.scenario import load_cell_scenario, rectangles_overlap

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def bench():
    path = ROOT / "benchmarks" / "grasp_experiments.py"
    spec = importlib.util.spec_from_file_location("grasp_experiments_bench", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def base():
    return load_cell_scenario("tower")


def _corners(o):
    return CLASSES[o.cls].footprint.corners(*o.xy, o.yaw)


@pytest.mark.parametrize("seed", range(6))
def test_clutter_scenes_touch_and_repeat(bench, base, seed):
    wb = bench._workcell_bench()
    scene, target, uid, v = bench.make("clutter", base, seed, wb)
    objs = scene.objects
    assert 5 <= len(objs) <= 8 and v is None
    assert objs[0].id == uid and objs[0].cls == target
    assert sum(o.cls == target for o in objs) == 1  # Pick(cls) has one candidate
    w = scene.workspaces["A"]
    for i, o in enumerate(objs):
        assert all(w.contains(*c) for c in _corners(o))
        others = [_corners(p) for p in objs[:i]]
        assert not any(rectangles_overlap(_corners(o), c, 0.0029) for c in others)
        if i:
            assert any(rectangles_overlap(_corners(o), c, 0.0081) for c in others)
    again = bench.make("clutter", base, seed, wb)[0]
    assert again.objects == objs


@pytest.mark.parametrize("seed", range(6))
def test_the_moving_target_stays_in_its_workspace(bench, base, seed):
    """Its path keeps it in W^A and clear of the distractor to its end, the longest of the
    16 directions (up to `MOVE_MAX`), so that it can go on sliding through the approach."""
    wb = bench._workcell_bench()
    scene, target, uid, move = bench.make("moving", base, seed, wb)
    assert move is not None and math.hypot(*move.velocity) == pytest.approx(bench.MOVE_SPEED)
    assert bench.MOVE_MIN <= move.travel <= bench.MOVE_MAX
    o = scene.object(uid)
    fp = CLASSES[o.cls].footprint
    u = np.array(move.velocity) / bench.MOVE_SPEED
    others = [_corners(p) for p in scene.objects if p.id != uid]
    for d in np.linspace(0.0, move.travel, 8):
        c = fp.corners(o.xy[0] + d * u[0], o.xy[1] + d * u[1], o.yaw)
        assert all(scene.workspaces["A"].contains(*p) for p in c)
        assert not any(rectangles_overlap(c, q, 0.0099) for q in others)
    assert bench.make("random", base, seed, wb)[0].objects == scene.objects
    assert bench.make("moving", base, seed, wb)[3] == move


def test_paired_bootstrap(bench):
    mean, lo, hi = bench.paired_bootstrap([1.0, 1.0, 1.0])
    assert (mean, lo, hi) == (1.0, 1.0, 1.0)
    rng = np.random.default_rng(1)
    d = list(rng.normal(0.5, 1.0, 40))
    mean, lo, hi = bench.paired_bootstrap(d)
    assert lo < mean < hi and lo > 0.0  # a clear shift: the interval excludes zero
    mean, lo, hi = bench.paired_bootstrap([-1.0, 1.0, -1.0, 1.0])
    assert lo < 0.0 < hi
    assert bench.paired_bootstrap([]) is None


def test_tables_pair_scenes_with_the_reference(bench):
    def pick(method, scene, ok, t):
        return {"set": "random", "method": method, "scene": scene, "success": ok, "status": "",
                "sim_time": t, "views": 5, "first_commit": 2.0}  # fmt: skip

    n = bench.MIN_PAIRS
    picks = [pick("hrgnet", s, True, 10.0 + s) for s in range(n)]
    picks += [pick("ggcnn", s, s != 0, 12.0 + s) for s in range(n)]
    picks += [pick("mask_axis", s, True, 10.0 + s + (0.5 if s % 2 else -0.5)) for s in range(n)]
    rows = {r["method"]: r for r in bench.tables(picks)}
    assert "success_diff" not in rows["hrgnet"]
    g = rows["ggcnn"]
    assert g["successes"] == n - 1 and g["paired_scenes"] == n
    assert g["time_diff"][0] == pytest.approx(2.0) and g["time_diff_significant"]
    assert g["success_diff"][0] == pytest.approx(-1 / n)
    assert not rows["mask_axis"]["time_diff_significant"]
    assert "n.s." in bench.markdown(list(rows.values()))
    # fewer paired scenes: no claim, even for a constant difference
    few = [p for p in picks if p["scene"] < 3]
    rows = {r["method"]: r for r in bench.tables(few)}
    assert rows["ggcnn"]["time_diff"] == [2.0, 2.0, 2.0]
    assert not rows["ggcnn"]["time_diff_significant"]
    assert "no claim" in bench.markdown(list(rows.values()))


def test_the_committed_results_hold_their_tables(bench):
    path = ROOT / "benchmarks" / "results" / "grasp_experiments.json"
    doc = json.loads(path.read_text())
    assert doc["rows"] == json.loads(json.dumps(bench.tables(doc["picks"])))
    assert {p["set"] for p in doc["picks"]} <= set(bench.SETS)


def test_a_resume_never_mixes_detectors_or_approaches(bench, tmp_path, monkeypatch, capsys):
    """A result file's picks keep the detector and approach they ran with; one that names
    neither ran before the closed approach existed (the oracle, the open approach)."""
    out = tmp_path / "picks.json"
    pick = {"set": "random", "method": "hrgnet", "scene": 0, "success": True, "status": "",
            "sim_time": 10.0, "views": 5, "first_commit": 2.0}  # fmt: skip
    out.write_text(json.dumps({"picks": [pick]}))

    def no_pick(*args, **kwargs):
        raise AssertionError("a resume of mixed picks ran a pick")

    monkeypatch.setattr(bench, "run_pick", no_pick)

    def run(*args: str) -> int:
        monkeypatch.setattr("sys.argv", ["grasp_experiments.py", "--out", str(out), *args])
        return bench.main()

    assert run("--resume") == 2
    assert "approach: its picks ran with open, not --approach closed" in capsys.readouterr().out
    assert run("--resume", "--approach", "open", "--detector", "learned") == 2
    assert "detector: its picks ran with oracle, not --detector learned" in capsys.readouterr().out
    with pytest.raises(SystemExit) as exit_:
        run("--approach", "sideways")
    assert exit_.value.code == 2
