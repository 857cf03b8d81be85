"""benchmarks/grasp.py end to end on fixture data: every run for two seeds, accuracies of the
final weights per seed, their pooled mean, the target verdicts computed from them, and runs
that no target compares left out or trained for fewer seeds."""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

import pytest
import torch

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("grasp_bench", ROOT / "benchmarks" / "grasp.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_two_seeds_pooled_from_final_weights(bench, jacquard_dir: Path, tmp_path: Path, capsys):
    budget = dict(bench.FULL_BUDGET, size=32, epochs=1, batches_per_epoch=1, batch_size=2)
    budget["test_fraction"] = 0.25
    bench.train_all(jacquard_dir, tmp_path, budget, (0, 1), threads=1)
    rows = bench.measure(tmp_path, None, [1], repeats=1, time_size=32)
    assert [r["model"] for r in rows] == list(bench.RUNS)
    for r in rows:
        assert [s["seed"] for s in r["seeds"]] == [0, 1]
        assert r["test_images"] == sum(s["images"] for s in r["seeds"])
        assert r["accuracy"] == sum(s["correct"] for s in r["seeds"]) / r["test_images"]
        assert r["budget"]["schedule"] == "cosine" and r["budget"]["epochs"] == 1
        assert r["cpu_1t"]["repeats"] == 1
    result = bench.report(rows, [1])
    by = {r["model"]: r["accuracy"] for r in rows}
    targets = result["targets"]
    assert targets["fusion on > off"] == (by["hrgnet"] > by["hrgnet_nofusion"])
    assert targets["hrgnet >= grconvnet"] == (by["hrgnet"] >= by["grconvnet"])
    gain = 100 * (by["hrgnet"] - by["hrgnet_final"])
    assert result["exchange_gain_points"] == pytest.approx(gain)
    fusion = {r["model"]: torch.load(tmp_path / r["model"] / "seed0" / "final.pt",
                                     weights_only=False)["meta"]["kwargs"].get("fusion")
              for r in rows}  # fmt: skip
    assert fusion == {"hrgnet": "full", "hrgnet_final": "final", "hrgnet_nofusion": "none",
                      "grconvnet": None, "ggcnn": None}  # fmt: skip
    out = capsys.readouterr().out
    assert "seed 0" in out and "seed 1" in out and "mean" in out

    # the runs no target compares may be missing, or trained for fewer seeds
    shutil.rmtree(tmp_path / "hrgnet_final")
    shutil.rmtree(tmp_path / "ggcnn" / "seed1")
    rows = bench.measure(tmp_path, None, [1], repeats=1, time_size=32)
    assert [r["model"] for r in rows] == ["hrgnet", "hrgnet_nofusion", "grconvnet", "ggcnn"]
    result = bench.report(rows, [1])
    assert "exchange_gain_points" not in result
    assert result["targets"]["fusion on > off"] == targets["fusion on > off"]
    ggcnn = capsys.readouterr().out.splitlines()[-5]
    assert ggcnn.startswith("ggcnn") and ggcnn.endswith("(seeds 0 only)")
    # ... but the compared runs must share their seeds
    shutil.rmtree(tmp_path / "grconvnet" / "seed1")
    rows = bench.measure(tmp_path, None, [1], repeats=1, time_size=32)
    with pytest.raises(SystemExit, match="the compared runs need the same seeds"):
        bench.report(rows, [1])


def test_missing_runs_are_reported(bench, tmp_path: Path):
    with pytest.raises(SystemExit, match="train the runs first"):
        bench.measure(tmp_path, None, [1])
