"""HRG-Net (§IV-B, Fig. 5) and the GG-CNN [49] and GR-ConvNet [57] style baselines.

All three are fully convolutional and map an ``(N, C, H, W)`` image (C = 1 depth, 3 RGB or
4 RGB-D) to four maps of the input size: grasp quality Q, cos 2Φ, sin 2Φ and width W
(§IV-B; the angle is encoded by its double angle so that Φ and Φ + π give the same output).

HRG-Net keeps a full-resolution branch through the whole network; every stage adds a
branch at half the resolution of the previous lowest one, all branches run in parallel
(residual blocks), and at the end of every exchange unit the branches exchange information
(layer fusion: each branch receives the sum of all branches, resampled by strided 3x3
convolutions going down and 1x1 convolutions + bilinear upsampling going up). The head
projects every branch, upsamples it to full resolution, sums and predicts the four maps.

Layer fusion has three settings (`tamp.grasp.networks.FUSION_MODES`):

- ``"full"``: the network above.
- ``"final"``: no exchange inside the network, the head alone sums the branches (HRNet's own
  ablation of repeated multi-scale fusion, "final fusion only").
- ``"none"``: no information passes between resolutions at all, the paper's Table IV
  ablation as its text explains it (layer fusion is what "allows the network to take into
  account both low-level spatial features and high-level semantic features"), and what the
  released code's commented head ``last_layer(x[0])`` computes once its exchange is removed.
  The lower branches could not reach the output, so they are not built: the network is the
  full-resolution branch alone, with the same blocks, stem and head.
"""

from __future__ import annotations

from collections.abc import Sequence

import torch
import torch.nn.functional as F
from torch import nn

from tamp.grasp.networks import FUSION_MODES, INPUT_CHANNELS, network


