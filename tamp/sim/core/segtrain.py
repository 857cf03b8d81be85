"""Training and evaluation of the object detector (torch).

`train` fits `tamp.sim.core.segnet.SegNet` to the training scenes of a set rendered by
`tamp.sim.core.segdata.generate`: per-pixel cross-entropy weighted per class (the square
root of the median class frequency over the class's, clipped to [0.2, 5]: objects are a few
per cent of the pixels), AdamW with a linear warm-up and a cosine decay, batches of random
views cropped at random (`TrainSettings.crop`) with horizontal flips, colour jitter and
depth noise. A GPU is used when present
(``device="auto"``), never required. The weights file records the classes, the network's
width, the image size and the data set's object-wise split (`DatasetInfo.split_record`).

`evaluate` scores weights (of either detector, `tamp.sim.core.detector.Detector.load`) on the
held-out (test) scenes as a detector is scored: per-view counting accuracy per class (what
LOTS consumes, Zhou et al., IEEE T-ASE 2023, §III-B), mask IoU of matched instances and
per-class pixel IoU (of the detections' masks), an instance confusion matrix and what became
of the task-class instances, false positives per view, and CPU time per frame on one thread
(the whole `detect` call; process time, so a busy machine does not inflate it). An object
held in the gripper is not counted (`true_instances`): the detector does not report it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from tamp.sim.core.instances import IN_HAND_DEPTH
from tamp.sim.core.segdata import (
    HAND,
    STUFF,
    TABLE,
    UNKNOWN,
    DatasetInfo,
    read_info,
    read_scene,
    scene_file,
    view_fixtures,
)
from tamp.sim.core.segnet import SegNet, parameter_count, prepare, save

#: a predicted instance matches a true one at this mask IoU or more
MATCH_IOU = 0.5
#: detected classes that are not task classes
NOT_TASK = (UNKNOWN, "hand")


@dataclass(frozen=True)
class TrainSettings:
    steps: int = 3000
    batch_size: int = 16
    lr: float = 3e-3
    width: int = 16
    device: str = "auto"
    threads: int = 0
    seed: int = 0
    warmup: int = 100
    weight_decay: float = 1e-4
    #: a weights file to start from (its classes and width must be the data's and these)
    init: str | None = None
    #: training crops (width, height) cut at random from each view: half the pixels of a
    #: 160 x 90 view per sample, twice the views per second (the network is convolutional)
    crop: tuple[int, int] = (112, 64)


def _device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def load_views(data: str | Path, scenes) -> dict[str, np.ndarray]:
    """The views of ``scenes`` stacked: rgb, depth (float16), cls."""
    rgb, depth, cls = [], [], []
    for i in scenes:
        s = read_scene(scene_file(Path(data), i))
        rgb.append(s["rgb"])
        depth.append(s["depth"].astype(np.float16))
        cls.append(s["cls"])
    return {"rgb": np.concatenate(rgb), "depth": np.concatenate(depth), "cls": np.concatenate(cls)}


def class_weights(cls: np.ndarray, n: int) -> np.ndarray:
    """sqrt(median frequency / frequency) per class, clipped to [0.2, 5] (1 if absent)."""
    freq = np.bincount(cls.ravel(), minlength=n).astype(float)
    present = freq > 0
    med = np.median(freq[present])
    w = np.ones(n)
    w[present] = np.clip(np.sqrt(med / freq[present]), 0.2, 5.0)
    return w


def _batch(views, idx, rng: np.random.Generator, crop: tuple[int, int]):
    xs, ys = [], []
    for i in idx:
        h, w = views["cls"][i].shape
        cw, ch = min(crop[0], w), min(crop[1], h)
        u0, v0 = int(rng.integers(w - cw + 1)), int(rng.integers(h - ch + 1))
        sl = (slice(v0, v0 + ch), slice(u0, u0 + cw))
        rgb = views["rgb"][i][sl].astype(np.float32)
        depth = views["depth"][i][sl].astype(np.float32)
        cls = views["cls"][i][sl]
        if rng.random() < 0.5:
            rgb, depth, cls = rgb[:, ::-1], depth[:, ::-1], cls[:, ::-1]
        gain = rng.uniform(0.75, 1.25)
        bias = rng.uniform(-20, 20, 3)
        rgb = np.clip(rgb * gain + bias, 0, 255)
        valid = depth > 0
        depth = np.where(valid, depth + rng.normal(0, 0.002, depth.shape), 0.0)
        xs.append(prepare(rgb.astype(np.uint8), depth))
        ys.append(np.ascontiguousarray(cls))
    return torch.from_numpy(np.stack(xs)), torch.from_numpy(np.stack(ys).astype(np.int64))


def begin_training(
    data: str | Path, out: str | Path, threads: int, seed: int
) -> tuple[DatasetInfo, Path, np.random.Generator]:
    """What every detector training starts with (`train`, `tamp.sim.core.croptrain.train`):
    the rendered set's description, the output folder (made), torch's threads (0: its
    default) and seed set, and the run's random generator (seeded alike)."""
    info = read_info(data)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if threads > 0:
        torch.set_num_threads(threads)
    torch.manual_seed(seed)
    return info, out, np.random.default_rng(seed)


