"""Rectangle-metric evaluation and inference timing (§V-A, Tables I, II, IV).

A prediction is the grasp at the peak of the smoothed quality map; it is correct when its
rectangle has IoU > 0.25 with some ground-truth rectangle and an angle within 30 degrees
of that rectangle's (:func:`tamp.grasp.rect.GraspRect.matches`). Accuracy is the fraction
of test images whose prediction is correct.

Opening width: for every prediction whose centre lies inside a ground-truth rectangle with an
angle within 30 degrees of it (a prediction on a true grasp, whatever its width, which the IoU
would also judge), its width against that rectangle's (the one with the nearest centre): mean
absolute error in pixels, mean absolute and mean signed relative error, and, where the dataset
knows its camera (the synthetic set's ``camera.json``), mean absolute error in metres at the
grasp's depth.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np
import torch

from tamp.grasp.maps import detect_grasps, post_process
from tamp.grasp.rect import ANGLE_THRESHOLD, GraspRect, angle_difference, is_correct


@dataclass
class WidthError:
    """Opening-width error of the predictions on a true grasp (see the module docstring)."""

    count: int = 0
    mean_abs_px: float = float("nan")
    mean_abs_rel: float = float("nan")
    mean_rel: float = float("nan")  # signed: > 0 means too wide
    mean_abs_m: float | None = None  # None without camera information
    metric_count: int = 0

    @staticmethod
    def of(pairs: list[tuple[float, float, float | None]]) -> WidthError:
        """From (predicted px, true px, metres per px or None) of the predictions."""
        if not pairs:
            return WidthError()
        pred = np.array([p for p, _, _ in pairs])
        true = np.array([t for _, t, _ in pairs])
        rel = (pred - true) / true
        metric = [abs(p - t) * m for p, t, m in pairs if m is not None]
        return WidthError(
            len(pairs),
            float(np.mean(np.abs(pred - true))),
            float(np.mean(np.abs(rel))),
            float(np.mean(rel)),
            float(np.mean(metric)) if metric else None,
            len(metric),
        )

    def as_dict(self) -> dict:
        return asdict(self)

    def describe(self) -> str:
        if not self.count:
            return "width: no prediction on a true grasp"
        text = (
            f"width error {self.mean_abs_px:.1f} px, {100 * self.mean_abs_rel:.1f} % "
            f"(bias {100 * self.mean_rel:+.1f} %)"
        )
        if self.mean_abs_m is not None:
            text += f", {100 * self.mean_abs_m:.2f} cm"
        return text + f" over {self.count} grasps"


@dataclass
class EvalResult:
    accuracy: float
    images: int
    correct: int
    per_image: list[bool] = field(default_factory=list)
    width: WidthError = field(default_factory=WidthError)

    def as_dict(self) -> dict:
        return {
            "accuracy": self.accuracy,
            "images": self.images,
            "correct": self.correct,
            "width": self.width.as_dict(),
        }


def width_pair(pred: GraspRect, sample) -> tuple[float, float, float | None] | None:
    """(predicted width, width of the true rectangle under the prediction, metres per pixel
    at the grasp) when ``pred`` lies on a true grasp of ``sample``, else None."""
    c = np.array([pred.x, pred.y])

    def inside(t: GraspRect) -> bool:
        d = c - np.array([t.x, t.y])
        return (
            abs(float(d @ t.direction)) <= t.width / 2
            and abs(float(d @ t.normal)) <= t.height / 2
            and angle_difference(pred.angle, t.angle) <= ANGLE_THRESHOLD + 1e-9
        )

    under = [t for t in sample.rects if inside(t)]
    if not under:
        return None
    truth = min(under, key=lambda t: math.hypot(t.x - pred.x, t.y - pred.y))
    m_per_px = None
    if sample.focal:
        r, c = int(round(truth.y)), int(round(truth.x))
        h, w = sample.depth.shape
        z = float(sample.depth[min(max(r, 0), h - 1), min(max(c, 0), w - 1)])
        m_per_px = z * sample.scale / sample.focal
    return pred.width, truth.width, m_per_px


def predict_maps(model: torch.nn.Module, x: np.ndarray, device="cpu") -> np.ndarray:
    """Raw output maps (N, 4, h, w) of ``model`` for inputs (N, C, h, w)."""
    with torch.inference_mode():
        return model(torch.from_numpy(np.ascontiguousarray(x)).to(device)).float().cpu().numpy()


def grasp_of(maps: np.ndarray, width_calibration: float = 1.0) -> GraspRect:
    """The top grasp read from one (4, h, w) output."""
    q, angle, width = post_process(maps, width_calibration)
    return detect_grasps(q, angle, width, n=1)[0][0]


def _top_grasps(model, dataset, indices, device, batch_size, progress, width_calibration):
    """(sample, top grasp) of every sample ``indices`` (no augmentation)."""
    from tqdm import tqdm

    idx = list(indices)
    for start in tqdm(range(0, len(idx), batch_size), desc="eval", disable=not progress):
        samples = [dataset.load(int(i)) for i in idx[start : start + batch_size]]
        maps = predict_maps(model, np.stack([s.x for s in samples]), device)
        for s, m in zip(samples, maps, strict=True):
            yield s, grasp_of(m, width_calibration)


def evaluate(
    model: torch.nn.Module,
    dataset,
    indices,
    *,
    device="cpu",
    batch_size: int = 16,
    progress: bool = True,
    width_calibration: float = 1.0,
) -> EvalResult:
    """Accuracy and width error of ``model`` on ``dataset`` samples ``indices`` (no
    augmentation), widths decoded with the weights' ``width_calibration``."""
    was_training = model.training
    model.eval()
    flags: list[bool] = []
    widths = []
    for s, pred in _top_grasps(
        model, dataset, indices, device, batch_size, progress, width_calibration
    ):
        flags.append(is_correct([pred], s.rects))
        pair = width_pair(pred, s)
        if pair is not None:
            widths.append(pair)
    model.train(was_training)
    n = len(flags)
    return EvalResult(sum(flags) / n if n else 0.0, n, sum(flags), flags, WidthError.of(widths))


