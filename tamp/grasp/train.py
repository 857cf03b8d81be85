"""Training of HRG-Net and the baselines with one code path (§V-A), resumable, optionally DDP.

Loss: smooth L1 on the four maps (GR-ConvNet [57]), Adam. The learning rate follows a
cosine from ``lr`` down to zero over all the steps of the run (``schedule="cosine"``, the
default) or stays at ``lr`` (``"constant"``). One epoch is ``batches_per_epoch`` batches
drawn from the training split (all of it when 0), so every model gets exactly the same
training budget. The dataset is split into train / validation / test parts
(:mod:`tamp.grasp.splits`). After each epoch the model is evaluated on the validation part
(rectangle metric) and a checkpoint is written: ``last.pt`` (model, optimizer, epoch, RNG
states: enough to resume bit-for-bit on the CPU) and ``best.pt`` (the weights of the epoch
most accurate on the validation part). When the run ends the final weights are evaluated once
on the test part and written to ``final.pt``. Nothing is ever chosen by its test score. With
``val_fraction = 0`` there is no validation part, no per-epoch evaluation and no ``best.pt``.

Every weights file records its split (:func:`tamp.grasp.splits.split_record`), so that
``tamp grasp eval`` tests on the same unseen part, and holds only tensors and plain Python
values, so that it loads with ``torch.load(weights_only=True)``.

Under ``torchrun`` (or any launcher that sets ``WORLD_SIZE``/``RANK``) the model is wrapped
in DistributedDataParallel (``gloo`` on CPU, ``nccl`` on GPUs); each rank takes its own
share of every epoch's batches, and only rank 0 evaluates and writes checkpoints.
"""

from __future__ import annotations

import json
import math
import os
import random
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from tamp.grasp.datasets import Augment, GraspDataset
from tamp.grasp.evaluate import evaluate, fit_width_calibration
from tamp.grasp.models import build_model, full_kwargs, parameter_count
from tamp.grasp.networks import DEFAULT_NETWORK, network
from tamp.grasp.splits import SplitSpec, split_record


@dataclass
class TrainConfig:
    dataset: str
    path: str
    model: str = DEFAULT_NETWORK
    input: str = "rgbd"
    out: str = "runs/grasp"
    size: int = 224
    epochs: int = 10
    batch_size: int = 8
    batches_per_epoch: int = 0
    lr: float = 1e-3
    schedule: str = "cosine"
    split: str = "image"
    test_fraction: float = 0.1
    val_fraction: float = 0.1
    fold: int | None = None
    folds: int = 5
    seed: int = 0
    fusion: str = "full"  # HRG-Net only: full, final or none (networks.FUSION_MODES)
    augment: bool = True
    device: str = "auto"
    threads: int = 0
    eval_limit: int = 0
    model_kwargs: dict = field(default_factory=dict)


def split_spec(cfg: TrainConfig) -> SplitSpec:
    return SplitSpec(cfg.split, cfg.seed, cfg.test_fraction, cfg.val_fraction, cfg.fold, cfg.folds)


def model_kwargs(cfg: TrainConfig) -> dict:
    kw = dict(cfg.model_kwargs)
    if network(cfg.model).fusion:
        kw["fusion"] = cfg.fusion
    return kw


