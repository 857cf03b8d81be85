"""Loaders for the Cornell and Jacquard formats, augmentation, splits, target maps."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.errors import InputError
from tamp.grasp.datasets import Augment, GraspDataset
from tamp.grasp.maps import WIDTH_SCALE, detect_grasps, draw_targets, post_process
from tamp.grasp.rect import GraspRect
from tamp.grasp.splits import SplitSpec, make_split


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
    split = make_split(groups, SplitSpec("object", seed, 0.3))
    train, test = split.train, split.test
    assert sorted(train + test) == list(range(len(groups))) and not split.val
    assert not {groups[i] for i in train} & {groups[i] for i in test}
    assert train and test


@given(
    st.lists(st.sampled_from("abcdefghijklmnop"), min_size=12, max_size=60).filter(
        lambda g: len(set(g)) >= 6
    ),
    st.integers(0, 99),
    st.sampled_from(["image", "object"]),
)
def test_validation_part_is_carved_from_training(groups, seed, kind):
    """Three disjoint parts covering every image, objects apart, and the test part of a seed
    the same with or without a validation part (so a recorded test split stays valid)."""
    plain = make_split(groups, SplitSpec(kind, seed, 0.2))
    split = make_split(groups, SplitSpec(kind, seed, 0.2, val_fraction=0.2))
    assert split.test == plain.test
    assert split.val and sorted(split.train + split.val) == plain.train
    assert sorted(split.train + split.val + split.test) == list(range(len(groups)))
    if kind == "object":
        parts = [{groups[i] for i in p} for p in (split.train, split.val, split.test)]
        assert not (parts[0] & parts[1] or parts[0] & parts[2] or parts[1] & parts[2])


@given(st.integers(5, 60), st.integers(0, 99))
def test_k_fold_covers_each_image_once(n, seed):
    groups = [str(i) for i in range(n)]
    tests = [make_split(groups, SplitSpec("image", seed, fold=k, folds=5)).test for k in range(5)]
    flat = sorted(i for t in tests for i in t)
    assert flat == list(range(n))


def test_split_errors():
    with pytest.raises(InputError, match="at least 2 objects"):
        make_split(["a", "a"], SplitSpec("object"))
    with pytest.raises(InputError, match="fold must be in 0..4"):
        make_split(["a", "b"], SplitSpec("image", fold=5))
    with pytest.raises(InputError, match="leaves no object for training"):
        make_split(["a", "b", "c"], SplitSpec("object", test_fraction=0.3, val_fraction=0.6))


def test_cornell_objects_come_from_the_object_list(tmp_path: Path):
    """Cornell file names hold the image number only and an object has any number of
    images: the object-wise split groups by the object list, never by runs of five files."""
    from tests.grasp.data import write_cornell_set

    root = write_cornell_set(tmp_path / "c", images=7, pcd=False)  # pcd0100 ... pcd0106
    ds = GraspDataset("cornell", root, size=24, mode="d")
    with pytest.raises(InputError, match="objects.txt: an object-wise split of a Cornell set"):
        ds.groups()
    assert len(ds.split(SplitSpec("image", 0, 0.3)).test) == 2  # image-wise needs no objects
    # three objects of 1, 4 and 2 images (i // 5 would have made {0..4}, {5, 6})
    (root / "objects.txt").write_text(
        "# image object\n0100 mug\n0101 shoe\n0102 shoe\n0103 shoe\n0104 shoe\n"
        "0105 pen\n0106 pen  a blue pen\n"
    )
    ds = GraspDataset("cornell", root, size=24, mode="d")
    assert ds.groups() == ["mug", "shoe", "shoe", "shoe", "shoe", "pen", "pen"]
    assert ds.ids() == [f"pcd{n:04d}" for n in range(100, 107)]
    for seed in range(10):
        split = ds.split(SplitSpec("object", seed, 0.34))
        test_objects = {ds.groups()[i] for i in split.test}
        assert not test_objects & {ds.groups()[i] for i in split.train}
        assert len(test_objects) == 1  # one object of three, with all its images
        assert len(split.test) == {"mug": 1, "shoe": 4, "pen": 2}[test_objects.pop()]
    (root / "objects.txt").write_text("0100 mug\n0101 shoe\n")
    with pytest.raises(InputError, match="objects.txt: image 0102 .* is not in the object list"):
        GraspDataset("cornell", root)
    (root / "objects.txt").write_text("0100 mug\nmug 0101\n")
    with pytest.raises(InputError, match="objects.txt: line 2: expected 'IMAGE_NUMBER OBJECT_ID'"):
        GraspDataset("cornell", root)
    (root / "objects.txt").write_text("0100 mug\n100 shoe\n")
    with pytest.raises(InputError, match="line 2: image 100 listed twice"):
        GraspDataset("cornell", root)


def test_split_record_fingerprints_the_data(jacquard_dir: Path):
    from tamp.grasp.splits import fingerprint, split_record

    ds = GraspDataset("jacquard", jacquard_dir, size=32)
    assert ds.ids()[:2] == ["obj0/0_obj0", "obj0/1_obj0"]
    spec = SplitSpec("object", 3, 0.25, 0.25)
    split = ds.split(spec)
    rec = split_record(ds, spec, split)
    assert SplitSpec.from_dict(rec) == spec
    assert rec["samples"] == 8 and rec["dataset"] == "jacquard"
    assert (rec["train_images"], rec["val_images"], rec["test_images"]) == (4, 2, 2)
    assert rec["fingerprint"] == fingerprint(reversed(ds.ids()))  # order does not matter
    assert rec["test_fingerprint"] == fingerprint(ds.ids()[i] for i in split.test)
    assert rec["fingerprint"] != fingerprint(ds.ids()[1:])


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
