"""The detector's network: a small encoder-decoder that gives every pixel a class (torch).

Zhou et al. (IEEE T-ASE 2023, §IV-V) detect the workcell's objects with a trained network;
ours is semantic segmentation, the simplest thing that gives masks, followed by instance
extraction (`tamp.sim.core.instances`). Built from the grasp networks' blocks
(`tamp.grasp.models`: convolution + batch norm, depthwise-separable convolutions and the
zero-initialised residual block): three stride-2 stages (1/2, 1/4, 1/8 of the input) with
residual blocks, a decoder that adds each coarser map (1x1 convolution, bilinear upsampling)
to the skip connection of its stage, and a full-resolution branch of eight channels that
keeps thin objects (a screw is 3 pixels wide at 160x90) from vanishing in the stride.
With ``width=16``: about 0.2 M parameters, 0.1 GMAC per 160x96 image.

Input (`prepare`): RGB in [0, 1] centred, depth relative to the view's median depth (the
table under the camera) in units of 5 cm, clipped, and a validity channel (depth 0 = no
return). The image is padded to a multiple of 8 and the logits are cropped back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from tamp.grasp.models import BasicBlock, _conv_bn, _separable

#: the shipped weights (``tamp/models/weights``)
WEIGHTS_FILE = "detector_seg_rgbd.pt"
IN_CHANNELS = 5
DEPTH_SCALE = 0.05


class SegNet(nn.Module):
    """Per-pixel class logits (N, classes, H, W) of an (N, 5, H, W) RGB-D input."""

    def __init__(self, classes: int, width: int = 16):
        super().__init__()
        c1, c2, c3 = width, 2 * width, 4 * width
        self.fine = _conv_bn(IN_CHANNELS, 8)
        self.stage1 = nn.Sequential(_conv_bn(IN_CHANNELS, c1, stride=2), _conv_bn(c1, c1))
        self.stage2 = nn.Sequential(_conv_bn(c1, c2, stride=2), BasicBlock(c2))
        self.stage3 = nn.Sequential(_conv_bn(c2, c3, stride=2), BasicBlock(c3), BasicBlock(c3))
        self.lat3 = _conv_bn(c3, c2, k=1, relu=False)
        self.dec2 = _separable(c2, c2)
        self.lat2 = _conv_bn(c2, c1, k=1, relu=False)
        self.dec1 = _separable(c1, c1)
        self.head = nn.Sequential(_conv_bn(c1 + 8, c1, k=1), nn.Conv2d(c1, classes, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h, w = x.shape[-2:]
        ph, pw = (-h) % 8, (-w) % 8
        if ph or pw:
            x = F.pad(x, (0, pw, 0, ph), mode="replicate")
        f = self.fine(x)
        s1 = self.stage1(x)
        s2 = self.stage2(s1)
        s3 = self.stage3(s2)
        d2 = self.dec2(s2 + F.interpolate(self.lat3(s3), size=s2.shape[-2:], mode="bilinear"))
        d1 = self.dec1(s1 + F.interpolate(self.lat2(d2), size=s1.shape[-2:], mode="bilinear"))
        up = F.interpolate(d1, size=x.shape[-2:], mode="bilinear")
        out = self.head(torch.cat([up, f], dim=1))
        return out[..., :h, :w]


def prepare(rgb: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """The network input (5, H, W) float32 of one view: RGB (H, W, 3) uint8 and depth (H, W)
    metres (0, NaN or inf = no return)."""
    d = np.nan_to_num(np.asarray(depth, np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    valid = d > 0
    ref = float(np.median(d[valid])) if valid.any() else 0.0
    rel = np.where(valid, np.clip((d - ref) / DEPTH_SCALE, -6.0, 6.0), 0.0)
    x = np.empty((IN_CHANNELS, *d.shape), np.float32)
    x[:3] = np.moveaxis(np.asarray(rgb[..., :3], np.float32) / 255.0 - 0.5, -1, 0)
    x[3] = rel
    x[4] = valid
    return x


def save(path: str | Path, model: SegNet, meta: dict) -> None:
    """A weights file (the grasp networks' format: ``{"meta", "state_dict"}``, loadable with
    ``weights_only=True``); ``meta`` holds the classes, the network's width and the split."""
    from tamp.grasp.train import write_weights

    write_weights(Path(path), meta, model.state_dict())


def load(path: str | Path, device: str = "cpu") -> tuple[SegNet, dict]:
    """(the network in eval mode, its meta) of a weights file; `InputError` naming the file
    when it is not a detector's weights."""
    from tamp.errors import InputError
    from tamp.grasp.train import read_weights

    blob = read_weights(path, device)
    meta = blob["meta"]
    try:
        model = SegNet(len(meta["classes"]), int(meta["width"]))
        model.load_state_dict(blob["state_dict"])
    except (KeyError, TypeError, RuntimeError) as exc:
        raise InputError(
            f"not detector weights ({type(exc).__name__}: {str(exc)[:200]})", file=str(path)
        ) from None
    return model.to(device).eval(), meta


def parameter_count(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
