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
