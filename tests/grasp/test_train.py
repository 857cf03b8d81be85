"""Training: a few steps on tiny data, checkpoints that resume exactly, evaluation with
oracle models, and DistributedDataParallel with two CPU processes (gloo)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch

from tamp.grasp.datasets import GraspDataset
from tamp.grasp.evaluate import evaluate, fit_width_calibration
from tamp.grasp.models import full_kwargs
from tamp.grasp.train import (
    TrainConfig,
    learning_rate,
    load_model,
    train,
    train_local_processes,
)


def _cfg(root: Path, out: Path, **kw) -> TrainConfig:
    base = dict(
        dataset="jacquard", path=str(root), model="hrgnet", input="rgbd", out=str(out),
        size=32, epochs=2, batch_size=2, batches_per_epoch=2, split="object",
        test_fraction=0.25, val_fraction=0.25, threads=1, model_kwargs={"widths": [4, 8]},
    )  # fmt: skip
    base.update(kw)
    return TrainConfig(**base)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["hrgnet", "ggcnn", "grconvnet"])
def test_few_steps_write_checkpoints(jacquard_dir: Path, tmp_path: Path, model: str):
    kwargs = {"widths": [4, 8]} if model == "hrgnet" else {}
    if model == "grconvnet":
        kwargs = {"channels": 4}
    summary = train(_cfg(jacquard_dir, tmp_path / model, model=model, model_kwargs=kwargs),
                    progress=False)  # fmt: skip
    assert [h["epoch"] for h in summary["history"]] == [1, 2]
    assert summary["test_images"] == 2 and summary["train_images"] == 4
    assert summary["val_images"] == 2  # one object of four for validation, one for the test
    assert all(h["val_images"] == 2 and "accuracy" not in h for h in summary["history"])
    for name in ("last.pt", "best.pt", "final.pt", "summary.json"):
        assert (tmp_path / model / name).is_file()
    net, meta = load_model(tmp_path / model / "best.pt")
    assert meta["model"] == model and meta["size"] == 32
    # best.pt is the epoch best on the validation part; both files record the split
    assert meta["epoch"] == summary["best_epoch"]
    assert (
        meta["val_accuracy"]
        == summary["best_val_accuracy"]
        == max(h["val_accuracy"] for h in summary["history"])
    )
    _, final_meta = load_model(tmp_path / model / "final.pt")
    assert meta["split"] == final_meta["split"] == summary["split"]
    assert meta["split"]["kind"] == "object" and meta["split"]["val_images"] == 2
    assert final_meta["accuracy"] == summary["final_accuracy"] == summary["final_test"]["accuracy"]
    # every constructor argument is recorded, so a later change of a default cannot
    # rebuild a different network from this file
    assert meta["kwargs"] == full_kwargs(
        model, **(kwargs | ({"fusion": "full"} if model == "hrgnet" else {}))
    )
    assert set(meta["kwargs"]) >= ({"widths", "blocks", "modules"} if model == "hrgnet" else set())
    assert json.loads((tmp_path / model / "summary.json").read_text())["parameters"] > 0


@pytest.mark.slow
def test_cosine_schedule_anneals_to_zero(jacquard_dir: Path, tmp_path: Path):
    cfg = _cfg(jacquard_dir, tmp_path)
    rates = [learning_rate(cfg, t, 100) for t in range(101)]
    assert rates[0] == cfg.lr and rates[50] == pytest.approx(cfg.lr / 2) and rates[100] == 0.0
    assert all(a >= b for a, b in zip(rates, rates[1:], strict=False))
    flat = _cfg(jacquard_dir, tmp_path, schedule="constant")
    assert {learning_rate(flat, t, 100) for t in range(101)} == {flat.lr}
    summary = train(_cfg(jacquard_dir, tmp_path / "run", epochs=2), progress=False)
    lrs = [h["lr"] for h in summary["history"]]  # rate of the last step of each epoch
    assert lrs == [learning_rate(cfg, 1, 4), learning_rate(cfg, 3, 4)]  # 2 steps an epoch
    # final.pt holds the weights after the last step, whatever epoch scored best
    final = torch.load(tmp_path / "run" / "final.pt", weights_only=True)
    last = torch.load(tmp_path / "run" / "last.pt", weights_only=True)["model"]
    assert all(torch.equal(final["state_dict"][k], last[k]) for k in last)
    assert final["meta"]["epoch"] == 2
    assert summary["final_accuracy"] == final["meta"]["accuracy"]
    assert summary["final_test"]["images"] == summary["test_images"] == 2


def test_unknown_schedule_is_an_input_error(jacquard_dir: Path, tmp_path: Path):
    from tamp.errors import InputError

    with pytest.raises(InputError, match="unknown schedule"):
        train(_cfg(jacquard_dir, tmp_path / "x", schedule="step"), progress=False)
    assert not (tmp_path / "x").exists()


def test_weights_load_without_running_pickled_code(tmp_path: Path):
    """Weights are read with weights_only=True: a file holding any other object than tensors
    and plain values is refused with one line naming it."""
    from tamp.errors import InputError
    from tamp.grasp.train import read_weights, write_weights

    good = tmp_path / "good.pt"
    write_weights(good, {"model": "ggcnn", "split": {"seed": 1, "fold": None}},
                  {"w": torch.ones(2)})  # fmt: skip
    assert read_weights(good)["meta"]["split"] == {"seed": 1, "fold": None}
    bad = tmp_path / "bad.pt"
    torch.save({"meta": _Oracle.__new__(_Oracle), "state_dict": {}}, bad)
    with pytest.raises(InputError, match=f"{bad}: not a grasp weights file"):
        read_weights(bad)


@pytest.mark.slow
def test_resume_continues_exactly(jacquard_dir: Path, tmp_path: Path):
    # a constant rate, so that a 1-epoch run is the first half of a 2-epoch one (a cosine
    # rate is a function of the step and the run's length, so it resumes exactly as well)
    flat = dict(schedule="constant")
    full = train(_cfg(jacquard_dir, tmp_path / "full", epochs=2, **flat), progress=False)
    train(_cfg(jacquard_dir, tmp_path / "part", epochs=1, **flat), progress=False)
    resumed = train(
        _cfg(jacquard_dir, tmp_path / "part", epochs=2, **flat), resume=True, progress=False
    )
    assert resumed["history"][0] == full["history"][0] | {
        "train_s": resumed["history"][0]["train_s"]
    }
    a = torch.load(tmp_path / "full" / "last.pt", weights_only=True)["model"]
    b = torch.load(tmp_path / "part" / "last.pt", weights_only=True)["model"]
    assert all(torch.equal(a[k], b[k]) for k in a)


@pytest.mark.slow
def test_resume_refuses_a_different_network(jacquard_dir: Path, tmp_path: Path):
    from tamp.errors import InputError

    train(_cfg(jacquard_dir, tmp_path / "run", epochs=1), progress=False)
    before = (tmp_path / "run" / "last.pt").read_bytes()
    for change, what in (
        (dict(fusion="final"), "network"),
        (dict(model_kwargs={"widths": [4, 8, 12]}), "network"),
        (dict(size=48), "network"),
        (dict(seed=1), "split"),
        (dict(val_fraction=0.0), "split"),
    ):
        cfg = _cfg(jacquard_dir, tmp_path / "run", epochs=2, **change)
        with pytest.raises(InputError, match=f"cannot resume a different {what}") as err:
            train(cfg, resume=True, progress=False)
        assert str(tmp_path / "run" / "last.pt") in str(err.value)
    assert (tmp_path / "run" / "last.pt").read_bytes() == before  # nothing half-done


class _Oracle(torch.nn.Module):
    """Returns the ground-truth maps of the sample it is shown (looked up by input)."""

    def __init__(self, dataset, flip_angle: bool = False):
        super().__init__()
        self.table = {}
        for i in range(len(dataset)):
            s = dataset.load(i)
            y = torch.from_numpy(s.y.copy())
            if flip_angle:  # a grasp turned by 90 degrees: cos 2a and sin 2a change sign
                y[1:3] = -y[1:3]
            self.table[s.x.tobytes()] = y

    def forward(self, x):
        return torch.stack([self.table[t.numpy().tobytes()] for t in x])


def test_evaluation_with_oracles(jacquard_dir: Path):
    ds = GraspDataset("jacquard", jacquard_dir, size=48)
    idx = list(range(len(ds)))
    assert evaluate(_Oracle(ds), ds, idx, progress=False).accuracy == 1.0
    assert evaluate(_Oracle(ds, flip_angle=True), ds, idx, progress=False).accuracy == 0.0


class _Scaled(torch.nn.Module):
    """The oracle with every opening width multiplied by ``factor``."""

    def __init__(self, oracle: _Oracle, factor: float):
        super().__init__()
        self.oracle, self.factor = oracle, factor

    def forward(self, x):
        y = self.oracle(x).clone()
        y[:, 3] *= self.factor
        return y


def test_width_error_against_the_ground_truth(jacquard_dir: Path):
    """The width error is measured on the true rectangle under the prediction: zero for the
    oracle, +50 % for an oracle whose widths are 1.5 x, and zero again for that oracle with
    the width calibration fitted on its images."""
    ds = GraspDataset("jacquard", jacquard_dir, size=48)
    idx = list(range(len(ds)))
    exact = evaluate(_Oracle(ds), ds, idx, progress=False).width
    assert exact.count == len(ds) and exact.mean_abs_m is None  # no camera.json here
    # the Q-weighted mean of W reads the exact maps back exactly (a plain blur of W read
    # these 9 px openings 14 % too narrow)
    assert exact.mean_abs_rel < 1e-4
    wide = evaluate(_Scaled(_Oracle(ds), 1.5), ds, idx, progress=False)
    assert wide.width.count == len(ds)
    assert wide.width.mean_rel == pytest.approx(0.5, abs=0.03)
    assert wide.width.mean_abs_px == pytest.approx(0.5 * 12 * 0.75, rel=0.05)  # bars 8 px x 1.5
    calib = fit_width_calibration(_Scaled(_Oracle(ds), 1.5), ds, idx, part="test data")
    assert calib["scale"] == pytest.approx(1 / 1.5, rel=1e-4) and calib["grasps"] == len(ds)
    fixed = evaluate(_Scaled(_Oracle(ds), 1.5), ds, idx, progress=False,
                     width_calibration=calib["scale"])  # fmt: skip
    assert fixed.width.mean_abs_rel < 1e-4
    # a camera gives the error in metres: metres per pixel = depth x crop scale / focal
    for sample in ds.samples:
        prefix = str(sample.grasps)[: -len("_grasps.txt")]
        Path(prefix + "_camera.json").write_text('{"K": [[80, 0, 31.5], [0, 80, 31.5], [0, 0, 1]]}')
    wide_m = evaluate(_Scaled(_Oracle(ds), 1.5), ds, idx, progress=False).width
    # true opening 12 px of the 64 px source at 0.57 m and f = 80 px: 8.55 cm; error half of it
    assert wide_m.mean_abs_m == pytest.approx(0.5 * 12 * 0.57 / 80, rel=0.05)


@pytest.mark.slow
def test_distributed_two_cpu_processes(jacquard_dir: Path, tmp_path: Path):
    cfg = _cfg(jacquard_dir, tmp_path / "ddp", epochs=1, batches_per_epoch=4, device="cpu")
    r0, r1 = train_local_processes(cfg, 2)
    assert r0["world_size"] == r1["world_size"] == 2
    # the two ranks saw different batches but end with the same weights (all-reduce)
    assert r0["checksum"] == r1["checksum"]
    ckpt = torch.load(tmp_path / "ddp" / "last.pt", weights_only=True)
    assert ckpt["epoch"] == 1 and ckpt["history"][0]["val_images"] == 2
