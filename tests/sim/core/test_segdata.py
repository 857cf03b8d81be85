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
                if p.z != q.z or p.pitch or q.pitch:
                    continue  # one rests on the other (a stack, one lying across)
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
    near = (views[0].depth < 0.12) & (views[0].depth > 0)
    near &= views[0].cls != names.index(sd.HAND)  # the person's hand may reach close too
    assert near.any() and (views[0].cls[near] == held).mean() > 0.5
    info = sd.generate(tmp_path / "set", 2, classes, fixtures, cfg, progress=False)
    saved = json.loads((tmp_path / "set" / sd.DATASET_FILE).read_text())
    assert saved["classes"] == list(names) and saved["scenes"] == 2
    assert sorted(info.train + info.test) == [0, 1]
    again = sd.read_scene(sd.scene_file(tmp_path / "set", 0))
    assert again["rgb"].shape[0] == 2 and again["X_WC"].shape == (2, 4, 4)


def _scenes(catalogue, tag: str, count: int, split: str = "train", seed: int = 3):
    """The first ``count`` scenes of kind ``tag`` (with the tray among the fixtures)."""
    classes, fixtures = catalogue
    cfg = sd.DataConfig()
    out = []
    for s in range(400):
        scene = sd.sample_scene(
            np.random.default_rng((seed, s)), classes, cfg, split, fixtures.tray
        )
        if tag in scene.tags:
            out.append(scene)
        if len(out) == count:
            return out
    raise AssertionError(f"fewer than {count} scenes of kind {tag}")


def _rests_on(upper: sd.Item, lower: sd.Item) -> bool:
    """Whether ``upper`` stands on ``lower``'s top with its centre over ``lower``."""
    return (
        upper.pitch == 0.0
        and upper.z == pytest.approx(lower.top, abs=1e-9)
        and math.hypot(upper.x - lower.x, upper.y - lower.y) <= sd.STACK_OFFSET + 1e-9
    )


def test_a_stack_rests_level_on_level(catalogue):
    """Each level of a tower stands on the top of the one below (z = its top), centred within
    1.5 cm; the tower's classes come in their order, base on the table; the cameras stay 12 cm
    above the tallest level."""
    heights = set()
    for scene in _scenes(catalogue, sd.STACK, 12):
        levels = [it for it in scene.items if it.z > 0 and it.pitch == 0.0]
        assert levels
        for it in levels:
            below = [q for q in scene.items if q is not it and _rests_on(it, q)]
            assert len(below) == 1, it
        base = [q for q in scene.items if q.z == 0 and any(_rests_on(it, q) for it in levels)]
        assert len(base) == 1
        tower, names = base, [base[0].cls]
        while nxt := [it for it in levels if _rests_on(it, tower[-1])]:
            tower.append(nxt[0])
            names.append(nxt[0].cls)
        assert 2 <= len(tower) <= 4 and names[0] in sd.STACK_CLASSES
        parts = [n for n in names if n in sd.STACK_CLASSES][:2]
        assert parts == sorted(parts, key=sd.STACK_CLASSES.index)
        heights.add(len(tower))
        tallest = max(it.top for it in scene.items)
        for X in scene.cameras:
            assert X[2, 3] >= min(0.2 * math.cos(math.radians(20)), tallest + 0.1)
    assert {2, 3} <= heights


def test_tray_scenes_keep_their_objects_inside_the_walls(catalogue):
    """The tray's geometry is read from its SDF; its objects lie on its floor (or across one
    there) wholly inside the walls, and some of them touch a wall or each other."""
    tray = catalogue[1].tray
    assert (tray.floor, tray.inside, tray.outside) == pytest.approx((0.01, 0.24, 0.26))
    touching = 0
    for scene in _scenes(catalogue, sd.TRAY, 15):
        assert scene.tray_at is not None and 1 <= len(scene.items) <= 5
        for it in scene.items:
            c = it.corners() - scene.tray_at
            assert np.abs(c).max() <= tray.inside / 2 + 1e-9
            if it.pitch == 0.0:
                assert it.z == pytest.approx(tray.floor)
                touching += bool(np.abs(c).max() >= tray.inside / 2 - 0.002)
        items = [it for it in scene.items if it.pitch == 0.0]
        for i, p in enumerate(items):
            for q in items[i + 1 :]:
                assert not sd.overlap(p.corners(), q.corners())
                touching += sd.overlap(p.corners(0.002), q.corners())
    assert touching >= 5