def loss_fn(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Sum over the four maps of the smooth L1 loss (GR-ConvNet)."""
    return sum(F.smooth_l1_loss(pred[:, k], target[:, k]) for k in range(4))


SCHEDULES = ("cosine", "constant")


def learning_rate(cfg: TrainConfig, step: int, total: int) -> float:
    """Rate at optimizer step ``step`` of ``total`` (cosine annealing to zero, or constant)."""
    if cfg.schedule == "constant":
        return cfg.lr
    return 0.5 * cfg.lr * (1.0 + math.cos(math.pi * min(step, total) / max(total, 1)))


def _rng_state() -> dict:
    """The RNG states as tensors and plain values (``weights_only`` loads them)."""
    name, keys, pos, has_gauss, cached = np.random.get_state()
    return {
        "torch": torch.get_rng_state(),
        "numpy": [name, torch.from_numpy(keys.astype(np.int64)), pos, has_gauss, cached],
        "python": random.getstate(),
    }


def _set_rng_state(state: dict) -> None:
    torch.set_rng_state(state["torch"])
    name, keys, pos, has_gauss, cached = state["numpy"]
    np.random.set_state((name, keys.numpy().astype(np.uint32), pos, has_gauss, cached))
    random.setstate(state["python"])


def _device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def save_weights(path: Path, model: torch.nn.Module, cfg: TrainConfig, extra: dict) -> None:
    """The deployable file: weights plus what is needed to rebuild the model and the split
    it was trained with (``extra`` holds the split record and the scores)."""
    kwargs = full_kwargs(cfg.model, **model_kwargs(cfg))
    meta = {"model": cfg.model, "input": cfg.input, "size": cfg.size, "kwargs": kwargs}
    write_weights(path, meta | extra, model.state_dict())


def write_weights(path: Path, meta: dict, state_dict: dict) -> None:
    """A weights file: ``{"meta": plain values, "state_dict": tensors}``."""
    state = {k: v.detach().cpu().contiguous() for k, v in state_dict.items()}
    torch.save({"meta": meta, "state_dict": state}, path)


def read_weights(path: str | Path, device: str = "cpu") -> dict:
    """The ``{"meta", "state_dict"}`` of a weights file, loaded with ``weights_only=True``
    (tensors and plain values only: no code in a weights file runs)."""
    from tamp.errors import InputError

    p = Path(path)
    if not p.is_file():
        raise InputError("weights file not found", file=str(p))
    try:
        blob = torch.load(p, map_location=device, weights_only=True)
        blob["meta"], blob["state_dict"]
    except Exception as exc:  # torch.load raises pickle, zip and key errors
        raise InputError(
            f"not a grasp weights file ({type(exc).__name__}: {str(exc)[:200]})", file=str(p)
        ) from None
    return blob


def load_model(path: str | Path, device: str = "cpu") -> tuple[torch.nn.Module, dict]:
    """Rebuild a model from a weights or checkpoint file; returns (model in eval mode, meta)."""
    from tamp.errors import InputError

    p = Path(path)
    blob = read_weights(p, device)
    try:
        meta = blob["meta"]
        model = build_model(meta["model"], meta["input"], **meta["kwargs"])
        model.load_state_dict(blob["state_dict"])
    except Exception as exc:  # key and shape errors
        raise InputError(
            f"not a grasp weights file ({type(exc).__name__}: {str(exc)[:200]})", file=str(p)
        ) from None
    return model.to(device).eval(), meta


NETWORK_FIELDS = ("model", "input", "size", "fusion", "model_kwargs")
SPLIT_FIELDS = ("dataset", "split", "test_fraction", "val_fraction", "fold", "folds", "seed")


def _check_same_network(saved: dict, cfg: TrainConfig, path: Path) -> None:
    """--resume continues the run in ``path`` only with the network it was started with."""
    from tamp.errors import InputError

    now = asdict(cfg)
    for fields, what in ((NETWORK_FIELDS, "network"), (SPLIT_FIELDS, "split")):
        changed = [k for k in fields if saved.get(k) != now[k]]
        if changed:
            diff = ", ".join(f"{k} {saved.get(k)!r} -> {now[k]!r}" for k in changed)
            raise InputError(f"cannot resume a different {what} ({diff})", file=str(path))


def train(
    cfg: TrainConfig,
    *,
    resume: bool = False,
    progress: bool = True,
    log: Callable[[str], None] | None = None,
) -> dict:
    """Train as configured; returns a summary (accuracies per epoch, best, timings)."""
    from tqdm import tqdm

    from tamp.errors import InputError

    if cfg.schedule not in SCHEDULES:
        raise InputError(f"unknown schedule {cfg.schedule!r}; expected one of {list(SCHEDULES)}")
    distributed = int(os.environ.get("WORLD_SIZE", "1")) > 1
    rank = int(os.environ.get("RANK", "0"))
    world = int(os.environ.get("WORLD_SIZE", "1"))
    device = _device(cfg.device)
    if distributed:
        import torch.distributed as dist

        if not dist.is_initialized():
            dist.init_process_group("nccl" if device.type == "cuda" else "gloo")
        if device.type == "cuda":
            device = torch.device("cuda", int(os.environ.get("LOCAL_RANK", "0")))
            torch.cuda.set_device(device)
    if cfg.threads:
        torch.set_num_threads(cfg.threads)
    log = log or (lambda m: None)

    out = Path(cfg.out)
    if rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    dataset = GraspDataset(cfg.dataset, cfg.path, cfg.size, cfg.input)
    spec = split_spec(cfg)
    split = dataset.split(spec)
    record = {"split": split_record(dataset, spec, split)}
    train_idx, val_idx, test_idx = split.train, split.val, split.test
    if cfg.eval_limit:
        val_idx, test_idx = val_idx[: cfg.eval_limit], test_idx[: cfg.eval_limit]

    torch.manual_seed(cfg.seed)
    np.random.seed(cfg.seed)
    random.seed(cfg.seed)
    # channels-last (NHWC) is what oneDNN's CPU convolutions run fastest on: about 1.4x per
    # training step for HRG-Net, whose 8-channel full-resolution maps suit NCHW worst
    model = build_model(cfg.model, cfg.input, **model_kwargs(cfg))
    model = model.to(device, memory_format=torch.channels_last)
    optimizer = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    history: list[dict] = []
    start_epoch = 0
    best = -1.0
    last = out / "last.pt"
    if resume and last.is_file():
        ckpt = torch.load(last, map_location=device, weights_only=True)
        _check_same_network(ckpt["config"], cfg, last)
        model.load_state_dict(ckpt["model"])
        optimizer.load_state_dict(ckpt["optimizer"])
        start_epoch = ckpt["epoch"]
        history = ckpt["history"]
        best = ckpt["best"]
        _set_rng_state(ckpt["rng"])
        log(f"resumed from {last} at epoch {start_epoch} ({cfg.schedule} schedule, lr {cfg.lr:g})")
    net = model
    if distributed:
        from torch.nn.parallel import DistributedDataParallel

        net = DistributedDataParallel(model, device_ids=[device] if device.type == "cuda" else None)

    aug = Augment() if cfg.augment else None
    per_epoch = cfg.batches_per_epoch or max(1, len(train_idx) // cfg.batch_size)
    per_rank = max(1, per_epoch // world)
    for epoch in range(start_epoch, cfg.epochs):
        net.train()
        # every rank draws the same permutation, then takes its own slice of it
        rng = np.random.default_rng((cfg.seed, epoch))
        order = rng.permutation(np.resize(rng.permutation(train_idx), per_epoch * cfg.batch_size))
        mine = order.reshape(per_epoch, cfg.batch_size)[rank::world][:per_rank]
        aug_rng = np.random.default_rng((cfg.seed, epoch, rank, 1))
        t0 = time.perf_counter()
        total = 0.0
        bar = tqdm(mine, desc=f"epoch {epoch + 1}/{cfg.epochs}", disable=not progress or rank)
        for b, batch in enumerate(bar):
            lr = learning_rate(cfg, epoch * per_rank + b, cfg.epochs * per_rank)
            for group in optimizer.param_groups:
                group["lr"] = lr
            samples = [dataset.load(int(i), aug, aug_rng) for i in batch]
            x = torch.from_numpy(np.stack([s.x for s in samples]))
            x = x.to(device, memory_format=torch.channels_last)
            y = torch.from_numpy(np.stack([s.y for s in samples])).to(device)
            loss = loss_fn(net(x), y)
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            optimizer.step()
            total += float(loss.detach())
            bar.set_postfix(loss=f"{float(loss.detach()):.4f}")
        train_s = time.perf_counter() - t0
        entry = {"epoch": epoch + 1, "lr": lr, "loss": total / len(mine), "train_s": train_s}
        if rank == 0:
            if val_idx:  # the epoch is chosen on the validation part, never on the test part
                result = evaluate(model, dataset, val_idx, device=device, progress=False)
                entry |= {"val_accuracy": result.accuracy, "val_images": result.images}
                if result.accuracy > best:
                    best = result.accuracy
                    save_weights(out / "best.pt", model, cfg,
                                 record | {"val_accuracy": best, "epoch": epoch + 1})  # fmt: skip
            history.append(entry)
            torch.save(
                {
                    "model": model.state_dict(),
                    "optimizer": optimizer.state_dict(),
                    "epoch": epoch + 1,
                    "history": history,
                    "best": best,
                    "rng": _rng_state(),
                    "config": asdict(cfg),
                },
                last,
            )
            log(json.dumps(entry))
        if distributed:
            torch.distributed.barrier()
    final = None
    if rank == 0 and history:
        part, calib_idx = calibration_images(train_idx, val_idx)
        if (out / "best.pt").is_file():  # the best epoch gets its own calibration
            best_model, best_meta = load_model(out / "best.pt", str(device))
            calib = fit_width_calibration(best_model, dataset, calib_idx, part=part, device=device)
            write_weights(
                out / "best.pt",
                best_meta | {"width_calibration": calib},
                best_model.state_dict(),
            )
        calib = fit_width_calibration(model, dataset, calib_idx, part=part, device=device)
        result = evaluate(
            model, dataset, test_idx, device=device, progress=False,
            width_calibration=calib["scale"],
        )  # fmt: skip
        final = result.as_dict()
        save_weights(
            out / "final.pt",
            model,
            cfg,
            record
            | {
                "accuracy": result.accuracy,
                "epoch": history[-1]["epoch"],
                "width_calibration": calib,
                "test": final,
            },
        )
    summary = {
        "config": asdict(cfg),
        "parameters": parameter_count(model),
        "train_images": len(train_idx),
        "val_images": len(val_idx),
        "test_images": len(test_idx),
        "split": record["split"],
        "history": history,
        # only rank 0 evaluates; the best epoch is the best on the validation part
        "best_val_accuracy": best if rank == 0 and val_idx else None,
        "best_epoch": next((h["epoch"] for h in history if h.get("val_accuracy") == best), None),
        "final_accuracy": final["accuracy"] if final else None,  # of final.pt, on the test part
        "final_test": final,
        "world_size": world,
        # sum of all weights: equal on every rank after DistributedDataParallel training
        "checksum": float(sum(p.detach().double().sum() for p in model.parameters())),
    }
    if rank == 0:
        (out / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary


def record_split_and_calibrate(
    weights: str | Path, out: str | Path, dataset: GraspDataset, spec: SplitSpec
) -> dict:
    """Write ``weights`` to ``out`` with the split ``spec`` of ``dataset`` they were trained
    with recorded, a width calibration fitted on that split (validation part, else training
    images) and the accuracy re-measured on its test part; returns the new meta. For weights
    made before files recorded their split: the caller vouches for ``spec``."""
    model, meta = load_model(weights)
    split = dataset.split(spec)
    part, calib_idx = calibration_images(split.train, split.val)
    calib = fit_width_calibration(model, dataset, calib_idx, part=part)
    result = evaluate(model, dataset, split.test, progress=False, width_calibration=calib["scale"])
    meta = meta | {
        "split": split_record(dataset, spec, split),
        "width_calibration": calib,
        "accuracy": result.accuracy,
        "test": result.as_dict(),
    }
    write_weights(Path(out), meta, model.state_dict())
    return meta


#: at most this many training images fit the width calibration when there is no validation part
CALIBRATION_IMAGES = 1000


def calibration_images(train_idx: list[int], val_idx: list[int]) -> tuple[str, list[int]]:
    """Where the width calibration is fitted: the validation part, or else every k-th
    training image (at most :data:`CALIBRATION_IMAGES`, unaugmented); never the test part."""
    if val_idx:
        return "validation", list(val_idx)
    step = max(1, math.ceil(len(train_idx) / CALIBRATION_IMAGES))
    return f"training (every {step})", list(train_idx[::step])


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _local_rank_entry(rank: int, world: int, port: int, cfg: TrainConfig, resume: bool) -> None:
    os.environ.update(
        MASTER_ADDR="127.0.0.1",
        MASTER_PORT=str(port),
        RANK=str(rank),
        WORLD_SIZE=str(world),
        LOCAL_RANK=str(rank),
    )
    import torch.distributed as dist

    summary = train(cfg, resume=resume, progress=rank == 0)
    (Path(cfg.out) / f"rank{rank}.json").write_text(json.dumps(summary))
    dist.barrier()
    dist.destroy_process_group()


def train_local_processes(cfg: TrainConfig, nprocs: int, *, resume: bool = False) -> list[dict]:
    """DistributedDataParallel on this machine without torchrun: ``nprocs`` processes
    (gloo on the CPU) on 127.0.0.1 and a free port; returns every rank's summary."""
    import torch.multiprocessing as mp

    Path(cfg.out).mkdir(parents=True, exist_ok=True)
    mp.spawn(_local_rank_entry, args=(nprocs, _free_port(), cfg, resume), nprocs=nprocs)
    return [json.loads((Path(cfg.out) / f"rank{r}.json").read_text()) for r in range(nprocs)]
