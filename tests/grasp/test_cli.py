"""`tamp grasp ...`: exit codes, one-line errors, JSON output."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch

from tamp.commands.main import main
from tamp.grasp import formats


@pytest.mark.slow
def test_train_eval_predict_round_trip(jacquard_dir: Path, tmp_path: Path, capsys):
    out = tmp_path / "run"
    rc = main(["grasp", "train", "--dataset", "jacquard", str(jacquard_dir), "--model", "ggcnn",
               "--input", "d", "--size", "32", "--epochs", "1", "--batches-per-epoch", "2",
               "--batch-size", "2", "--split", "object", "--test-fraction", "0.25",
               "--out", str(out), "--quiet", "--json"])  # fmt: skip
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["config"]["model"] == "ggcnn" and summary["history"][0]["epoch"] == 1
    rc = main(["grasp", "eval", str(out / "best.pt"), "--dataset", "jacquard", str(jacquard_dir),
               "--split", "both", "--test-fraction", "0.25", "--time-size", "32", "--quiet",
               "--json"])  # fmt: skip
    assert rc == 0
    result = json.loads(capsys.readouterr().out)
    assert result["object_wise"]["images"] == 2 and result["image_wise"]["images"] == 2
    assert result["time"]["median_ms"] > 0
    depth = next(jacquard_dir.rglob("*_perfect_depth.tiff"))
    cam = tmp_path / "camera.json"
    cam.write_text(json.dumps({"K": [[50, 0, 31.5], [0, 50, 31.5], [0, 0, 1]],
                               "X_WC": np.eye(4).tolist()}))  # fmt: skip
    rc = main(["grasp", "predict", str(depth), "--weights", str(out / "best.pt"), "--camera",
               str(cam), "--top", "2", "--json"])  # fmt: skip
    assert rc == 0
    grasps = json.loads(capsys.readouterr().out)
    assert len(grasps) == 2
    for g in grasps:
        assert 0 <= g["u"] < 64 and 0 <= g["v"] < 64
        # identity camera pose: the world point is the camera-frame point at the depth
        d = formats.read_depth_tiff(depth)
        assert abs(g["position"][2] - np.median(d)) < 0.05


@pytest.mark.slow
def test_eval_uses_the_recorded_split_and_warns_otherwise(
    jacquard_dir: Path, tmp_path: Path, capsys
):
    """Weights record their split; eval tests on it by default, and says so when asked for
    another split (counting the test images the weights were trained on), another dataset,
    or when the weights record no split."""
    out = tmp_path / "run"
    rc = main(["grasp", "train", "--dataset", "jacquard", str(jacquard_dir), "--model", "ggcnn",
               "--input", "d", "--size", "32", "--epochs", "1", "--batches-per-epoch", "1",
               "--batch-size", "2", "--split", "object", "--test-fraction", "0.25",
               "--val-fraction", "0.25", "--seed", "2", "--out", str(out), "--quiet"])  # fmt: skip
    assert rc == 0 and "best validation epoch 1" in capsys.readouterr().out
    weights = str(out / "final.pt")
    base = ["grasp", "eval", weights, "--dataset", "jacquard", str(jacquard_dir),
            "--time-size", "32", "--quiet", "--json"]  # fmt: skip

    def run(*flags):
        assert main(base + list(flags)) == 0
        captured = capsys.readouterr()
        return json.loads(captured.out), captured.err

    result, err = run()
    assert result["warnings"] == [] and err == ""
    recorded = result["trained_split"]
    assert recorded["kind"] == "object" and recorded["seed"] == 2
    assert result["object_wise"]["split"]["seed"] == 2 and result["object_wise"]["images"] == 2
    assert result["width_calibration"]["part"] == "validation"
    assert "mean_abs_rel" in result["object_wise"]["width"]

    result, err = run("--split", "image")
    assert "image-wise test set holds other views of the objects" in err
    n = len([w for w in result["warnings"] if "are training images of these weights" in w])
    assert n == 1 and err.count("tamp grasp eval: warning:") == len(result["warnings"])

    result, err = run("--seed", "0")
    assert "evaluating object-wise, seed 0" in err and "trained with object-wise, seed 2" in err

    other = tmp_path / "other"
    shutil.copytree(jacquard_dir, other)
    shutil.rmtree(other / "obj0")
    assert main(["grasp", "eval", weights, "--dataset", "jacquard", str(other), "--time-size",
                 "32", "--quiet"]) == 0  # fmt: skip
    err = capsys.readouterr().err
    assert "the dataset differs from the one the weights were trained on (6 samples" in err

    blob = torch.load(weights, weights_only=True)
    del blob["meta"]["split"]
    torch.save(blob, tmp_path / "old.pt")
    base[2] = str(tmp_path / "old.pt")
    result, err = run()
    assert "the weights record no training split" in err
    assert result["image_wise"]["split"]["seed"] == 0  # the old default: image-wise, seed 0


def test_bad_input_exits_2_with_one_line(tmp_path: Path, capsys):
    rc = main(["grasp", "train", "--dataset", "jacquard", str(tmp_path / "missing")])
    err = capsys.readouterr().err
    assert rc == 2 and "missing: dataset folder not found" in err and "Traceback" not in err
    rc = main(["grasp", "train", "--dataset", "imagenet", str(tmp_path)])
    assert rc == 2 and "unknown kind 'imagenet'" in capsys.readouterr().err
    rc = main(["grasp", "predict", str(tmp_path / "nope.png"), "--weights", str(tmp_path / "w")])
    assert rc == 2 and "nope.png: file not found" in capsys.readouterr().err
    (tmp_path / "junk.pt").write_bytes(b"junk")
    img = tmp_path / "d.tiff"
    formats.write_depth_tiff(img, np.ones((8, 8), np.float32))
    rc = main(["grasp", "predict", str(img), "--weights", str(tmp_path / "junk.pt")])
    assert rc == 2 and "junk.pt: not a grasp weights file" in capsys.readouterr().err


def test_bad_model_arg(jacquard_dir: Path, tmp_path: Path, capsys):
    rc = main(["grasp", "train", "--dataset", "jacquard", str(jacquard_dir), "--model-arg",
               "depth=3", "--out", str(tmp_path / "x"), "--quiet"])  # fmt: skip
    assert rc == 2 and "--model-arg" in capsys.readouterr().err


@pytest.mark.slow
def test_fusion_modes(jacquard_dir: Path, tmp_path: Path, capsys):
    base = ["grasp", "train", "--dataset", "jacquard", str(jacquard_dir), "--size", "32",
            "--epochs", "1", "--batches-per-epoch", "1", "--batch-size", "2", "--quiet",
            "--json", "--model-arg", "widths=[4,8]"]  # fmt: skip
    for flags, mode in ((["--fusion", "final"], "final"), (["--no-fusion"], "none")):
        rc = main(base + flags + ["--out", str(tmp_path / mode)])
        assert rc == 0
        assert json.loads(capsys.readouterr().out)["config"]["fusion"] == mode
        meta = torch.load(tmp_path / mode / "final.pt", weights_only=True)["meta"]
        assert meta["kwargs"]["fusion"] == mode
    for flags, message in (
        (["--no-fusion", "--fusion", "final"], "--no-fusion contradicts --fusion final"),
        (["--fusion", "none", "--model", "ggcnn"], "HRG-Net only"),
        (["--fusion", "half"], "invalid choice"),
    ):
        rc = main(base + flags + ["--out", str(tmp_path / "bad")])
        assert rc == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()


def test_synth_writes_a_jacquard_set(tmp_path: Path, capsys):
    rc = main(["grasp", "synth", str(tmp_path / "s"), "--scenes", "2", "--views", "1",
               "--size", "48", "--seed", "3", "--json"])  # fmt: skip
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["scenes"] == 2
    assert len(list((tmp_path / "s").rglob("*_grasps.txt"))) == summary["images"]
    rc = main(["grasp", "synth", str(tmp_path / "t"), "--scenes", "0"])
    assert rc == 2 and "--scenes" in capsys.readouterr().err
    from tamp.grasp.synthetic import TABLES

    for table in TABLES:  # every kind of table the renderer knows is on the command line
        rc = main(["grasp", "synth", str(tmp_path / table), "--scenes", "1", "--views", "1",
                   "--size", "32", "--table", table, "--json"])  # fmt: skip
        assert rc == 0 and json.loads(capsys.readouterr().out)["scenes"] == 1
    rc = main(["grasp", "synth", str(tmp_path / "g"), "--table", "green"])
    assert rc == 2 and "'plain', 'mats'" in capsys.readouterr().err


def _bar_scene(tmp_path: Path) -> tuple[Path, np.ndarray]:
    """A red bar 5 cm above a table seen from 0.6 m (the scene of tests/test_wheel.py)."""
    n = 96
    depth = np.full((n, n), 0.60, np.float32)
    rgb = np.full((n, n, 3), 150, np.uint8)
    depth[40:56, 30:66] = 0.55
    rgb[40:56, 30:66] = (200, 40, 40)
    formats.write_rgb(tmp_path / "rgb.png", rgb)
    return tmp_path / "rgb.png", depth


@pytest.mark.parametrize(
    "fill, dtype, message",
    [(np.nan, np.float32, "no valid depth: 0 of 9216 pixels in 0.05-5 m, 9216 holes (0 or NaN)"),
     (0.0, np.float32, "9216 holes (0 or NaN)"),
     (-0.6, np.float32, "9216 of 9216 pixels have negative depth"),
     (7.0, np.float32, "9216 farther than 5 m; --depth-range MIN,MAX sets the range"),
     (600, np.uint16, "values near 600 look like millimetres: depth must be in metres")],
)  # fmt: skip
def test_hostile_depth_image_exits_2_naming_the_file(tmp_path: Path, capsys, fill, dtype, message):
    """All NaN, all zero, all negative, all beyond the sensor's range, millimetres: bad
    input, before any weights are read."""
    import tifffile

    rgb, _ = _bar_scene(tmp_path)
    bad = tmp_path / "D.tiff"
    tifffile.imwrite(bad, np.full((96, 96), fill, dtype))
    no_weights = str(tmp_path / "none.pt")
    rc = main(["grasp", "predict", str(rgb), "--depth", str(bad), "--weights", no_weights])
    err = capsys.readouterr().err
    assert rc == 2 and f"{bad}: " in err and message in err and err.count("\n") == 1, err
    rc = main(["grasp", "predict", str(bad), "--weights", no_weights, "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert rc == 2 and doc["exit"] == 2 and doc["file"] == str(bad) and message in doc["error"]


@pytest.mark.parametrize(
    "flags, message",
    [(["--depth-range", "1,0.5"], "--depth-range: depth range needs 0 < MIN < MAX"),
     (["--depth-range", "near,far"], "--depth-range: expected MIN,MAX in metres"),
     (["--depth-range", "0.05,0.5"], "9216 farther than 0.5 m"),
     (["--top", "0"], "--top must be >= 1")],
)  # fmt: skip
def test_bad_depth_range_and_top_exit_2(tmp_path: Path, capsys, flags, message):
    rgb, depth = _bar_scene(tmp_path)
    formats.write_depth_tiff(tmp_path / "d.tiff", depth)
    rc = main(["grasp", "predict", str(rgb), "--depth", str(tmp_path / "d.tiff"), *flags])
    assert rc == 2 and message in capsys.readouterr().err


def test_depth_holes_off_the_object_still_grasp_it_on_valid_depth(tmp_path: Path, capsys):
    """A real camera's holes (NaN to the right, zeros along the top, a little beyond the
    range in a corner) away from the bar: the grasp is on the bar, on measured depth."""
    rgb, depth = _bar_scene(tmp_path)
    depth[:, 70:] = np.nan
    depth[:20] = 0.0
    depth[80:, :10] = 9.0
    formats.write_depth_tiff(tmp_path / "d.tiff", depth)
    down = "1 0 0 0  0 -1 0 0  0 0 -1 0.6  0 0 0 1".split()
    rc = main(["grasp", "predict", str(rgb), "--depth", str(tmp_path / "d.tiff"),
               "--intrinsics", "100", "100", "47.5", "47.5", "--pose", *down,
               "--top", "2", "--json"])  # fmt: skip
    assert rc == 0
    for g in json.loads(capsys.readouterr().out):
        assert 30 <= g["u"] <= 66 and 40 <= g["v"] <= 56, g
        assert g["position"][2] == pytest.approx(0.05, abs=0.01)


def test_no_grasp_where_the_object_has_no_depth_exits_1(tmp_path: Path, capsys):
    """The bar (and its rim) is a hole: the network still sees it in colour, but every grasp
    it rates best lies where the camera measured nothing: no grasp, exit 1, the reason."""
    rgb, depth = _bar_scene(tmp_path)
    depth[35:61, 25:71] = np.nan
    d = tmp_path / "d.tiff"
    formats.write_depth_tiff(d, depth)
    rc = main(["grasp", "predict", str(rgb), "--depth", str(d)])
    err = capsys.readouterr().err
    assert rc == 1 and f"{d}: no grasp: the network's best grasps lie on invalid depth" in err
    assert "8020 of 9216 pixels in 0.05-5 m, 1196 holes" in err
    rc = main(["grasp", "predict", str(rgb), "--depth", str(d), "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert rc == 1 and doc["exit"] == 1 and "no grasp" in doc["error"]