def train(
    data: str | Path,
    out: str | Path,
    settings: TrainSettings = TrainSettings(),
    *,
    log: Callable[[str], None] | None = None,
) -> dict:
    """Train on the training scenes of ``data``; writes ``out/final.pt``; returns a summary."""
    info, out, rng = begin_training(data, out, settings.threads, settings.seed)
    device = _device(settings.device)
    views = load_views(data, info.train)
    n = len(info.classes)
    weights = torch.tensor(class_weights(views["cls"], n), dtype=torch.float32, device=device)
    model = SegNet(n, settings.width)
    if settings.init:
        from tamp.errors import InputError
        from tamp.sim.core.segnet import load

        start, start_meta = load(settings.init)
        if (
            list(start_meta["classes"]) != list(info.classes)
            or start_meta["width"] != settings.width
        ):
            raise InputError("--init: other classes or width than this run's", file=settings.init)
        model.load_state_dict(start.state_dict())
    model = model.to(device)
    opt = torch.optim.AdamW(model.parameters(), lr=settings.lr, weight_decay=settings.weight_decay)
    t0 = time.perf_counter()
    cpu0 = time.process_time()
    model.train()
    total = len(views["cls"])
    running = 0.0
    for step in range(settings.steps):
        lr = settings.lr * min(1.0, (step + 1) / settings.warmup)
        lr *= 0.5 * (1 + math.cos(math.pi * step / settings.steps))
        for g in opt.param_groups:
            g["lr"] = lr
        x, y = _batch(views, rng.integers(total, size=settings.batch_size), rng, settings.crop)
        loss = F.cross_entropy(model(x.to(device)), y.to(device), weight=weights)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        running = 0.98 * running + 0.02 * loss.item() if step else loss.item()
        if log and (step + 1) % 100 == 0:
            log(f"step {step + 1}/{settings.steps}: loss {running:.3f}, lr {lr:.2e}")
    seconds = time.perf_counter() - t0
    model.eval()
    h, w = views["cls"].shape[1:]
    meta = {
        "kind": "detector",
        "classes": list(info.classes),
        "width": settings.width,
        "size": [int(w), int(h)],
        "split": info.split_record(),
        "training": asdict(settings) | {"device": str(device), "views": int(total)},
        "seconds": round(seconds, 1),
        "cpu_seconds": round(time.process_time() - cpu0, 1),
        "parameters": parameter_count(model),
    }
    path = out / "final.pt"
    save(path, model.cpu(), meta)
    return {
        "weights": str(path),
        "steps": settings.steps,
        "seconds": round(seconds, 1),
        "cpu_seconds": meta["cpu_seconds"],
        "device": str(device),
        "parameters": meta["parameters"],
        "final_loss": round(running, 4),
        "train_views": int(total),
        "split": meta["split"],
    }


