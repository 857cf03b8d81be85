"""Training: a few steps on tiny data, checkpoints that resume exactly, evaluation with
oracle models, and DistributedDataParallel with two CPU processes (gloo)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch

from tamp.grasp.datasets import GraspDataset
from tamp.grasp.evaluate import evaluate
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
        test_fraction=0.25, threads=1, model_kwargs={"widths": [4, 8]},
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
    assert summary["test_images"] == 2 and summary["train_images"] == 6
    for name in ("last.pt", "best.pt", "final.pt", "summary.json"):
        assert (tmp_path / model / name).is_file()
    net, meta = load_model(tmp_path / model / "best.pt")
    assert meta["model"] == model and meta["size"] == 32
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
    final = torch.load(tmp_path / "run" / "final.pt", weights_only=False)
    last = torch.load(tmp_path / "run" / "last.pt", weights_only=False)["model"]
    assert all(torch.equal(final["state_dict"][k], last[k]) for k in last)
    assert final["meta"]["epoch"] == 2
    assert summary["final_accuracy"] == summary["history"][-1]["accuracy"]


def test_unknown_schedule_is_an_input_error(jacquard_dir: Path, tmp_path: Path):
    from tamp.errors import InputError

    with pytest.raises(InputError, match="unknown schedule"):
        train(_cfg(jacquard_dir, tmp_path / "x", schedule="step"), progress=False)
    assert not (tmp_path / "x").exists()


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
    a = torch.load(tmp_path / "full" / "last.pt", weights_only=False)["model"]
    b = torch.load(tmp_path / "part" / "last.pt", weights_only=False)["model"]
    assert all(torch.equal(a[k], b[k]) for k in a)


@pytest.mark.slow
def test_resume_refuses_a_different_network(jacquard_dir: Path, tmp_path: Path):
    from tamp.errors import InputError

    train(_cfg(jacquard_dir, tmp_path / "run", epochs=1), progress=False)
    before = (tmp_path / "run" / "last.pt").read_bytes()
    for change in (dict(fusion="final"), dict(model_kwargs={"widths": [4, 8, 12]}),
                   dict(size=48)):  # fmt: skip
        cfg = _cfg(jacquard_dir, tmp_path / "run", epochs=2, **change)
        with pytest.raises(InputError, match="cannot resume a different network") as err:
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


@pytest.mark.slow
def test_distributed_two_cpu_processes(jacquard_dir: Path, tmp_path: Path):
    cfg = _cfg(jacquard_dir, tmp_path / "ddp", epochs=1, batches_per_epoch=4, device="cpu")
    r0, r1 = train_local_processes(cfg, 2)
    assert r0["world_size"] == r1["world_size"] == 2
    # the two ranks saw different batches but end with the same weights (all-reduce)
    assert r0["checksum"] == r1["checksum"]
    ckpt = torch.load(tmp_path / "ddp" / "last.pt", weights_only=False)
    assert ckpt["epoch"] == 1 and ckpt["history"][0]["eval_images"] == 2