def _conv_bn(cin: int, cout: int, k: int = 3, stride: int = 1, relu: bool = True) -> nn.Sequential:
    layers: list[nn.Module] = [
        nn.Conv2d(cin, cout, k, stride, k // 2, bias=False),
        nn.BatchNorm2d(cout),
    ]
    if relu:
        layers.append(nn.ReLU(inplace=True))
    return nn.Sequential(*layers)


def _small_output(conv: nn.Conv2d) -> None:
    """Start the output maps near zero (the value of almost every target pixel), so that
    training spends no steps unlearning a random output offset."""
    nn.init.normal_(conv.weight, std=1e-3)
    nn.init.zeros_(conv.bias)


def _separable(cin: int, cout: int, relu: bool = True) -> nn.Sequential:
    """Depthwise 3x3 + pointwise 1x1 convolution: the 3x3 receptive field at ~1/8 the cost."""
    layers: list[nn.Module] = [
        nn.Conv2d(cin, cin, 3, 1, 1, groups=cin, bias=False),
        nn.BatchNorm2d(cin),
        nn.Conv2d(cin, cout, 1, bias=False),
        nn.BatchNorm2d(cout),
    ]
    if relu:
        layers.append(nn.ReLU(inplace=True))
    return nn.Sequential(*layers)


class BasicBlock(nn.Module):
    """Residual block of two 3x3 convolutions (the HRNet/ResNet basic block), starting as
    the identity (zero-initialised last batch-norm scale)."""

    def __init__(self, channels: int):
        super().__init__()
        self.conv1 = _conv_bn(channels, channels)
        self.conv2 = _conv_bn(channels, channels, relu=False)
        nn.init.zeros_(self.conv2[-1].weight)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return F.relu(x + self.conv2(self.conv1(x)))


def _down_path(cin: int, cout: int, steps: int) -> nn.Sequential:
    """HRNet's downsampling exchange path: ``steps`` strided 3x3 convolutions (ReLU between
    them, none after the last), halving the resolution each time."""
    layers = [
        _conv_bn(cin, cout if k == steps - 1 else cin, stride=2, relu=k < steps - 1)
        for k in range(steps)
    ]
    return nn.Sequential(*layers)


class FusionLayer(nn.Module):
    """Layer fusion: output branch i = ReLU(x_i + sum_{j != i} resample_{j->i}(x_j)) (Fig. 5).

    As in HRNet, going down (j < i) the map passes i - j strided 3x3 convolutions; going up
    (j > i) it is mapped by a 1x1 convolution and upsampled bilinearly. The last batch norm
    of every path starts at zero, so each exchange opens as training finds it useful: with
    HRNet's ordinary initialisation the coarse maps summed into the 8-channel
    full-resolution branch from the first step wiped out its detail (5-epoch pilot on the
    synthetic set: 74.8 % against 86.7 % gated; average-pooled down paths: 86.0 %).
    """

    def __init__(self, widths: Sequence[int]):
        super().__init__()
        n = len(widths)
        self.paths = nn.ModuleList(
            nn.ModuleList(
                nn.Identity()
                if j == i
                else _down_path(widths[j], widths[i], i - j)
                if j < i
                else _conv_bn(widths[j], widths[i], k=1, relu=False)
                for j in range(n)
            )
            for i in range(n)
        )
        for row in self.paths:  # zero-init gate: the last BN of every path
            for path in row:
                if not isinstance(path, nn.Identity):
                    norms = [m for m in path.modules() if isinstance(m, nn.BatchNorm2d)]
                    nn.init.zeros_(norms[-1].weight)

    def forward(self, xs: list[torch.Tensor]) -> list[torch.Tensor]:
        out = []
        for i, row in enumerate(self.paths):
            y = xs[i]
            for j, path in enumerate(row):
                if j < i:
                    y = y + path(xs[j])
                elif j > i:
                    z = path(xs[j])
                    y = y + F.interpolate(
                        z, size=y.shape[-2:], mode="bilinear", align_corners=False
                    )
            out.append(F.relu(y))
        return out


class ExchangeUnit(nn.Module):
    """HRNet's high-resolution module: residual blocks on every branch in parallel, then
    (with fusion) one exchange between all branches (Fig. 5).

    ``blocks[b]`` is the number of residual blocks on branch ``b``.
    """

    def __init__(self, widths: Sequence[int], blocks: Sequence[int], fusion: bool):
        super().__init__()
        self.branches = nn.ModuleList(
            nn.Sequential(*[BasicBlock(w) for _ in range(n)])
            for w, n in zip(widths, blocks, strict=False)
        )
        self.fusion = FusionLayer(widths) if fusion and len(widths) > 1 else None

    def forward(self, xs: list[torch.Tensor]) -> list[torch.Tensor]:
        xs = [branch(t) for branch, t in zip(self.branches, xs, strict=True)]
        return self.fusion(xs) if self.fusion is not None else xs


class HRGNet(nn.Module):
    """High-resolution grasp network (§IV-B): parallel multi-resolution branches + fusion.

    ``widths[k]`` is the channel count of the branch at 1/2^k resolution. Stage ``s``
    (s = 1..len(widths)) runs ``s`` branches through ``modules[s-1]`` exchange units
    (:class:`ExchangeUnit`), each with ``blocks[b]`` residual blocks on branch ``b`` and, with
    fusion, one exchange at its end: HRNet's stage/module layout, which the released HRG-Net
    code uses with 1, 1, 4 and 3 modules of 4 blocks. ``blocks`` and ``modules`` take one
    count per branch/stage (an int for all; entries past ``len(widths)`` are ignored, so
    ``widths=(4, 8)`` is a two-branch network).

    The defaults are a CPU-sized version. As the width doubles when the resolution halves,
    a 3x3 convolution costs the same multiply-adds on every branch, but the wide
    low-resolution ones run several times faster per multiply-add on a CPU than the
    8-channel full-resolution one. So the full-resolution branch has one block per unit, the
    1/2 branch two and the 1/4 and 1/8 branches three, and stage 3 repeats its unit: four
    exchanges instead of three.

    The head maps every branch to ``head_channels`` by a 1x1 convolution at its own
    resolution, upsamples and sums them at full resolution (HRNetV2-style aggregation at the
    cost of a sum instead of a concatenation), then a separable 3x3 and a 1x1 convolution
    give the four output maps. ``fusion`` is one of ``FUSION_MODES`` (module docstring);
    ``True``/``False`` mean ``"full"``/``"none"``.
    """

    def __init__(
        self,
        in_channels: int = 4,
        widths: Sequence[int] = (8, 16, 32, 64),
        blocks: int | Sequence[int] = (1, 2, 3, 3),
        modules: int | Sequence[int] = (1, 1, 2, 1),
        fusion: str | bool = "full",
        head_channels: int = 16,
    ):
        super().__init__()
        if isinstance(fusion, bool):
            fusion = "full" if fusion else "none"
        if fusion not in FUSION_MODES:
            raise ValueError(f"unknown fusion {fusion!r}; expected one of {list(FUSION_MODES)}")
        n = len(widths)
        blocks = [blocks] * n if isinstance(blocks, int) else list(blocks)[:n]
        modules = [modules] * n if isinstance(modules, int) else list(modules)[:n]
        if len(blocks) < n or len(modules) < n or min(blocks + modules) < 1:
            raise ValueError(
                f"blocks and modules need {n} positive counts (one per branch/stage; "
                f"later ones are ignored), got {blocks} and {modules}"
            )
        self.fusion = fusion
        self.widths = tuple(widths) if fusion != "none" else tuple(widths[:1])
        exchange = fusion == "full"
        c0, ch = widths[0], head_channels
        self.stem = nn.Sequential(_conv_bn(in_channels, c0), _separable(c0, c0))
        self.transitions = nn.ModuleList(
            _conv_bn(widths[s - 1], widths[s], stride=2) for s in range(1, len(self.widths))
        )
        self.stages = nn.ModuleList(
            nn.Sequential(
                *[
                    ExchangeUnit(self.widths[:s], blocks[:s], exchange)
                    for _ in range(modules[s - 1])
                ]
            )
            for s in range(1, n + 1)
        )
        self.aggregate = nn.ModuleList(_conv_bn(w, ch, k=1, relu=False) for w in self.widths)
        self.head = nn.Sequential(_separable(ch, ch), nn.Conv2d(ch, 4, 1))
        _small_output(self.head[-1])

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        xs = [self.stem(x)]
        for s, stage in enumerate(self.stages):
            if 0 < s < len(self.widths):  # a new, lower-resolution branch from the lowest one
                xs = xs + [self.transitions[s - 1](xs[-1])]
            xs = stage(xs)
        y = self.aggregate[0](xs[0])
        for conv, t in zip(self.aggregate[1:], xs[1:], strict=True):
            y = y + F.interpolate(conv(t), size=y.shape[-2:], mode="bilinear", align_corners=False)
        return self.head(F.relu(y))


class GGCNN(nn.Module):
    """GG-CNN [49]: three strided convolutions and three transposed convolutions (~62 k)."""

    def __init__(self, in_channels: int = 1, filters: Sequence[int] = (32, 16, 8)):
        super().__init__()
        f1, f2, f3 = filters
        self.body = nn.Sequential(
            nn.Conv2d(in_channels, f1, 9, 3, 3),
            nn.ReLU(inplace=True),
            nn.Conv2d(f1, f2, 5, 2, 2),
            nn.ReLU(inplace=True),
            nn.Conv2d(f2, f3, 3, 2, 1),
            nn.ReLU(inplace=True),
            nn.ConvTranspose2d(f3, f3, 3, 2, 1, output_padding=1),
            nn.ReLU(inplace=True),
            nn.ConvTranspose2d(f3, f2, 5, 2, 2, output_padding=1),
            nn.ReLU(inplace=True),
            nn.ConvTranspose2d(f2, f1, 9, 3, 3),
            nn.ReLU(inplace=True),
        )
        self.out = nn.Conv2d(f1, 4, 3, padding=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.body(x)
        y = F.interpolate(y, size=x.shape[-2:], mode="bilinear", align_corners=False)
        return self.out(y)


class ResidualBlock(nn.Module):
    def __init__(self, channels: int):
        super().__init__()
        self.conv1 = _conv_bn(channels, channels)
        self.conv2 = _conv_bn(channels, channels, relu=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.conv2(self.conv1(x))


class GRConvNet(nn.Module):
    """GR-ConvNet [57]: encoder (9x9, two strided 4x4), five residual blocks, decoder."""

    def __init__(self, in_channels: int = 4, channels: int = 32, dropout: float = 0.1):
        super().__init__()
        c = channels
        self.encoder = nn.Sequential(
            _conv_bn(in_channels, c, k=9),
            nn.Conv2d(c, 2 * c, 4, 2, 1, bias=False),
            nn.BatchNorm2d(2 * c),
            nn.ReLU(inplace=True),
            nn.Conv2d(2 * c, 4 * c, 4, 2, 1, bias=False),
            nn.BatchNorm2d(4 * c),
            nn.ReLU(inplace=True),
        )
        self.res = nn.Sequential(*[ResidualBlock(4 * c) for _ in range(5)])
        self.decoder = nn.Sequential(
            nn.ConvTranspose2d(4 * c, 2 * c, 4, 2, 1, bias=False),
            nn.BatchNorm2d(2 * c),
            nn.ReLU(inplace=True),
            nn.ConvTranspose2d(2 * c, c, 4, 2, 1, bias=False),
            nn.BatchNorm2d(c),
            nn.ReLU(inplace=True),
            nn.Conv2d(c, c, 9, 1, 4),
        )
        self.dropout = nn.Dropout(dropout)
        self.out = nn.Conv2d(c, 4, 3, padding=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.decoder(self.res(self.encoder(x)))
        # identity when the side is a multiple of 4; unconditional so that torch.fx traces it
        y = F.interpolate(y, size=x.shape[-2:], mode="bilinear", align_corners=False)
        return self.out(self.dropout(y))


def full_kwargs(name: str, **kwargs) -> dict:
    """``kwargs`` completed with the constructor defaults of model ``name`` (without the
    input channels), so that a weights file rebuilds the same network even after a default
    changes."""
    import inspect

    cls = network(name).model_class()
    params = list(inspect.signature(cls.__init__).parameters.values())[2:]  # self, in_channels
    out = {p.name: p.default for p in params} | kwargs
    return {k: list(v) if isinstance(v, tuple) else v for k, v in out.items()}


def build_model(name: str, input_mode: str = "rgbd", **kwargs) -> nn.Module:
    """A model by name (`tamp.grasp.networks.NETWORKS`) for an input mode of
    ``INPUT_CHANNELS``."""
    if input_mode not in INPUT_CHANNELS:
        raise ValueError(f"unknown input {input_mode!r}; expected one of {list(INPUT_CHANNELS)}")
    return network(name).model_class()(INPUT_CHANNELS[input_mode], **kwargs)


def parameter_count(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
