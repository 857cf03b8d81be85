"""The detector: a tiny model trains and is scored through the command line; the shipped
weights are small, record their split, find the catalogue's objects in scenes rendered from a
seed training never used, work at the wrist camera's full size, and never give a task class
to an object they were not trained on."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from tamp.commands.detect import default_weights, workcell_catalogue
from tamp.commands.main import main as tamp_main
from tamp.sim.core import segdata as sd
from tamp.sim.core.detector import Detector
from tamp.sim.core.segtrain import Tally, report, score_view, true_instances

UNKNOWN_SDF = Path(__file__).parent / "data" / "unknown_dumbbell.sdf"


@pytest.fixture(scope="module")
def catalogue():
    return workcell_catalogue()


@pytest.fixture(scope="module")
def detector() -> Detector:
    torch.set_num_threads(1)
    return Detector.load()


def test_a_tiny_model_trains_and_is_scored_through_the_command_line(tmp_path, capsys):
    """render (3 scenes, 1 view) -> train (5 steps) -> eval, each with --json (schema 1)."""
    data, run = tmp_path / "data", tmp_path / "run"
    assert tamp_main(["detect", "render", str(data), "--scenes", "3", "--views", "1",
                      "--seed", "4", "--json"]) == 0  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == 1 and doc["views"] == 3
    assert tamp_main(["detect", "train", str(data), "--out", str(run), "--steps", "5",
                      "--batch-size", "2", "--width", "4", "--threads", "1", "--quiet",
                      "--json"]) == 0  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == 1 and doc["steps"] == 5 and doc["device"] in ("cpu", "cuda")
    assert doc["split"]["kind"] == "object" and doc["split"]["scenes"] == 3
    weights = run / "final.pt"
    meta = torch.load(weights, weights_only=True)["meta"]
    assert meta["classes"] == list(sd.class_names(workcell_catalogue()[0]))
    assert meta["size"] == [160, 90] and meta["width"] == 4
    # more steps from those weights (--init); another width is refused naming the file
    assert tamp_main(["detect", "train", str(data), "--out", str(tmp_path / "more"), "--steps",
                      "2", "--batch-size", "2", "--width", "4", "--init", str(weights),
                      "--threads", "1", "--quiet"]) == 0  # fmt: skip
    capsys.readouterr()
    assert tamp_main(["detect", "train", str(data), "--out", str(tmp_path / "bad"), "--steps",
                      "2", "--width", "8", "--init", str(weights), "--quiet"]) == 2  # fmt: skip
    assert "final.pt: --init" in capsys.readouterr().err
    # the proposal classifier (the shipped detector's kind) through the same command
    assert tamp_main(["detect", "train", str(data), "--out", str(tmp_path / "crops"),
                      "--kind", "classifier", "--epochs", "1", "--width", "4", "--threads",
                      "1", "--quiet", "--json"]) == 0  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == 1 and doc["epochs"] == 1 and doc["proposals"] > 0
    crops = torch.load(tmp_path / "crops" / "final.pt", weights_only=True)["meta"]
    assert crops["kind"] == "crop_classifier" and crops["outputs"][-2:] == ["several", "none"]
    assert 0.3 <= crops["unknown_below"] < 1.0
    # fine-tuning the classifier (--init): its size gate spans the start's and the fit's
    start = tmp_path / "crops" / "final.pt"
    assert tamp_main(["detect", "train", str(data), "--out", str(tmp_path / "tuned"),
                      "--kind", "classifier", "--epochs", "1", "--width", "4", "--init",
                      str(start), "--unknown-below", "0.85", "--threads", "1",
                      "--quiet"]) == 0  # fmt: skip
    capsys.readouterr()
    tuned = torch.load(tmp_path / "tuned" / "final.pt", weights_only=True)["meta"]
    assert tuned["training"]["init"] == str(start)
    assert tuned["unknown_below"] == 0.85 and 0.3 <= tuned["held_back"]["chosen"] < 1.0
    for name, span in crops["sizes"].items():
        assert all(a <= b for a, b in zip(tuned["sizes"][name]["low"], span["low"], strict=True))
        assert all(a >= b for a, b in zip(tuned["sizes"][name]["high"], span["high"], strict=True))
    # segmentation weights (or another width) cannot start a classifier: exit 2, the file
    assert tamp_main(["detect", "train", str(data), "--kind", "classifier", "--width", "4",
                      "--init", str(weights), "--quiet"]) == 2  # fmt: skip
    assert "final.pt: " in capsys.readouterr().err
    assert tamp_main(["detect", "train", str(data), "--kind", "classifier",
                      "--unknown-below", "1.5", "--quiet"]) == 2  # fmt: skip
    assert "--unknown-below" in capsys.readouterr().err
    # score on the training scenes too (the test part of 3 scenes may be empty)
    info = sd.read_info(data)
    assert len(info.train) + len(info.test) == 3
    assert tamp_main(["detect", "eval", str(weights), str(data), "--out", str(tmp_path),
                      "--json"]) == 0  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == 1 and doc["views"] == len(info.test)
    assert (tmp_path / "detector_eval.json").is_file()
    assert tamp_main(["detect", "eval", str(tmp_path / "crops" / "final.pt"), str(data),
                      "--json"]) == 0  # fmt: skip
    assert json.loads(capsys.readouterr().out)["views"] == len(info.test)


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert tamp_main(["detect", "train", str(tmp_path), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "dataset.json" in err and "Traceback" not in err
    assert tamp_main(["detect", "render", str(tmp_path), "--scenes", "0"]) == 2
    junk = tmp_path / "junk.pt"
    junk.write_bytes(b"not torch")
    sd_dir = tmp_path / "d"
    sd_dir.mkdir()
    (sd_dir / sd.DATASET_FILE).write_text("{}")
    assert tamp_main(["detect", "eval", str(junk), str(sd_dir)]) == 2


def test_the_shipped_weights_are_small_and_record_their_split(detector, catalogue):
    path = default_weights()
    assert path.stat().st_size < 2_000_000
    meta = detector.meta
    assert list(meta["classes"]) == list(sd.class_names(catalogue[0]))
    split = meta["split"]
    assert split["kind"] == "object" and split["test_scenes"] > 0
    assert split["unknown_test_kinds"] == list(sd.UNKNOWN_TEST_KINDS)
    assert meta["parameters"] < 500_000


def _views(scene, catalogue, cfg: sd.DataConfig):
    classes, fixtures = catalogue
    return sd.render_scene(scene, classes, fixtures, cfg)


def test_the_shipped_weights_count_scenes_from_an_unseen_seed(detector, catalogue):
    """Eight scenes of seed 99 (training used seed 0): the instances found with their class,
    how well their masks fit, and how few are invented. Plain scenes (no stacks, no object
    lying across another: the shipped weights never saw them; the benchmark scores them)."""
    classes, _ = catalogue
    cfg = sd.DataConfig(views=2, stack_share=0.0, across_share=0.0)
    tally = Tally(list(detector.classes))
    for s in range(8):
        scene = sd.sample_scene(np.random.default_rng((99, s)), classes, cfg, "test")
        for v in _views(scene, catalogue, cfg):
            K = v.K
            found = detector.detect(v.rgb, v.depth, (K[0, 0], K[1, 1], K[0, 2], K[1, 2]), v.X_WC)
            truth, small = true_instances(
                v.inst, v.inst_cls, detector.min_pixels, v.depth, list(detector.classes)
            )
            score_view(tally, found, truth, small)
    r = report(tally)
    assert r["views"] == 16
    true_instances_total = sum(sum(row) for row in r["confusion"]["matrix"][:-1])
    # found with their own class and a mask IoU >= 0.5 (the benchmark's figure on the
    # held-out test scenes is the reference; this guards against a broken detector:
    # the shipped weights find 50 of 61 here, with a mask IoU of 0.95)
    assert r["matched_instances"] >= 0.65 * true_instances_total
    assert r["mask_iou_matched"] > 0.85
    assert r["false_positives_per_view"] < 1.0
    assert r["task_instances"]["other_task_class"] <= 1


def test_full_size_images_give_full_size_masks_and_world_points(detector, catalogue):
    """A 320 x 180 image (the LOTS wrist camera) is subsampled for the network; masks come
    back at 320 x 180 and points lie where the 160 x 90 detection puts them."""
    classes, _ = catalogue
    scene = sd.sample_scene(np.random.default_rng((98, 0)), classes, sd.DataConfig(views=1), "test")
    (v,) = _views(scene, catalogue, sd.DataConfig(views=1))
    K = v.K
    intr = (K[0, 0], K[1, 1], K[0, 2], K[1, 2])
    small = detector.detect(v.rgb, v.depth, intr, v.X_WC)
    big = detector.detect(
        v.rgb.repeat(2, 0).repeat(2, 1),
        v.depth.repeat(2, 0).repeat(2, 1),
        (2 * intr[0], 2 * intr[1], 2 * intr[2] + 0.5, 2 * intr[3] + 0.5),
        v.X_WC,
    )
    assert small and len(big) == len(small)
    for a, b in zip(sorted(small, key=lambda d: d.u), sorted(big, key=lambda d: d.u), strict=True):
        assert b.mask.shape == (180, 320) and b.cls == a.cls
        assert b.pixels == 4 * a.pixels
        assert np.allclose(a.centroid, b.centroid, atol=0.005)


def test_an_object_the_detector_never_saw_is_unknown_or_ignored(detector, catalogue):
    """A test-only shape (a dumbbell, ``tests/sim/core/data/unknown_dumbbell.sdf``) beside
    catalogue objects, in twelve views: no detection of a task class lies mostly on it."""
    classes, fixtures = catalogue
    dumbbell = sd.object_class("dumbbell", UNKNOWN_SDF)
    cfg = sd.DataConfig(views=3)
    names = list(detector.classes)
    reported = []
    for s in range(4):
        scene = sd.sample_scene(np.random.default_rng((97, s)), classes, cfg, "test")
        items = [i for i in scene.items if i.cls != sd.UNKNOWN][:2]
        thing = sd.Item(sd.UNKNOWN, dumbbell.visuals, 0.0, 0.0, 0.3 * s)
        for i, it in enumerate(items):  # make room at the origin
            items[i] = sd.Item(it.cls, it.visuals, 0.18 * (1 if i else -1), 0.1, it.yaw)
        cams = sd.sample_cameras(np.random.default_rng(s), [thing], cfg, 0.05)
        scene = sd.Scene(tuple([thing, *items]), (), scene.table_rgba, scene.lights, None,
                         tuple(cams))  # fmt: skip
        for v in sd.render_scene(scene, classes, fixtures, cfg):
            ids = [k for k in np.unique(v.inst)[1:] if names[v.inst_cls[k]] == sd.UNKNOWN]
            if not ids:
                continue
            mask = v.inst == ids[0]
            K = v.K
            for d in detector.detect(v.rgb, v.depth, (K[0, 0], K[1, 1], K[0, 2], K[1, 2]), v.X_WC):
                if (d.mask & mask).sum() > 0.5 * d.mask.sum():
                    reported.append(d.cls)
    assert all(c in (sd.UNKNOWN, sd.HAND) for c in reported), reported


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="split at its levels, the tower shows its bottom and peak, but the body between "
    "them (two 1 cm strips round the peak) is named unknown in every view by the shipped "
    "weights; the LOTS cell's perception reads the tower by its heights instead "
    "(test_a_three_high_tower_is_read_by_its_heights)",
)
def test_the_shipped_detector_counts_a_three_high_tower(detector, catalogue):
    """Fig. 10's tower (bottom, body on it, peak on that; `tamp.sim.lots.stack`) rendered
    from four wrist views above it (Drake, ~2 s): each view counts one of each level."""
    counts = [sorted(d.cls for d in found) for found, _ in _three_high_tower(detector, catalogue)]
    assert counts == [["body", "bottom", "peak"]] * 4, counts


@pytest.mark.slow
def test_a_three_high_tower_is_read_by_its_heights(detector, catalogue):
    """The same views read as the LOTS cell's perception reads W^B (`on_table`, then
    `stack_reading.read_stack` with the catalogue models' heights): one of each level in
    every view, the lower levels under the peak's middle."""
    from tamp.sim.core.perception import on_table
    from tamp.sim.core.stack_reading import StackModel, read_stack
    from tamp.sim.lots.scenario import load_cell_scenario

    cell = load_cell_scenario("tower")
    order = ("bottom", "body", "peak")
    model = StackModel("B", order, tuple(cell.object_class(c).footprint.top for c in order))
    for found, (depth, K, X_WC) in _three_high_tower(detector, catalogue):
        read = read_stack(on_table(found, depth, K, X_WC), model, depth, K, X_WC)
        assert sorted(d.cls for d in read) == ["body", "bottom", "peak"], [d.cls for d in found]
        xy = np.array([d.centroid[:2] for d in read])
        assert np.ptp(xy, axis=0).max() < 1e-9  # one column: the peak's middle


