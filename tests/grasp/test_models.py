"""HRG-Net and the baselines: output maps the size of the input, full-resolution branch,
layer fusion switch (Table IV ablation), parameter counts."""

from __future__ import annotations

import pytest
import torch

from tamp.grasp.models import INPUT_CHANNELS, MODELS, HRGNet, build_model, parameter_count


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("mode", list(INPUT_CHANNELS))
def test_four_maps_the_size_of_the_input(name, mode):
    torch.manual_seed(0)
    model = build_model(name, mode).eval()
    for h, w in ((32, 32), (40, 56)):
        x = torch.randn(2, INPUT_CHANNELS[mode], h, w)
        with torch.no_grad():
            y = model(x)
        assert y.shape == (2, 4, h, w)
        assert torch.isfinite(y).all()


def test_full_resolution_branch_through_the_whole_network():
    model = HRGNet(4).eval()
    seen = []
    for stage in model.stages:
        stage[0].register_forward_hook(lambda m, i, o: seen.append(tuple(o.shape[-2:])))
    with torch.no_grad():
        model(torch.randn(1, 4, 48, 40))
    assert seen == [(48, 40)] * len(model.widths)


def test_branches_halve_the_resolution_stage_by_stage():
    model = HRGNet(1, widths=(4, 8, 12, 16)).eval()
    shapes = []
    for t in model.transitions:
        t.register_forward_hook(lambda m, i, o: shapes.append(tuple(o.shape[1:])))
    with torch.no_grad():
        model(torch.randn(1, 1, 64, 64))
    assert shapes == [(8, 32, 32), (12, 16, 16), (16, 8, 8)]


def _lowres_influence(model: HRGNet) -> float:
    """How much the full-resolution branch after the last stage depends on the
    lower-resolution branches: perturb the lowest branch's input and watch branch 0."""
    captured = {}
    model.eval()

    def grab(_m, _i, out):
        captured["xs"] = out

    last = model.fusions[-1] if model.fusion else model.stages[-1][0]
    handle = last.register_forward_hook(grab)
    x = torch.randn(1, 4, 32, 32)
    with torch.no_grad():
        model(x)
        base = captured["xs"][0].clone() if model.fusion else captured["xs"].clone()
        # perturb only the lowest branch by hooking its transition
        h2 = model.transitions[-1].register_forward_hook(lambda m, i, o: o + 5.0)
        model(x)
        after = captured["xs"][0] if model.fusion else captured["xs"]
        h2.remove()
    handle.remove()
    return float((after - base).abs().max())


def _as_if_trained(model: HRGNet) -> HRGNet:
    """Undo the zero/small initialisations of the residual blocks and the output layer."""
    for m in model.modules():
        if isinstance(m, torch.nn.BatchNorm2d):
            torch.nn.init.ones_(m.weight)
        elif isinstance(m, torch.nn.Conv2d):
            m.reset_parameters()
    return model


def test_fusion_paths_start_gated_shut():
    model = HRGNet(4, fusion=True)
    assert _lowres_influence(model) == 0.0  # zero-initialised gate: opened by training
    for row in model.fusions[-1].paths:
        for path in row:
            if not isinstance(path, torch.nn.Identity):
                norms = [m for m in path.modules() if isinstance(m, torch.nn.BatchNorm2d)]
                assert torch.count_nonzero(norms[-1].weight) == 0


def test_down_paths_stride_once_per_halving():
    model = HRGNet(4, widths=(4, 8, 12, 16))
    last = model.fusions[-1]
    # branch 0 -> branch 3: three strided 3x3 convolutions, as in HRNet
    strides = [m.stride for m in last.paths[3][0].modules() if isinstance(m, torch.nn.Conv2d)]
    assert strides == [(2, 2)] * 3


def test_fusion_switch():
    torch.manual_seed(0)
    on, off = _as_if_trained(HRGNet(4, fusion=True)), _as_if_trained(HRGNet(4, fusion=False))
    assert parameter_count(on) > parameter_count(off)
    # with fusion the full-resolution branch hears the lowest branch; without, it does not
    assert _lowres_influence(on) > 1e-3
    assert _lowres_influence(off) == 0.0
    # ... but the output still sees every branch through the head in both cases
    for model in (on, off):
        model.eval()
        x = torch.randn(1, 4, 32, 32)
        with torch.no_grad():
            a = model(x)
            h = model.transitions[-1].register_forward_hook(lambda m, i, o: o + 5.0)
            b = model(x)
            h.remove()
        assert float((a - b).abs().max()) > 1e-4


def test_parameter_counts_are_small():
    counts = {name: parameter_count(build_model(name, "rgbd")) for name in MODELS}
    assert counts["hrgnet"] < 500_000  # real time on a CPU
    assert 50_000 < counts["ggcnn"] < 100_000  # GG-CNN is ~62 k (depth input)
    assert 1_500_000 < counts["grconvnet"] < 2_500_000  # GR-ConvNet is ~1.9 M at 32 ch


def test_unknown_model_or_input():
    with pytest.raises(ValueError, match="unknown model"):
        build_model("resnet", "d")
    with pytest.raises(ValueError, match="unknown input"):
        build_model("hrgnet", "xyz")
