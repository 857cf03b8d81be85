"""Training of the detector's proposal classifier (`tamp.sim.core.cropnet`, torch).

Samples: the instance proposals (`tamp.sim.core.instances.proposals`) of every view of the
training scenes of a set rendered by ``tamp detect render``, exactly as the detector makes
them (in a view of the tray with its floor as the plane and its walls left out, as the cell
gives them at run time: `segdata.view_fixtures`), labelled from the renders' instance images
(`label_proposal`): the class of the one object that fills it, ``several`` when two or more
objects each have 30 % of their pixels in it (and then its finer split, as the detector makes
it, adds samples too), ``none`` when less than half of it is an object. The held-out (test)
scenes are never read.

Training: cross-entropy weighted per output (square root of the median count over the
output's, clipped to [0.2, 5]: ``several`` and the rarer classes would otherwise be
drowned), AdamW with a cosine decay, batches of crops turned by a random multiple of 90
degrees and flipped (a view from above has no up), with colour gain and offset jitter.
Each proposal of the fit gives `TrainSettings.copies` crops: the detector's window and
jittered ones. A tenth of the training scenes (`TrainSettings.val_fraction`, drawn from the
seed) is kept out of the fit; on them the ``unknown`` threshold is chosen (`choose_threshold`)
and the classifier is scored. The sizes each class spans in the fit (`size_ranges`) are the
size gate (`cropnet.size_gate`). Fine-tuning (`TrainSettings.init`) starts from earlier
weights of the same outputs and keeps their size gate widened by the new fit's (`widest`),
so weights that learn stacks and trays from a new set still accept what the old set showed.
`TrainSettings.unknown_below` records a given threshold instead of the chosen one (the chosen
one is kept in ``meta["held_back"]["chosen"]``).
The weights file records the outputs, the threshold, the
sizes, the split (`DatasetInfo.split_record`) and the CPU time.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from tamp.sim.core import cropnet
from tamp.sim.core.instances import (
    MIN_PIXELS,
    backproject_mask,
    proposals,
    split_several,
)
from tamp.sim.core.segdata import STUFF, UNKNOWN, read_scene, scene_file, view_fixtures
from tamp.sim.core.segtrain import begin_training

#: an object belongs to a proposal when this share of its pixels lies in it
MEMBER_SHARE = 0.3
#: a proposal is an object's when this share of its pixels are the object's
OWN_SHARE = 0.5


@dataclass(frozen=True)
class TrainSettings:
    epochs: int = 18
    batch_size: int = 128
    lr: float = 3e-3
    width: int = 16
    threads: int = 0
    seed: int = 0
    weight_decay: float = 1e-4
    #: the share of the training scenes kept out of the fit (threshold and scores)
    val_fraction: float = 0.1
    #: crops per proposal in the fit (the detector's window, then jittered ones)
    copies: int = 2
    #: start from these weights (fine-tuning: same outputs and width); the size gate then
    #: spans both the start's sizes and the new fit's
    init: str | None = None
    #: the ``unknown`` threshold to record instead of the one `choose_threshold` picks
    unknown_below: float | None = None


def label_proposal(mask: np.ndarray, inst: np.ndarray, inst_cls: np.ndarray, outputs) -> int:
    """The output index a proposal should get (module docstring): ``inst`` the view's
    instance ids, ``inst_cls`` the data-set class of each id, ``outputs`` the classifier's
    output names (objects first, in the data set's class order after the stuff classes)."""
    ids, inside = np.unique(inst[mask], return_counts=True)
    sizes = np.bincount(inst.ravel(), minlength=int(ids.max()) + 1)
    members = [
        k
        for k, n in zip(ids, inside, strict=True)
        if k and sizes[k] >= MIN_PIXELS and n >= MEMBER_SHARE * sizes[k]
    ]
    if len(members) >= 2:
        return outputs.index(cropnet.SEVERAL)
    obj = [(n, k) for k, n in zip(ids, inside, strict=True) if k]
    if not obj:
        return outputs.index(cropnet.NONE)
    n, k = max(obj)
    if n < OWN_SHARE * mask.sum():
        return outputs.index(cropnet.NONE)
    return int(inst_cls[k]) - len(STUFF)


def view_samples(
    rgb, depth, inst, inst_cls, intrinsics, X_WC, outputs, copies: int = 1, rng=None, known=None
) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """(crop, features, label) of every proposal of one view, and of the finer split of
    those labelled ``several`` (module docstring); ``copies`` crops of each, the first as
    the detector cuts it, the others with the window's margin (1.1-1.5) and centre (up to a
    tenth of its side) drawn from ``rng``. ``known``: the view's fixtures as the cell gives
    them at run time (`segdata.view_fixtures`: a tray's floor as the plane, its walls
    excluded)."""
    depth = np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)
    prop = proposals(depth, intrinsics, X_WC, **(known or {}))
    several = outputs.index(cropnet.SEVERAL)
    out = []
    for m in prop.masks:
        masks = [m]
        label = label_proposal(m, inst, inst_cls, outputs)
        if label == several:
            parts, _ = split_several(m, depth, prop.heights)
            masks += parts if len(parts) > 1 else []
        for part in masks:
            pts = backproject_mask(part, depth, intrinsics, X_WC)
            y = label if part is m else label_proposal(part, inst, inst_cls, outputs)
            for c in range(copies):
                window = {}
                if c:
                    window = {"margin": float(rng.uniform(1.1, 1.5)),
                              "shift": tuple(rng.uniform(-0.1, 0.1, 2))}  # fmt: skip
                x, f = cropnet.crop_input(rgb, prop.heights, depth, part, pts, **window)
                out.append((x, f, y))
    return out