def _three_high_tower(detector, catalogue) -> list:
    """The detector's objects in four wrist views of Fig. 10's tower, each with its (depth,
    intrinsics, camera pose)."""
    classes, fixtures = catalogue
    by_name = {c.name: c for c in classes}
    cfg = sd.DataConfig(views=4)
    rng = np.random.default_rng(11)
    tower = [sd.Item("bottom", by_name["bottom"].visuals, 0.02, -0.03, 0.4, kind="bottom")]
    for name in ("body", "peak"):
        tower.append(sd.stacked(tower[-1], by_name[name], rng))
    cams = sd.sample_cameras(rng, tower[:1], cfg, max(it.top for it in tower))
    scene = sd.Scene(tuple(tower), (), (0.6, 0.55, 0.45, 1.0), ({"direction": [0.2, 0.1, -1.0],
                     "intensity": 0.9, "color": [1.0, 1.0, 1.0]},), None, tuple(cams))  # fmt: skip
    out = []
    for v in sd.render_scene(scene, classes, fixtures, cfg):
        K = (v.K[0, 0], v.K[1, 1], v.K[0, 2], v.K[1, 2])
        out.append((detector.detect(v.rgb, v.depth, K, v.X_WC), (v.depth, K, v.X_WC)))
    return out


def _counted_from_the_look_pose(detector, catalogue, items, table_rgba) -> list[str]:
    """The classes the detector reports for ``items`` (`segdata.Item`s) rendered from the LOTS
    look pose: straight down from 0.47 m, 320 x 180."""
    classes, fixtures = catalogue
    cfg = sd.DataConfig(views=1, width=320, height=180)
    X_WC = np.eye(4)
    X_WC[:3, :3] = np.diag([1.0, -1.0, -1.0])  # straight down
    X_WC[:3, 3] = [0.03, -0.04, 0.47]
    light = ({"direction": [0.2, 0.1, -1.0], "intensity": 0.9, "color": [1.0, 1.0, 1.0]},)
    scene = sd.Scene(tuple(items), (), table_rgba, light, None, (X_WC,))
    (v,) = sd.render_scene(scene, classes, fixtures, cfg)
    K = v.K
    found = detector.detect(v.rgb, v.depth, (K[0, 0], K[1, 1], K[0, 2], K[1, 2]), v.X_WC)
    return sorted(d.cls for d in found)