# --- evaluation -------------------------------------------------------------------------


def true_instances(
    inst: np.ndarray,
    inst_cls: np.ndarray,
    min_pixels: int,
    depth: np.ndarray | None = None,
    names: Sequence[str] | None = None,
) -> tuple[list[tuple[int, np.ndarray]], list[np.ndarray]]:
    """(the view's instances that count: (class index, mask)), (the masks of those that do
    not: a detection on them is not a false positive, missing them is no miss): an instance
    counts when it has ``min_pixels`` or more and, given ``depth`` and the class ``names``,
    is not held in the gripper (median depth under `IN_HAND_DEPTH` and not the person's
    hand: the detector does not report the held object, perception knows it)."""
    big, small = [], []
    for k in np.unique(inst):
        if k == 0 or inst_cls[k] < len(STUFF):
            continue
        m = inst == k
        held = False
        if depth is not None and names is not None and names[inst_cls[k]] != HAND:
            d = depth[m]
            d = d[np.isfinite(d) & (d > 0)]
            held = d.size > 0 and float(np.median(d)) < IN_HAND_DEPTH
        if m.sum() >= min_pixels and not held:
            big.append((int(inst_cls[k]), m))
        else:
            small.append(m)
    return big, small


def predicted_map(found, names: Sequence[str], shape: tuple[int, int]) -> np.ndarray:
    """A class map of detections (``table`` where none lies) for the per-class pixel IoU."""
    out = np.full(shape, names.index(TABLE), np.int64)
    for d in found:
        out[d.mask] = names.index(d.cls)
    return out


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    inter = np.logical_and(a, b).sum()
    return float(inter / max(1, np.logical_or(a, b).sum()))


def _mostly_on(mask: np.ndarray, other: np.ndarray) -> bool:
    """Whether more than half of ``mask`` lies on ``other``."""
    return bool((mask & other).sum() > 0.5 * mask.sum())


def match(
    truth: list[tuple[int, np.ndarray]], masks: list[np.ndarray]
) -> list[tuple[int, int, float]]:
    """Greedy one-to-one matches (true index, predicted index, IoU) at IoU >= `MATCH_IOU`."""
    pairs = sorted(
        ((_iou(t[1], m), i, j) for i, t in enumerate(truth) for j, m in enumerate(masks)),
        reverse=True,
    )
    used_t, used_p, out = set(), set(), []
    for iou, i, j in pairs:
        if iou < MATCH_IOU:
            break
        if i in used_t or j in used_p:
            continue
        used_t.add(i)
        used_p.add(j)
        out.append((i, j, iou))
    return out


class Tally:
    """The running scores of `evaluate` over views (see `score_view`)."""

    def __init__(self, names: list[str]):
        self.names = names
        n = len(names)
        self.objects = [i for i, c in enumerate(names) if c not in STUFF]
        # rows: true class, then "none" (false positives); columns: predicted, then "missed"
        self.confusion = np.zeros((n + 1, n + 1), int)
        self.pixels = np.zeros((n, n), np.int64)
        self.counts = {names[c]: [0, 0] for c in self.objects}
        self.views = 0
        self.all_right = 0
        self.ious: list[float] = []
        self.false_positives = 0
        self.task_false_positives = 0
        self.unknown = 0
        self.unknown_as_task = 0


