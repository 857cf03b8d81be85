"""Rectangle-metric evaluation and inference timing (§V-A, Tables I, II, IV).

A prediction is the grasp at the peak of the smoothed quality map; it is correct when its
rectangle has IoU > 0.25 with some ground-truth rectangle and an angle within 30 degrees
of that rectangle's (:func:`tamp.grasp.rect.GraspRect.matches`). Accuracy is the fraction
of test images whose prediction is correct.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import torch

from tamp.grasp.maps import detect_grasps, post_process
from tamp.grasp.rect import GraspRect, is_correct


@dataclass
class EvalResult:
    accuracy: float
    images: int
    correct: int
    per_image: list[bool] = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"accuracy": self.accuracy, "images": self.images, "correct": self.correct}


def predict_maps(model: torch.nn.Module, x: np.ndarray, device="cpu") -> np.ndarray:
    """Raw output maps (N, 4, h, w) of ``model`` for inputs (N, C, h, w)."""
    with torch.inference_mode():
        return model(torch.from_numpy(np.ascontiguousarray(x)).to(device)).float().cpu().numpy()


def grasp_of(maps: np.ndarray) -> GraspRect:
    """The top grasp read from one (4, h, w) output."""
    q, angle, width = post_process(maps)
    return detect_grasps(q, angle, width, n=1)[0][0]


def evaluate(
    model: torch.nn.Module,
    dataset,
    indices,
    *,
    device="cpu",
    batch_size: int = 16,
    progress: bool = True,
) -> EvalResult:
    """Accuracy of ``model`` on ``dataset`` samples ``indices`` (no augmentation)."""
    from tqdm import tqdm

    was_training = model.training
    model.eval()
    flags: list[bool] = []
    idx = list(indices)
    for start in tqdm(range(0, len(idx), batch_size), desc="eval", disable=not progress):
        samples = [dataset.load(int(i)) for i in idx[start : start + batch_size]]
        maps = predict_maps(model, np.stack([s.x for s in samples]), device)
        for s, m in zip(samples, maps, strict=True):
            flags.append(is_correct([grasp_of(m)], s.rects))
    model.train(was_training)
    n = len(flags)
    return EvalResult(sum(flags) / n if n else 0.0, n, sum(flags), flags)


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