def collect(data: str | Path, scenes, outputs, copies: int = 1, seed: int = 0) -> dict:
    """The samples of every view of ``scenes`` (`view_samples`, ``copies`` crops of each
    proposal): crops (float16), features, labels, and the scene index of each."""
    rng = np.random.default_rng((seed, 2))
    xs, fs, ys, ss = [], [], [], []
    for i in scenes:
        s = read_scene(scene_file(Path(data), i))
        K = s["K"]
        intr = (K[0, 0], K[1, 1], K[0, 2], K[1, 2])
        for v in range(len(s["rgb"])):
            known = view_fixtures(s, s["depth"][v], intr, s["X_WC"][v])
            for x, f, y in view_samples(
                s["rgb"][v], s["depth"][v], s["inst"][v], s["inst_cls"][v], intr,
                s["X_WC"][v], outputs, copies, rng, known,
            ):  # fmt: skip
                xs.append(x.astype(np.float16))
                fs.append(f)
                ys.append(y)
                ss.append(i)
    return {
        "x": np.stack(xs)
        if xs
        else np.zeros((0, cropnet.IN_CHANNELS, cropnet.CROP, cropnet.CROP), np.float16),
        "f": np.stack(fs).astype(np.float32) if fs else np.zeros((0, cropnet.FEATURES), np.float32),
        "y": np.asarray(ys, np.int64),
        "scene": np.asarray(ss, np.int64),
    }


def output_weights(y: np.ndarray, n: int) -> np.ndarray:
    """sqrt(median count / count) per output, clipped to [0.2, 5] (1 if absent)."""
    freq = np.bincount(y, minlength=n).astype(float)
    present = freq > 0
    w = np.ones(n)
    w[present] = np.clip(np.sqrt(np.median(freq[present]) / freq[present]), 0.2, 5.0)
    return w


def _augment(x: torch.Tensor, rng: np.random.Generator) -> torch.Tensor:
    k = int(rng.integers(4))
    x = torch.rot90(x, k, dims=(2, 3))
    if rng.random() < 0.5:
        x = torch.flip(x, dims=(3,))
    n = x.shape[0]
    gain = torch.from_numpy(rng.uniform(0.75, 1.25, (n, 1, 1, 1)).astype(np.float32))
    bias = torch.from_numpy(rng.uniform(-0.08, 0.08, (n, 3, 1, 1)).astype(np.float32))
    rgb = ((x[:, :3] + 0.5) * gain + bias).clamp(0.0, 1.0) - 0.5
    return torch.cat([rgb, x[:, 3:]], dim=1)


