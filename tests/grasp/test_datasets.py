"""Loaders for the Cornell and Jacquard formats, augmentation, splits, target maps."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.errors import InputError
from tamp.grasp.datasets import Augment, GraspDataset, make_split
from tamp.grasp.maps import WIDTH_SCALE, detect_grasps, draw_targets, post_process
from tamp.grasp.rect import GraspRect


def _q_on_object(sample) -> float:
    """Fraction of the Q > 0 pixels that lie on the bar (raised depth)."""
    q = sample.y[0] > 0
    on = sample.depth < 0.585
    return float((q & on).sum() / max(q.sum(), 1))


def test_jacquard_loader(jacquard_dir: Path):
    ds = GraspDataset("jacquard", jacquard_dir, size=32, mode="rgbd")
    assert len(ds) == 8
    assert sorted(set(ds.groups())) == ["obj0", "obj1", "obj2", "obj3"]
    s = ds.load(0)
    assert s.x.shape == (4, 32, 32) and s.y.shape == (4, 32, 32)
    # the 64 px image is scaled by one half: the rectangle follows the image
    (raw_rgb, raw_depth, (raw_rect,)) = ds.read(0)
    (rect,) = s.rects
    assert math.isclose(rect.width, raw_rect.width * 0.5, rel_tol=1e-6)
    assert _q_on_object(s) == 1.0
    r, c = int(round(rect.y)), int(round(rect.x))
    assert s.y[0, r, c] == 1.0
    assert math.isclose(s.y[3, r, c], rect.width / WIDTH_SCALE, rel_tol=1e-6)
    assert math.isclose(s.y[1, r, c], math.cos(2 * rect.angle), abs_tol=1e-6)


@pytest.mark.parametrize("pcd", [True, False])
def test_cornell_loader(tmp_path: Path, pcd: bool):
    from tests.grasp.data import write_cornell_set

    root = write_cornell_set(tmp_path / "c", images=3, pcd=pcd)
    ds = GraspDataset("cornell", root, size=24, mode="d")
    assert len(ds) == 3
    s = ds.load(1)
    assert s.x.shape == (1, 24, 24)
    assert _q_on_object(s) == 1.0


@given(seed=st.integers(0, 10_000))
@settings(max_examples=15)
def test_augmentation_moves_rectangles_with_the_image(tmp_path_factory, seed):
    from tests.grasp.data import write_jacquard_set

    root = tmp_path_factory.getbasetemp() / "aug"
    if not root.exists():
        write_jacquard_set(root, objects=2, views=1)
    ds = GraspDataset("jacquard", root, size=48, mode="rgbd")
    s = ds.load(seed % 2, Augment(rotation=180, zoom_min=0.7), np.random.default_rng(seed))
    # after any rotation and zoom the grasp region still lies on the bar
    assert _q_on_object(s) > 0.9


def test_missing_and_malformed_files_are_named(jacquard_dir: Path, tmp_path: Path):
    victim = next(jacquard_dir.rglob("*_RGB.png"))
    victim.unlink()
    with pytest.raises(InputError, match=f"{victim}: file not found"):
        GraspDataset("jacquard", jacquard_dir)
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no jacquard grasp file"):
        GraspDataset("jacquard", tmp_path / "empty")
    with pytest.raises(InputError, match="dataset folder not found"):
        GraspDataset("cornell", tmp_path / "nope")
    victim.write_bytes(b"")  # present again (unreadable: only read in RGB modes)
    grasps = next(jacquard_dir.rglob("*_grasps.txt"))
    grasps.write_text("1;2;3\n")
    ds = GraspDataset("jacquard", jacquard_dir, mode="d")
    index = [s.grasps for s in ds.samples].index(grasps)
    with pytest.raises(InputError, match=f"{grasps}: line 1: expected 5 fields"):
        ds.load(index)


groups_strategy = st.lists(st.sampled_from("abcdefgh"), min_size=4, max_size=40).filter(
    lambda g: len(set(g)) >= 2
)


@given(groups_strategy, st.integers(0, 99))
def test_object_split_keeps_objects_apart(groups, seed):
    train, test = make_split(groups, "object", 0.3, seed)
    assert sorted(train + test) == list(range(len(groups)))
    assert not {groups[i] for i in train} & {groups[i] for i in test}
    assert train and test


@given(st.integers(5, 60), st.integers(0, 99))
def test_k_fold_covers_each_image_once(n, seed):
    groups = [str(i) for i in range(n)]
    tests = [make_split(groups, "image", seed=seed, fold=k, folds=5)[1] for k in range(5)]
    flat = sorted(i for t in tests for i in t)
    assert flat == list(range(n))


def test_split_errors():
    with pytest.raises(InputError, match="at least 2 objects"):
        make_split(["a", "a"], "object")
    with pytest.raises(InputError, match="fold must be in 0..4"):
        make_split(["a", "b"], "image", fold=5)


@given(
    st.floats(10, 38), st.floats(10, 38), st.floats(-1.5, 1.5), st.floats(12, 24), st.floats(4, 8)
)
def test_targets_decode_back_to_the_rectangle(x, y, angle, width, height):
    """Maps drawn from a rectangle and read back by the post-processing match it.

    (Below ~12 px the smoothing of the narrow width map shrinks the width too much: the
    standard GG-CNN post-processing has that limit too.)"""
    truth = GraspRect(x, y, angle, width, height)
    maps = draw_targets([truth], 48)
    q, ang, w = post_process(maps)
    (pred, quality), *_ = detect_grasps(q, ang, w)
    assert pred.matches(truth)