@pytest.mark.slow
def test_a_body_stacked_on_a_bottom_is_two_detections(detector, catalogue):
    """Fig. 10 with the learned detector: the person puts a body on the bottom in W^B; the
    proposal is named ``several`` but no depth step parts it (the body's sides run on into
    the bottom's). Split at its levels (the bottom's top showing round the body), each part
    is named. The two-high stack at six yaws, seen from the LOTS look pose: 4 of 6 views
    count a bottom and a body (3 before the level split: most such stacks are parted by the
    8 mm depth step; the level split is for those that are not, as the narrative's was;
    `test_instances.py` tests the split itself)."""
    by_name = {c.name: c for c in catalogue[0]}
    rng = np.random.default_rng(11)
    counts = []
    for yaw in np.linspace(0.0, 3.0, 6):
        bottom = sd.Item("bottom", by_name["bottom"].visuals, 0.0, 0.0, float(yaw), kind="bottom")
        stack = (bottom, sd.stacked(bottom, by_name["body"], rng))
        counts.append(
            _counted_from_the_look_pose(detector, catalogue, stack, (0.6, 0.55, 0.45, 1.0))
        )
    assert sum(c == ["body", "bottom"] for c in counts) >= 4, counts


@pytest.mark.parametrize("name", ["saw", "hammer", "screwdriver"])
def test_an_object_of_parts_at_two_heights_is_one_detection(detector, catalogue, name):
    """A saw's handle stands 3 cm over its flat blade: the depth jump splits the proposal in
    two and each part looks like a saw (Fig. 9 with the learned detector counted a phantom
    second saw in W^B; before the join, three of these six saw views counted two). Touching
    parts of one class are one object when their union is named that class too: the tool
    alone at six yaws, seen from the LOTS look pose, counts one."""
    by_name = {c.name: c for c in catalogue[0]}
    counts = [
        _counted_from_the_look_pose(
            detector,
            catalogue,
            [sd.Item(name, by_name[name].visuals, 0.0, 0.0, float(yaw))],
            (0.55, 0.62, 0.85, 1.0),
        )
        for yaw in np.linspace(0.0, 3.0, 6)
    ]
    assert counts == [[name]] * 6, counts
