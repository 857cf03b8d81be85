"""The seeded noisy detector: same seed and frame, same errors; the named levels differ; each
kind of error does what it says."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tamp.sim.core.detection_noise import LEVELS, NoiseLevel, occlusion, perturb
from tamp.sim.core.instances import extract

NAMES = ("background", "table", "block", "cube", "unknown", "hand")
INTR = (100.0, 100.0, 40.0, 30.0)
CLASSES = NAMES[2:]


def _view():
    depth = np.full((60, 80), 0.5, np.float32)
    cls_map = np.ones((60, 80), int)
    for k, (v0, u0, size, c) in enumerate([(5, 5, 12, 2), (30, 10, 3, 3), (20, 50, 10, 3)]):
        cls_map[v0 : v0 + size, u0 : u0 + size] = c
        depth[v0 : v0 + size, u0 : u0 + size] = 0.47 - 0.01 * k
    probs = np.full((len(NAMES), 60, 80), 0.02, np.float32)
    for c in range(len(NAMES)):
        probs[c][cls_map == c] = 0.9
    dets = extract(probs, depth, NAMES, [2, 3, 4, 5], INTR, np.eye(4), min_pixels=8)
    return dets, depth


NONE = NoiseLevel(0.0, 1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def _summary(dets):
    return [(d.cls, d.pixels, tuple(np.round(d.centroid, 6))) for d in dets]


def test_no_noise_changes_nothing():
    dets, depth = _view()
    out = perturb(dets, seed=1, frame=0, level=NONE, classes=CLASSES, depth=depth,
                  intrinsics=INTR, X_WC=np.eye(4))  # fmt: skip
    assert _summary(out) == _summary(dets)


def test_same_seed_and_frame_same_errors_and_frames_differ():
    dets, depth = _view()
    kw = dict(level="high", classes=CLASSES, depth=depth, intrinsics=INTR, X_WC=np.eye(4))
    runs = [_summary(perturb(dets, seed=7, frame=f, **kw)) for f in (3, 3)]
    assert runs[0] == runs[1]
    frames = {str(_summary(perturb(dets, seed=7, frame=f, **kw))) for f in range(20)}
    assert len(frames) > 5


def test_high_noise_makes_more_errors_than_low():
    dets, depth = _view()
    kw = dict(classes=CLASSES, depth=depth, intrinsics=INTR, X_WC=np.eye(4))
    changed = {}
    for level in ("low", "high"):
        n = 0
        for f in range(200):
            n += _summary(perturb(dets, seed=0, frame=f, level=level, **kw)) != _summary(dets)
        changed[level] = n
    assert 0 < changed["low"] < changed["high"]


def test_small_detections_are_missed_more_often():
    dets, depth = _view()
    small = min(dets, key=lambda d: d.pixels)
    big = max(dets, key=lambda d: d.pixels)
    only_misses = dataclasses.replace(NONE, miss_small=1.0, small_area=60)
    kept = {small.pixels: 0, big.pixels: 0}
    for f in range(100):
        for d in perturb(dets, seed=0, frame=f, level=only_misses, classes=CLASSES):
            if d.pixels in kept:
                kept[d.pixels] += 1
    assert kept[big.pixels] == 100 and kept[small.pixels] < 100


def test_swaps_jumps_and_false_positives():
    dets, depth = _view()
    swaps = dataclasses.replace(NONE, swap=1.0)
    out = perturb(dets, seed=0, frame=0, level=swaps, classes=CLASSES)
    assert all(a.cls != b.cls for a, b in zip(dets, out, strict=True))
    assert all(b.cls in ("block", "cube") for b in out)
    jumps = dataclasses.replace(NONE, fresh=1.0, fresh_jump=0.08)
    out = perturb(dets, seed=0, frame=0, level=jumps, classes=CLASSES)
    for a, b in zip(dets, out, strict=True):
        assert np.linalg.norm(np.subtract(b.centroid, a.centroid)) == pytest.approx(0.08)
    fps = dataclasses.replace(NONE, false_positives=3.0)
    extra = [
        len(
            perturb(
                dets,
                seed=0,
                frame=f,
                level=fps,
                classes=CLASSES,
                depth=depth,
                intrinsics=INTR,
                X_WC=np.eye(4),
            )
        )
        - len(dets)  # fmt: skip
        for f in range(50)
    ]
    assert 2.0 < np.mean(extra) < 4.0
    assert set(LEVELS) == {"low", "high"}


def test_occlusion_counts_the_image_edge_and_nearer_things():
    depth = np.full((20, 20), 0.5, np.float32)
    mask = np.zeros((20, 20), bool)
    mask[5:10, 5:10] = True
    depth[mask] = 0.45
    assert occlusion(mask, depth) == 0.0
    depth[5:10, 10] = 0.3  # something nearer along one side
    assert 0.15 < occlusion(mask, depth) < 0.3
    edge = np.zeros((20, 20), bool)
    edge[0:5, 0:5] = True
    assert occlusion(edge, None) > 0.3


def test_the_pixel_and_depth_follow_a_jitter_and_a_jump():
    """A consumer that places detections from their pixel centroid and depth (the SMP-MRO
    pose estimator) sees the same errors as one that reads the world centroid."""
    from tamp.grasp.pinhole import pixel_to_camera

    dets, depth = _view()
    kw = dict(seed=3, frame=0, classes=CLASSES, depth=depth, intrinsics=INTR, X_WC=np.eye(4))
    grow = dataclasses.replace(NONE, jitter=1.0)
    for d, g in zip(dets, perturb(dets, level=grow, **kw), strict=True):
        vs, us = np.nonzero(g.mask)
        assert g.pixels != d.pixels and (g.u, g.v) == pytest.approx((us.mean(), vs.mean()))
    jump = dataclasses.replace(NONE, fresh=1.0, fresh_jump=0.08)
    for d, j in zip(dets, perturb(dets, level=jump, **kw), strict=True):
        before = pixel_to_camera(d.u, d.v, d.depth, INTR)
        after = pixel_to_camera(j.u, j.v, j.depth, INTR)
        moved = after - before
        assert np.linalg.norm(moved[:2]) == pytest.approx(0.08, abs=1e-9) and moved[2] == 0.0
        assert np.subtract(j.centroid, d.centroid) == pytest.approx(moved)