def score_view(
    tally: Tally,
    found,
    truth: list[tuple[int, np.ndarray]],
    small: list[np.ndarray],
    class_map: np.ndarray | None = None,
    predicted_map: np.ndarray | None = None,
) -> None:
    """Add one view to ``tally``: ``found`` the detections, ``truth`` the true instances
    ((class index, mask), large enough to count), ``small`` the masks of those too small to
    count; optionally the true and predicted class maps for the pixel IoU."""
    names, n = tally.names, len(tally.names)
    tally.views += 1
    if class_map is not None and predicted_map is not None:
        flat = class_map.ravel().astype(np.int64) * n + predicted_map.ravel()
        tally.pixels += np.bincount(flat, minlength=n * n).reshape(n, n)
    pred = [names.index(d.cls) for d in found]
    pairs = match(truth, [d.mask for d in found])
    matched_t = {i for i, _, _ in pairs}
    matched_p = {j for _, j, _ in pairs}
    for i, j, iou in pairs:
        tally.confusion[truth[i][0], pred[j]] += 1
        if truth[i][0] == pred[j]:
            tally.ious.append(iou)
    for i, (c, m) in enumerate(truth):
        if i not in matched_t:
            tally.confusion[c, n] += 1
        if names[c] == UNKNOWN:
            tally.unknown += 1
            if any(d.cls not in NOT_TASK and _mostly_on(d.mask, m) for d in found):
                tally.unknown_as_task += 1
    for j, d in enumerate(found):
        if j in matched_p or any(_mostly_on(d.mask, m) for m in small):
            continue  # matched, or on an object too small to count
        tally.confusion[n, pred[j]] += 1
        tally.false_positives += 1
        tally.task_false_positives += int(d.cls not in NOT_TASK)
    right = True
    for c in tally.objects:
        t = sum(1 for k, _ in truth if k == c)
        p = sum(1 for k in pred if k == c)
        if t or p:
            tally.counts[names[c]][1] += 1
            tally.counts[names[c]][0] += int(t == p)
        right &= t == p
    tally.all_right += int(right)


def _task_outcomes(tally: Tally) -> dict:
    """What became of the true task-class instances (rows of the confusion matrix): found
    with their class, reported ``unknown`` or ``hand``, given another task class, missed."""
    names, m = tally.names, tally.confusion
    task = [c for c in tally.objects if names[c] not in NOT_TASK]
    other = [c for c in tally.objects if names[c] in NOT_TASK]
    total = int(m[task].sum())
    right = int(sum(m[c, c] for c in task))
    wrong = int(sum(m[c, k] for c in task for k in task if k != c))
    return {
        "total": total,
        "right_class": right,
        "unknown_or_hand": int(m[np.ix_(task, other)].sum()),
        "other_task_class": wrong,
        "other_task_class_share": round(wrong / total, 4) if total else None,
        "missed": int(m[task, -1].sum()),
    }


def report(tally: Tally) -> dict:
    """The scores of a tally (JSON-ready)."""
    names, views = tally.names, max(1, tally.views)
    inter = np.diag(tally.pixels)
    union = tally.pixels.sum(0) + tally.pixels.sum(1) - inter
    return {
        "views": tally.views,
        "counting_accuracy": {
            k: {"correct": a, "views": b, "accuracy": round(a / b, 4) if b else None}
            for k, (a, b) in tally.counts.items()
        },
        "views_all_counts_right": round(tally.all_right / views, 4),
        "mask_iou_matched": round(float(np.mean(tally.ious)), 4) if tally.ious else None,
        "matched_instances": len(tally.ious),
        "pixel_iou": {
            names[c]: round(float(inter[c] / union[c]), 4) if union[c] else None
            for c in range(len(names))
        },
        "confusion": {
            "rows": names + ["none"],
            "columns": names + ["missed"],
            "matrix": tally.confusion.tolist(),
        },
        "task_instances": _task_outcomes(tally),
        "false_positives_per_view": round(tally.false_positives / views, 4),
        "task_class_false_positives_per_view": round(tally.task_false_positives / views, 4),
        "unknown_objects": tally.unknown,
        "unknown_reported_as_task_class": tally.unknown_as_task,
    }


