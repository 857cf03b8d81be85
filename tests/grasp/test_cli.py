"""`tamp grasp ...`: exit codes, one-line errors, JSON output."""

from __future__ import annotations

import json
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
        meta = torch.load(tmp_path / mode / "final.pt", weights_only=False)["meta"]
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
    import pytest

    pytest.importorskip("pydrake")
    rc = main(["grasp", "synth", str(tmp_path / "s"), "--scenes", "2", "--views", "1",
               "--size", "48", "--seed", "3", "--json"])  # fmt: skip
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["scenes"] == 2
    assert len(list((tmp_path / "s").rglob("*_grasps.txt"))) == summary["images"]
    rc = main(["grasp", "synth", str(tmp_path / "t"), "--scenes", "0"])
    assert rc == 2 and "--scenes" in capsys.readouterr().err
