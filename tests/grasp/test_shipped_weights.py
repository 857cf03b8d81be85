"""The shipped HRG-Net weights (tamp/models/weights/): load, run at 224x224 RGB-D, and find
correct grasps on synthetic scenes rendered with a seed the training set never used."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from tamp.grasp.predict import GraspPredictor

WEIGHTS = (
    Path(__file__).resolve().parents[2] / "tamp" / "models" / "weights" / "hrgnet_synth_rgbd.pt"
)


@pytest.fixture(scope="module")
def predictor() -> GraspPredictor:
    torch.set_num_threads(1)
    return GraspPredictor.load(WEIGHTS)


def test_weights_file_is_small_and_describes_itself(predictor):
    assert WEIGHTS.stat().st_size < 3_000_000
    assert predictor.meta["model"] == "hrgnet" and predictor.meta["input"] == "rgbd"
    assert predictor.meta["kwargs"]["fusion"] == "full"
    # fully convolutional: the 128 px network runs at 224 x 224 as well
    out = predictor.model(torch.zeros(1, 4, 224, 224))
    assert out.shape == (1, 4, 224, 224)


@pytest.mark.slow
@pytest.mark.parametrize("table", ["plain", "mats"])
def test_correct_grasps_on_new_scenes(predictor, tmp_path: Path, table: str):
    """On the plain beige table and on coloured mats like the LOTS workcell's (the weights
    are trained on ``--table mats``, whose scenes are three in four on a mat)."""
    from tamp.grasp import formats
    from tamp.grasp.datasets import GraspDataset
    from tamp.grasp.evaluate import evaluate
    from tamp.grasp.synthetic import SynthConfig, generate

    config = SynthConfig(size=predictor.size, views=2, seed=123, table=table)
    generate(tmp_path, 8, config, progress=False)
    ds = GraspDataset("jacquard", tmp_path, predictor.size, "rgbd")
    result = evaluate(predictor.model, ds, range(len(ds)), progress=False)
    assert result.accuracy >= 0.75, result.as_dict()
    # the robot's call: world point on an object (table top z = 0, objects under 8 cm)
    prefix = str(ds.samples[0].grasps)[: -len("_grasps.txt")]
    cam = json.loads(Path(prefix + "_camera.json").read_text())
    K, X = np.array(cam["K"]), np.array(cam["X_WC"])
    rgb = formats.read_rgb(prefix + "_RGB.png")
    depth = formats.read_depth_tiff(prefix + "_perfect_depth.tiff")
    grasps = predictor.predict(
        rgb=rgb, depth=depth, intrinsics=(K[0, 0], K[1, 1], K[0, 2], K[1, 2]), X_WC=X, n=3
    )
    assert len(grasps) == 3 and grasps[0].quality >= grasps[1].quality >= grasps[2].quality
    for g in grasps:
        assert -0.005 < g.position[2] < 0.1
        assert 0.0 < g.width_m < 0.15