def evaluate(
    weights: str | Path,
    data: str | Path,
    *,
    max_views: int = 0,
    detector=None,
    scenes: Sequence[int] | None = None,
) -> dict:
    """Score ``weights`` on the test scenes of ``data`` (module docstring; ``scenes``: these
    scene indices instead, e.g. training scenes held back from a fit); a JSON-ready dict."""
    from tamp.errors import InputError
    from tamp.sim.core.detector import Detector

    info = read_info(data)
    det = detector or Detector.load(weights)
    names = list(det.classes)
    if names != list(info.classes):
        raise InputError(
            f"the weights' classes {names} are not the data set's {list(info.classes)}",
            file=str(weights),
        )
    record = info.split_record()
    trained = det.meta.get("split", {})
    note = ""
    if (
        trained.get("seed") != record["seed"]
        or trained.get("test_fraction") != record["test_fraction"]
    ):
        note = "the weights were trained with another split seed or test share than this set's"
    tally = Tally(names)
    times: list[float] = []

    def known(scene: dict, v: int, intr) -> dict:
        """What the cell gives the proposal detector of this view (`view_fixtures`: a tray,
        a known floor); a segmentation network takes none."""
        if not isinstance(det, Detector):
            return {}
        return view_fixtures(scene, scene["depth"][v], intr, scene["X_WC"][v])

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        for s in info.test if scenes is None else scenes:
            scene = read_scene(scene_file(Path(data), s))
            K = scene["K"]
            intr = (K[0, 0], K[1, 1], K[0, 2], K[1, 2])
            for v in range(len(scene["rgb"])):
                if max_views and tally.views >= max_views:
                    break
                rgb, depth = scene["rgb"][v], scene["depth"][v]
                t0 = time.process_time()
                found = det.detect(rgb, depth, intr, scene["X_WC"][v], **known(scene, v, intr))
                times.append(time.process_time() - t0)
                truth, small = true_instances(
                    scene["inst"][v], scene["inst_cls"][v], det.min_pixels, depth, names
                )
                score_view(tally, found, truth, small, scene["cls"][v],
                           predicted_map(found, names, depth.shape))  # fmt: skip
    finally:
        torch.set_num_threads(threads)
    return {
        "weights": str(weights),
        "data": str(data),
        "test_scenes": len(info.test),
        "resolution": list(det.size),
        "split": record,
        "note": note,
        **report(tally),
        "cpu_ms_per_frame_1_thread": {
            "median": round(1000 * float(np.median(times)), 2) if times else None,
            "p90": round(1000 * float(np.percentile(times, 90)), 2) if times else None,
        },
    }


def format_report(r: dict) -> str:
    """The evaluation as text: one line per class, then the totals."""
    lines = [
        f"{r['views']} held-out views ({r['test_scenes']} scenes), network at "
        f"{r['resolution'][0]}x{r['resolution'][1]}",
        f"{'class':<13} {'count acc':>9} {'views':>6} {'pixel IoU':>9}",
    ]
    for k, c in r["counting_accuracy"].items():
        acc = "-" if c["accuracy"] is None else f"{100 * c['accuracy']:.1f} %"
        iou = r["pixel_iou"].get(k)
        lines.append(f"{k:<13} {acc:>9} {c['views']:>6} {'-' if iou is None else f'{iou:.3f}':>9}")
    t = r["cpu_ms_per_frame_1_thread"]
    lines += [
        f"views with every count right: {100 * r['views_all_counts_right']:.1f} %",
        f"mask IoU (matched, same class): {r['mask_iou_matched']}",
        f"false positives per view: {r['false_positives_per_view']} "
        f"(task classes: {r['task_class_false_positives_per_view']})",
        "task-class instances: {right_class} of {total} with their class, {unknown_or_hand} "
        "unknown or hand, {other_task_class} another task class, {missed} missed".format(
            **r["task_instances"]
        ),
        f"unknown objects reported as a task class: {r['unknown_reported_as_task_class']} "
        f"of {r['unknown_objects']}",
        f"CPU per frame, one thread: median {t['median']} ms, p90 {t['p90']} ms",
    ]
    if r.get("note"):
        lines.append(f"note: {r['note']}")
    return "\n".join(lines)
