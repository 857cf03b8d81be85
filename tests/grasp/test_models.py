"""HRG-Net and the baselines: output maps the size of the input, full-resolution branch,
layer fusion switch (Table IV ablation), parameter counts."""

from __future__ import annotations

import pytest
import torch

from tamp.grasp.evaluate import optimize_for_cpu
from tamp.grasp.models import HRGNet, build_model, parameter_count
from tamp.grasp.networks import INPUT_CHANNELS, NETWORKS


@pytest.mark.slow  # heavy for the quick loop; make test runs it
@pytest.mark.parametrize("name", list(NETWORKS))
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


def _units(model: HRGNet) -> list:
    return [unit for stage in model.stages for unit in stage]


@pytest.mark.slow  # heavy for the quick loop; make test runs it
def test_full_resolution_branch_through_the_whole_network():
    model = HRGNet(4).eval()
    seen = []
    for unit in _units(model):
        unit.register_forward_hook(lambda m, i, o: seen.append(tuple(o[0].shape[-2:])))
    with torch.no_grad():
        model(torch.randn(1, 4, 48, 40))
    assert seen == [(48, 40)] * len(_units(model))


@pytest.mark.slow  # heavy for the quick loop; make test runs it
def test_branches_halve_the_resolution_stage_by_stage():
    model = HRGNet(1, widths=(4, 8, 12, 16)).eval()
    shapes = []
    for t in model.transitions:
        t.register_forward_hook(lambda m, i, o: shapes.append(tuple(o.shape[1:])))
    with torch.no_grad():
        model(torch.randn(1, 1, 64, 64))
    assert shapes == [(8, 32, 32), (12, 16, 16), (16, 8, 8)]


def test_stage_layout_blocks_and_modules():
    model = HRGNet(4, widths=(4, 8, 12, 16), blocks=(1, 2, 3, 2), modules=(1, 2, 3, 1))
    assert [len(stage) for stage in model.stages] == [1, 2, 3, 1]
    for s, stage in enumerate(model.stages, start=1):
        for unit in stage:
            assert [len(b) for b in unit.branches] == [1, 2, 3, 2][:s]
            assert (unit.fusion is None) == (s == 1)  # one exchange per unit from stage 2
    assert sum(u.fusion is not None for u in _units(model)) == 2 + 3 + 1
    default = HRGNet(4)
    assert [len(stage) for stage in default.stages] == [1, 1, 2, 1]
    assert sum(u.fusion is not None for u in _units(default)) == 4
    assert len(HRGNet(4, widths=(4, 8)).stages) == 2  # counts past the branches are ignored
    for bad in (dict(blocks=(1, 2)), dict(modules=0)):
        with pytest.raises(ValueError, match="positive counts"):
            HRGNet(4, **bad)


def _lowres_influence(model: HRGNet) -> float:
    """How much the full-resolution branch after the last unit depends on the
    lower-resolution branches: perturb the lowest branch's input and watch branch 0."""
    captured = {}
    model.eval()
    handle = _units(model)[-1].register_forward_hook(lambda m, i, o: captured.update(xs=o))
    x = torch.randn(1, 4, 32, 32)
    with torch.no_grad():
        model(x)
        base = captured["xs"][0].clone()
        # perturb only the lowest branch by hooking its transition
        h2 = model.transitions[-1].register_forward_hook(lambda m, i, o: o + 5.0)
        model(x)
        after = captured["xs"][0]
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
    for unit in _units(model)[1:]:
        for row in unit.fusion.paths:
            for path in row:
                if not isinstance(path, torch.nn.Identity):
                    norms = [m for m in path.modules() if isinstance(m, torch.nn.BatchNorm2d)]
                    assert torch.count_nonzero(norms[-1].weight) == 0