def size_ranges(features: np.ndarray, labels: np.ndarray, outputs) -> dict:
    """Per task class, the sizes its training proposals span (`cropnet.size_gate`): the
    0.5th and 99.5th percentiles of length, width and height (m), the low ones over the
    proposals wholly inside the image (a cut object looks smaller)."""
    out = {}
    for c, name in enumerate(outputs):
        mine = labels == c
        if name in (UNKNOWN, "hand", *_NOT_OBJECT) or mine.sum() < 20:
            continue
        size = features[:, 1:4] / 10.0
        inside = mine & (features[:, 5] == 0)
        low = np.percentile(size[inside], 0.5, axis=0) if inside.sum() >= 20 else np.zeros(3)
        out[name] = {
            "low": [round(float(x), 4) for x in low],
            "high": [round(float(x), 4) for x in np.percentile(size[mine], 99.5, axis=0)],
        }
    return out


def widest(a: dict | None, b: dict) -> dict:
    """The size gate spanning both ``a`` and ``b`` (per class, the lower lows and higher
    highs; a class in one only keeps its own)."""
    out = {k: {"low": list(v["low"]), "high": list(v["high"])} for k, v in (a or {}).items()}
    for name, v in b.items():
        if name not in out:
            out[name] = {"low": list(v["low"]), "high": list(v["high"])}
            continue
        out[name]["low"] = [min(x, y) for x, y in zip(out[name]["low"], v["low"], strict=True)]
        out[name]["high"] = [max(x, y) for x, y in zip(out[name]["high"], v["high"], strict=True)]
    return out


def _start(settings: TrainSettings, outputs: list[str]) -> tuple[cropnet.CropNet, dict]:
    """(the model to train, the meta of the weights it starts from: {} for a fresh one)."""
    if not settings.init:
        return cropnet.CropNet(len(outputs), settings.width), {}
    model, meta = cropnet.load(settings.init)
    if list(meta["outputs"]) != list(outputs) or int(meta["width"]) != settings.width:
        from tamp.errors import InputError

        raise InputError(
            f"--init: outputs {meta['outputs']} width {meta['width']}, this run's "
            f"{outputs} width {settings.width}",
            file=settings.init,
        )
    return model.train(), meta


def choose_threshold(probs: np.ndarray, labels: np.ndarray, outputs) -> float:
    """The ``unknown`` threshold: the probability below which a proposal given a task class
    is reported ``unknown``, chosen on held-back training scenes to maximise the proposals
    named right less three times those given a wrong task class (a wrong class misleads the
    task; ``unknown`` only withholds)."""
    task = [i for i, n in enumerate(outputs) if n not in (UNKNOWN, "hand", *_NOT_OBJECT)]
    unknown = outputs.index(UNKNOWN)
    pred = probs.argmax(axis=1)
    top = probs.max(axis=1)
    best, best_score = 0.5, -math.inf
    for t in np.arange(0.3, 0.96, 0.05):
        named = np.where(np.isin(pred, task) & (top < t), unknown, pred)
        right = int((named == labels).sum())
        wrong = int((np.isin(named, task) & (named != labels)).sum())
        score = right - 3 * wrong
        if score > best_score:
            best, best_score = float(round(t, 2)), score
    return best


_NOT_OBJECT = (cropnet.SEVERAL, cropnet.NONE)