def fit_width_calibration(
    model: torch.nn.Module, dataset, indices, *, part: str, device="cpu", batch_size: int = 16
) -> dict:
    """The width calibration of ``model``: the median ratio of true to decoded width over the
    predictions on a true grasp among samples ``indices`` (the validation part, or training
    images; never the test part). Returned as the weights' ``width_calibration`` record."""
    was_training = model.training
    model.eval()
    ratios = []
    for s, pred in _top_grasps(model, dataset, indices, device, batch_size, False, 1.0):
        pair = width_pair(pred, s)
        if pair is not None:
            ratios.append(pair[1] / pair[0])
    model.train(was_training)
    scale = float(np.median(ratios)) if ratios else 1.0
    return {"scale": scale, "grasps": len(ratios), "images": len(list(indices)), "part": part}


def calibration_of(meta: dict) -> float:
    """The width calibration factor recorded in a weights file's meta (1 when none)."""
    return float(meta.get("width_calibration", {}).get("scale", 1.0))


def time_inference(
    model: torch.nn.Module,
    channels: int,
    size: int = 224,
    *,
    device="cpu",
    repeats: int = 20,
    warmup: int = 3,
) -> dict:
    """Forward-pass time of one ``size`` x ``size`` image (batch 1): median and minimum ms."""
    model.eval()
    x = torch.randn(1, channels, size, size, device=device)
    times = []
    with torch.inference_mode():
        for k in range(warmup + repeats):
            if device != "cpu" and torch.cuda.is_available():
                torch.cuda.synchronize()
            t = time.perf_counter()
            model(x)
            if device != "cpu" and torch.cuda.is_available():
                torch.cuda.synchronize()
            if k >= warmup:
                times.append((time.perf_counter() - t) * 1000)
    times.sort()
    return {"median_ms": times[len(times) // 2], "min_ms": times[0], "repeats": repeats}


class ChannelsLast(torch.nn.Module):
    """Runs ``inner`` (converted to channels-last) on a channels-last copy of the input and
    returns the output in the ordinary layout: oneDNN's CPU convolutions are fastest on
    NHWC (HRG-Net: about 1.4x at 224x224)."""

    def __init__(self, inner: torch.nn.Module):
        super().__init__()
        self.inner = inner.to(memory_format=torch.channels_last)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.inner(x.contiguous(memory_format=torch.channels_last)).contiguous()


def optimize_for_cpu(model: torch.nn.Module) -> torch.nn.Module:
    """An inference copy with every BatchNorm folded into the convolution before it
    (torch.fx), run channels-last; same outputs, fewer passes over memory. Falls back to
    the unfused model when it cannot be traced."""
    import copy

    from torch.fx.experimental.optimization import fuse

    try:
        fused = fuse(copy.deepcopy(model).eval())
    except Exception:  # pragma: no cover - an untraceable model still runs unfused
        fused = copy.deepcopy(model).eval()
    return ChannelsLast(fused).eval()