def test_down_paths_stride_once_per_halving():
    model = HRGNet(4, widths=(4, 8, 12, 16))
    last = _units(model)[-1].fusion
    # branch 0 -> branch 3: three strided 3x3 convolutions, as in HRNet
    strides = [m.stride for m in last.paths[3][0].modules() if isinstance(m, torch.nn.Conv2d)]
    assert strides == [(2, 2)] * 3


def _output_hears_lowest_branch(model: HRGNet) -> float:
    model.eval()
    x = torch.randn(1, 4, 32, 32)
    with torch.no_grad():
        a = model(x)
        h = model.transitions[-1].register_forward_hook(lambda m, i, o: o + 5.0)
        b = model(x)
        h.remove()
    return float((a - b).abs().max())


@pytest.mark.slow  # heavy for the quick loop; make test runs it
def test_fusion_modes():
    torch.manual_seed(0)
    full, final, none = (
        _as_if_trained(HRGNet(4, fusion=mode)) for mode in ("full", "final", "none")
    )
    assert parameter_count(full) > parameter_count(final) > parameter_count(none)
    # full: the full-resolution branch hears the lowest branch inside the network
    assert _lowres_influence(full) > 1e-3
    # final fusion only: it does not, but the head still sums every branch
    assert _lowres_influence(final) == 0.0
    assert all(u.fusion is None for u in _units(final))
    for model in (full, final):
        assert len(model.widths) == 4 and _output_hears_lowest_branch(model) > 1e-4
    # none: nothing passes between resolutions, so only the full-resolution branch exists,
    # with the same number of units and blocks on it
    assert none.widths == (8,) and len(none.transitions) == 0 and len(none.aggregate) == 1
    assert len(_units(none)) == len(_units(full))
    assert all(len(u.branches) == 1 and u.fusion is None for u in _units(none))
    assert none(torch.randn(1, 4, 24, 40)).shape == (1, 4, 24, 40)
    # booleans name the paper's two settings
    assert HRGNet(4, fusion=True).fusion == "full" and HRGNet(4, fusion=False).fusion == "none"
    with pytest.raises(ValueError, match="unknown fusion"):
        HRGNet(4, fusion="partial")


@pytest.mark.slow  # heavy for the quick loop; make test runs it
@pytest.mark.parametrize("name", list(NETWORKS))
def test_cpu_inference_copy_gives_the_same_maps(name):
    """BatchNorm folded and channels-last: same outputs, ordinary layout out."""
    torch.manual_seed(0)
    model = build_model(name, "rgbd")
    model.train()
    with torch.no_grad():  # a few batches give the batch norms non-trivial statistics
        for _ in range(3):
            model(torch.randn(2, 4, 48, 48) * 2 + 0.5)
    model.eval()
    x = torch.randn(1, 4, 48, 48)
    fast = optimize_for_cpu(model)
    with torch.no_grad():
        want, got = model(x), fast(x)
    assert got.is_contiguous() and got.shape == want.shape
    assert torch.allclose(got, want, atol=1e-4, rtol=1e-3)
    norms = sum(isinstance(m, torch.nn.BatchNorm2d) for m in fast.modules())
    # every batch norm of HRG-Net follows a convolution; GR-ConvNet's after its transposed
    # convolutions stay
    assert norms == (0 if name != "grconvnet" else 2)


def test_parameter_counts_are_small():
    counts = {name: parameter_count(build_model(name, "rgbd")) for name in NETWORKS}
    assert 300_000 < counts["hrgnet"] < 600_000  # real time on a CPU
    assert 50_000 < counts["ggcnn"] < 100_000  # GG-CNN is ~62 k (depth input)
    assert 1_500_000 < counts["grconvnet"] < 2_500_000  # GR-ConvNet is ~1.9 M at 32 ch


def test_unknown_model_or_input():
    with pytest.raises(ValueError, match="unknown model"):
        build_model("resnet", "d")
    with pytest.raises(ValueError, match="unknown input"):
        build_model("hrgnet", "xyz")