def train(
    data: str | Path,
    out: str | Path,
    settings: TrainSettings = TrainSettings(),
    *,
    log: Callable[[str], None] | None = None,
) -> dict:
    """Train on the training scenes of ``data``; writes ``out/final.pt``; returns a summary."""
    info, out, rng = begin_training(data, out, settings.threads, settings.seed)
    cpu0, t0 = time.process_time(), time.perf_counter()
    names = list(info.classes)
    outputs = cropnet.output_names([n for n in names if n not in STUFF])
    held = np.random.default_rng((settings.seed, 1)).random(info.scenes) < settings.val_fraction
    fit_scenes = [i for i in info.train if not held[i]]
    val_scenes = [i for i in info.train if held[i]]
    samples = collect(data, fit_scenes, outputs, settings.copies, settings.seed)
    fit = np.arange(len(samples["y"]))
    if not len(fit):
        from tamp.errors import InputError

        raise InputError("no object proposals in the training scenes", file=str(data))
    if val_scenes:
        kept = collect(data, val_scenes, outputs)
        samples = {k: np.concatenate([samples[k], kept[k]]) for k in samples}
    val = np.arange(len(samples["y"])) >= len(fit)
    if log:
        log(f"{len(samples['y'])} proposals ({len(fit)} fit, {int(val.sum())} held back) "
            f"in {time.process_time() - cpu0:.0f} s CPU")  # fmt: skip
    n = len(outputs)
    weights = torch.tensor(output_weights(samples["y"][fit], n), dtype=torch.float32)
    model, start = _start(settings, outputs)
    opt = torch.optim.AdamW(model.parameters(), lr=settings.lr, weight_decay=settings.weight_decay)
    x_all = torch.from_numpy(samples["x"])
    f_all = torch.from_numpy(samples["f"])
    y_all = torch.from_numpy(samples["y"])
    per_epoch = max(1, len(fit) // settings.batch_size)
    steps = settings.epochs * per_epoch
    model.train()
    step = 0
    for epoch in range(settings.epochs):
        order = rng.permutation(fit)
        total = 0.0
        for b in range(per_epoch):
            idx = torch.from_numpy(order[b * settings.batch_size : (b + 1) * settings.batch_size])
            lr = settings.lr * 0.5 * (1 + math.cos(math.pi * step / steps))
            for g in opt.param_groups:
                g["lr"] = lr
            x = _augment(x_all[idx].float(), rng)
            loss = F.cross_entropy(model(x, f_all[idx]), y_all[idx], weight=weights)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            total += loss.item()
            step += 1
        if log:
            log(f"epoch {epoch + 1}/{settings.epochs}: loss {total / per_epoch:.3f}")
    model.eval()
    vi = np.flatnonzero(val)
    probs = cropnet.classify(model, samples["x"][vi].astype(np.float32), samples["f"][vi])
    labels = samples["y"][vi]
    chosen = choose_threshold(probs, labels, outputs) if len(vi) else 0.5
    threshold = chosen if settings.unknown_below is None else settings.unknown_below
    accuracy = float((probs.argmax(1) == labels).mean()) if len(vi) else None
    cpu = time.process_time() - cpu0
    meta = {
        "kind": "crop_classifier",
        "classes": names,
        "outputs": outputs,
        "width": settings.width,
        "size": [int(info.config["width"]), int(info.config["height"])],
        "unknown_below": threshold,
        "sizes": widest(
            start.get("sizes"), size_ranges(samples["f"][fit], samples["y"][fit], outputs)
        ),
        "split": info.split_record(),
        "training": asdict(settings) | {"proposals": int(len(fit))},
        "held_back": {"proposals": int(len(vi)), "accuracy": accuracy, "chosen": chosen},
        "seconds": round(time.perf_counter() - t0, 1),
        "cpu_seconds": round(cpu, 1),
        "parameters": sum(p.numel() for p in model.parameters()),
    }
    path = out / "final.pt"
    cropnet.save(path, model, meta)
    return {
        "weights": str(path),
        "epochs": settings.epochs,
        "steps": steps,
        "seconds": meta["seconds"],
        "cpu_seconds": meta["cpu_seconds"],
        "device": "cpu",
        "parameters": meta["parameters"],
        "final_loss": round(total / per_epoch, 4),
        "proposals": int(len(fit)),
        "held_back_accuracy": None if accuracy is None else round(accuracy, 4),
        "unknown_below": threshold,
        "split": meta["split"],
    }
