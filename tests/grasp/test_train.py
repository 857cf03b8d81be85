"""Training: a few steps on tiny data, checkpoints that resume exactly, evaluation with
oracle models, and DistributedDataParallel with two CPU processes (gloo)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch

from tamp.grasp.datasets import GraspDataset
from tamp.grasp.evaluate import evaluate
from tamp.grasp.train import TrainConfig, load_model, train, train_local_processes


def _cfg(root: Path, out: Path, **kw) -> TrainConfig:
    base = dict(
        dataset="jacquard", path=str(root), model="hrgnet", input="rgbd", out=str(out),
        size=32, epochs=2, batch_size=2, batches_per_epoch=2, split="object",
        test_fraction=0.25, threads=1, model_kwargs={"widths": [4, 8]},
    )  # fmt: skip
    base.update(kw)
    return TrainConfig(**base)


@pytest.mark.parametrize("model", ["hrgnet", "ggcnn", "grconvnet"])
def test_few_steps_write_checkpoints(jacquard_dir: Path, tmp_path: Path, model: str):
    kwargs = {"widths": [4, 8]} if model == "hrgnet" else {}
    if model == "grconvnet":
        kwargs = {"channels": 4}
    summary = train(_cfg(jacquard_dir, tmp_path / model, model=model, model_kwargs=kwargs),
                    progress=False)  # fmt: skip
    assert [h["epoch"] for h in summary["history"]] == [1, 2]
    assert summary["test_images"] == 2 and summary["train_images"] == 6
    for name in ("last.pt", "best.pt", "summary.json"):
        assert (tmp_path / model / name).is_file()
    net, meta = load_model(tmp_path / model / "best.pt")
    assert meta["model"] == model and meta["size"] == 32
    assert json.loads((tmp_path / model / "summary.json").read_text())["parameters"] > 0


def test_resume_continues_exactly(jacquard_dir: Path, tmp_path: Path):
    full = train(_cfg(jacquard_dir, tmp_path / "full", epochs=2), progress=False)
    train(_cfg(jacquard_dir, tmp_path / "part", epochs=1), progress=False)
    resumed = train(_cfg(jacquard_dir, tmp_path / "part", epochs=2), resume=True, progress=False)
    assert resumed["history"][0] == full["history"][0] | {
        "train_s": resumed["history"][0]["train_s"]
    }
    a = torch.load(tmp_path / "full" / "last.pt", weights_only=False)["model"]
    b = torch.load(tmp_path / "part" / "last.pt", weights_only=False)["model"]
    assert all(torch.equal(a[k], b[k]) for k in a)


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


def test_distributed_two_cpu_processes(jacquard_dir: Path, tmp_path: Path):
    cfg = _cfg(jacquard_dir, tmp_path / "ddp", epochs=1, batches_per_epoch=4, device="cpu")
    r0, r1 = train_local_processes(cfg, 2)
    assert r0["world_size"] == r1["world_size"] == 2
    # the two ranks saw different batches but end with the same weights (all-reduce)
    assert r0["checksum"] == r1["checksum"]
    ckpt = torch.load(tmp_path / "ddp" / "last.pt", weights_only=False)
    assert ckpt["epoch"] == 1 and ckpt["history"][0]["eval_images"] == 2
