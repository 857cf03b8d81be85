"""The detector's training data: the catalogue read from the SDF files, scenes with touching
clutter and an object-wise split, renders whose targets match the label images."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tamp.commands.detect import workcell_catalogue
from tamp.grasp.pinhole import camera_to_pixel
from tamp.sim.core import segdata as sd


@pytest.fixture(scope="module")
def catalogue():
    return workcell_catalogue()


def test_the_catalogue_is_both_cells_classes_with_their_palettes(catalogue):
    classes, fixtures = catalogue
    names = [c.name for c in classes]
    from tamp.sim.lots.catalogue import CLASSES
    from tamp.sim.smp.robot import OBJECT_KINDS

    assert names == [*CLASSES, *OBJECT_KINDS]
    hammer = classes[names.index("hammer")]
    assert hammer.palette == CLASSES["hammer"].palette
    lo, hi = sd.footprint(hammer.visuals)
    assert lo[2] == pytest.approx(0.0) and hi[2] == pytest.approx(CLASSES["hammer"].height)
    assert sd.class_names(classes)[:2] == ("background", "table")
    assert sd.class_names(classes)[-2:] == ("unknown", "hand")
    assert fixtures.gripper and fixtures.hand
    # the TCP seen from the camera: lots_arm.sdf's tcp (0, 0, 0.1034) and camera
    # (0.065, 0, 0.048) frames on the hand
    assert np.allclose(fixtures.X_CT[:3, 3], [-0.065, 0.0, 0.0554])


def test_the_wrist_camera_does_not_see_the_gripper(catalogue):
    """Why the gripper is background: every corner of the fingers and palm lies outside the
    LOTS wrist camera's field of view (320 x 180, 42.5 deg vertical)."""
    _, fixtures = catalogue
    h, w = 180, 320
    fy = (h / 2) / math.tan(math.radians(42.5) / 2)
    intr = (fy, fy, w / 2, h / 2)
    for vis in fixtures.gripper:
        half = np.array(vis.size if vis.shape == "box" else (vis.size[0],) * 2 + (vis.size[1],)) / 2
        if vis.shape == "cylinder":
            half = np.array([vis.size[0], vis.size[0], vis.size[1] / 2])
        for corner in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T:
            p = vis.X_BG[:3, :3] @ (corner * half) + vis.X_BG[:3, 3]
            if p[2] <= 0.03:
                continue  # behind the near plane
            u, v = camera_to_pixel(p, intr)
            assert not (0 <= u < w and 0 <= v < h), (vis, p, u, v)


def test_scenes_are_seeded_touch_and_never_overlap(catalogue):
    classes, _ = catalogue
    cfg = sd.DataConfig()
    a = sd.sample_scene(np.random.default_rng((0, 5)), classes, cfg, "train")
    b = sd.sample_scene(np.random.default_rng((0, 5)), classes, cfg, "train")
    assert [(i.cls, i.x, i.y) for i in a.items] == [(i.cls, i.x, i.y) for i in b.items]
    touching = 0
    for s in range(30):
        scene = sd.sample_scene(np.random.default_rng((0, s)), classes, cfg, "train")
        items = scene.items
        for i, p in enumerate(items):
            for q in items[i + 1 :]:
                assert not sd.overlap(p.corners(), q.corners())
                touching += sd.overlap(p.corners(0.002), q.corners())
        assert len(scene.cameras) == cfg.views
        for X in scene.cameras:
            tallest = max((i.top for i in items), default=0.0)
            assert X[2, 3] >= min(cfg.min_height * math.cos(math.radians(20)), tallest + 0.1)
    assert touching >= 10  # clutter that touches is common, not rare


def test_the_split_is_object_wise_and_recorded():
    tests = [i for i in range(400) if sd.split_of(i, 0, 0.15) == "test"]
    assert 30 < len(tests) < 90
    assert sd.split_of(17, 0, 0.15) == sd.split_of(17, 0, 0.15)
    assert not set(sd.UNKNOWN_TRAIN_KINDS) & set(sd.UNKNOWN_TEST_KINDS)


def test_unknown_shapes_differ_between_the_parts(catalogue):
    classes, _ = catalogue
    rng = np.random.default_rng(0)
    for kind in sd.UNKNOWN_TRAIN_KINDS + sd.UNKNOWN_TEST_KINDS:
        vis = sd.unknown_visuals(kind, rng)
        lo, _ = sd.footprint(vis)
        assert lo[2] == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(ValueError, match="unknown shape kind"):
        sd.unknown_visuals("teapot", rng)


def test_renders_carry_targets_that_match_the_scene(catalogue, tmp_path):
    """One scene rendered (Drake, ~1 s): class map, instance ids and their classes agree, the
    held object of the first view is near the camera, and `generate` writes the set."""
    classes, fixtures = catalogue
    cfg = sd.DataConfig(views=2)
    names = sd.class_names(classes)
    scene = None
    for s in range(50):
        cand = sd.sample_scene(np.random.default_rng((1, s)), classes, cfg, "train")
        if cand.held is not None and cand.hand is not None:
            scene = cand
            break
    assert scene is not None
    views = sd.render_scene(scene, classes, fixtures, cfg)
    assert len(views) == 2
    for v in views:
        assert v.rgb.shape == (90, 160, 3) and v.depth.shape == (90, 160)
        assert (v.cls == 1).any()  # the table
        for k in np.unique(v.inst)[1:]:
            assert (v.cls[v.inst == k] == v.inst_cls[k]).all()
            assert v.inst_cls[k] >= 2
        assert ((v.inst == 0) == (v.cls < 2)).all()
    held = names.index(scene.held.cls)
    near = views[0].depth < 0.12
    assert near.any() and (views[0].cls[near & (views[0].depth > 0)] == held).mean() > 0.5
    info = sd.generate(tmp_path / "set", 2, classes, fixtures, cfg, progress=False)
    saved = json.loads((tmp_path / "set" / sd.DATASET_FILE).read_text())
    assert saved["classes"] == list(names) and saved["scenes"] == 2
    assert sorted(info.train + info.test) == [0, 1]
    again = sd.read_scene(sd.scene_file(tmp_path / "set", 0))
    assert again["rgb"].shape[0] == 2 and again["X_WC"].shape == (2, 4, 4)