def test_an_object_lying_across_rests_on_the_surface_and_the_other(catalogue):
    """Its lowest point is on the surface the lower object stands on, tilted at most 35
    degrees, and its underside rests on the lower object's top: no point of that top under
    its width lies above its underside, and one lies within 1 mm of it."""
    for scene in _scenes(catalogue, sd.ACROSS, 12):
        (long,) = [it for it in scene.items if it.pitch != 0.0]
        assert 0 < -long.pitch <= sd.MAX_ACROSS_TILT + 1e-9
        base = min(it.z for it in scene.items if it.pitch == 0.0)
        X = long.X_WO()
        lo, hi = long.box
        corners = np.array(np.meshgrid(*zip(lo, hi, strict=True))).reshape(3, -1).T
        world = corners @ X[:3, :3].T + X[:3, 3]
        assert world[:, 2].min() == pytest.approx(base, abs=1e-9)
        X_OW = np.linalg.inv(X)
        gaps = []
        for q in scene.items:
            if q is long or q.pitch != 0.0 or not sd.overlap(q.corners(), long.corners()):
                continue
            # a fine grid over q's top, in the long object's frame: its underside is z = 0
            qlo, qhi = q.box
            g = np.linspace(0, 1, 121)
            gx, gy = np.meshgrid(qlo[0] + g * (qhi[0] - qlo[0]), qlo[1] + g * (qhi[1] - qlo[1]))
            top = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, qhi[2]), np.ones(gx.size)])
            p = X_OW @ q.X_WO() @ top
            under = (p[0] >= lo[0]) & (p[0] <= hi[0]) & (np.abs(p[1]) <= hi[1])
            if under.any():
                gaps.append(float(p[2][under].max()))  # > 0: inside the long object
        assert gaps and max(gaps) < 1e-6, gaps
        assert max(gaps) > -0.001, gaps


def test_training_scenes_never_show_the_held_out_unknown_shapes(catalogue):
    """Two hundred training scenes (all kinds) draw unknown objects of the training kinds
    only; the test scenes only of the held-out kinds."""
    classes, fixtures = catalogue
    cfg = sd.DataConfig()
    seen = {"train": set(), "test": set()}
    for split in seen:
        for s in range(200 if split == "train" else 60):
            scene = sd.sample_scene(
                np.random.default_rng((5, s)), classes, cfg, split, fixtures.tray
            )
            seen[split] |= {it.kind for it in scene.items if it.cls == sd.UNKNOWN}
    assert seen["train"] and seen["train"] <= set(sd.UNKNOWN_TRAIN_KINDS)
    assert seen["test"] and seen["test"] <= set(sd.UNKNOWN_TEST_KINDS)
    assert len(seen["train"]) >= 6


def test_the_tray_is_table_and_its_views_carry_the_cells_fixtures(catalogue, tmp_path):
    """A tray scene rendered (Drake, ~1 s): the tray is never an instance, the scene file
    records the tray, and `view_fixtures` gives the detector what the cell gives it there
    (`Region.fixtures`): the floor as the plane and the wall pixels (high above the floor,
    no object's) left out."""
    classes, fixtures = catalogue
    cfg = sd.DataConfig(views=1)
    scene = next(
        sc
        for s in range(100)
        if sd.TRAY in (sc := sd.sample_scene(np.random.default_rng((2, s)), classes, cfg,
                                             "train", fixtures.tray)).tags
        and sc.held is None
    )  # fmt: skip
    (v,) = sd.render_scene(scene, classes, fixtures, cfg)
    sd.write_scene(tmp_path / "s.npz", [v], scene, fixtures.tray)
    record = sd.read_scene(tmp_path / "s.npz")
    assert list(record["tags"]) == list(scene.tags)
    assert record["tray"] == pytest.approx([*scene.tray_at, 0.01, 0.24, 0.26])
    K = v.K
    known = sd.view_fixtures(record, v.depth, (K[0, 0], K[1, 1], K[0, 2], K[1, 2]), v.X_WC)
    assert known["plane"] == pytest.approx(0.01)
    walls = known["exclude"]
    assert walls.any() and (v.cls[walls] == 1).mean() > 0.9  # the walls: table, no object
    assert (v.inst_cls[v.inst_cls >= 0] >= 2).all()  # every instance is an object's
    assert sd.view_fixtures({}, v.depth, (1, 1, 0, 0), v.X_WC) == {}
