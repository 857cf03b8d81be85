"""The proposal classifier: its input (crop and metric features), its outputs, the training
labels of a proposal, and the detector's rules on top (``unknown`` threshold, ``none``)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from tamp.sim.core import cropnet
from tamp.sim.core.croptrain import choose_threshold, label_proposal
from tamp.sim.core.detector import Detector
from tamp.sim.core.instances import backproject_mask

INTR = (100.0, 100.0, 40.0, 30.0)
X_DOWN = np.eye(4)
X_DOWN[:3, :3] = np.diag([1.0, -1.0, -1.0])
X_DOWN[:3, 3] = [0.0, 0.0, 0.5]
OBJECTS = ["block", "ball", "unknown", "hand"]
OUTPUTS = cropnet.output_names(OBJECTS)


def _block():
    """A 20 x 8 px block 4 cm high under the camera (0.46 m away: 9.2 x 3.7 cm)."""
    depth = np.full((60, 80), 0.5, np.float32)
    mask = np.zeros((60, 80), bool)
    mask[26:34, 30:50] = True
    depth[mask] = 0.46
    heights = 0.5 - depth.astype(float)
    rgb = np.zeros((60, 80, 3), np.uint8)
    rgb[mask] = (200, 40, 40)
    return rgb, depth, heights, mask


def test_a_crop_holds_colour_height_and_mask_and_features_measure_the_object():
    rgb, depth, heights, mask = _block()
    x, f = cropnet.crop_input(
        rgb, heights, depth, mask, backproject_mask(mask, depth, INTR, X_DOWN)
    )
    assert x.shape == (5, cropnet.CROP, cropnet.CROP) and f.shape == (cropnet.FEATURES,)
    assert x[4].mean() == pytest.approx(8 / (20 * 1.25 + 2), abs=0.1)  # the mask's share
    assert x[3].max() == pytest.approx(0.04 / cropnet.HEIGHT_SCALE, abs=1e-5)
    assert x[0][x[4] > 0].mean() == pytest.approx(200 / 255 - 0.5, abs=1e-6)
    # length and width (decimetres; 9.2 x 3.7 cm less the 5 % tails), height, depth
    assert 0.75 < f[1] < 0.92 and 0.25 < f[2] < 0.37
    assert f[3] == pytest.approx(0.4, abs=1e-4) and f[4] == pytest.approx(5 * 0.46)
    assert f[5] == 0.0  # not on the image border


def test_the_classifier_gives_a_distribution_over_its_outputs():
    torch.manual_seed(0)
    model = cropnet.CropNet(len(OUTPUTS)).eval()
    rgb, depth, heights, mask = _block()
    x, f = cropnet.crop_input(
        rgb, heights, depth, mask, backproject_mask(mask, depth, INTR, X_DOWN)
    )
    p = cropnet.classify(model, np.stack([x, x]), np.stack([f, f]))
    assert p.shape == (2, len(OUTPUTS)) and np.allclose(p.sum(axis=1), 1.0, atol=1e-5)
    assert cropnet.classify(
        model, np.zeros((0, 5, 32, 32), np.float32), np.zeros((0, 6))
    ).shape == (
        0,
        len(OUTPUTS),
    )


def test_a_task_class_below_the_threshold_is_unknown_and_none_is_dropped():
    meta = {"classes": ["background", "table", *OBJECTS], "outputs": OUTPUTS,
            "unknown_below": 0.6}  # fmt: skip
    det = Detector(cropnet.CropNet(len(OUTPUTS)), meta)

    def probs(**share):
        p = np.zeros(len(OUTPUTS))
        for k, v in share.items():
            p[OUTPUTS.index(k)] = v
        return p

    assert det.label(probs(block=0.55, ball=0.45)) == ("unknown", 0.55)  # unsure
    assert det.label(probs(block=0.9, ball=0.1))[0] == "block"
    # hand and unknown are never turned into anything else; none is dropped
    assert det.label(probs(hand=0.4, block=0.3, ball=0.3))[0] == "hand"
    assert det.label(probs(none=0.6, block=0.4))[0] is None


def test_training_labels_name_one_object_several_or_none():
    inst = np.zeros((20, 20), np.uint8)
    inst[2:8, 2:8] = 1  # class 2 (the first object class after background and table)
    inst[2:8, 8:14] = 2  # class 3, touching it
    inst_cls = np.full(256, -1, np.int16)
    inst_cls[1], inst_cls[2] = 2, 3
    both = inst > 0
    assert OUTPUTS[label_proposal(both, inst, inst_cls, OUTPUTS)] == cropnet.SEVERAL
    one = inst == 1
    one[8:10, 2:8] = True  # a little table around it
    assert OUTPUTS[label_proposal(one, inst, inst_cls, OUTPUTS)] == "block"
    table = np.zeros_like(both)
    table[12:20, 0:20] = True
    table[7, 2] = True
    assert OUTPUTS[label_proposal(table, inst, inst_cls, OUTPUTS)] == cropnet.NONE


def test_the_threshold_trades_right_names_against_wrong_task_classes():
    """Sure and right proposals keep their class; unsure ones that are mostly wrong are
    better reported unknown: the threshold lands between the two confidences."""
    sure = np.array([0.9, 0.02, 0.02, 0.02, 0.02, 0.02])
    unsure = np.array([0.2, 0.5, 0.1, 0.1, 0.05, 0.05])
    probs = np.stack([sure] * 10 + [unsure] * 10)
    labels = np.array([0] * 10 + [0] * 8 + [1] * 2)
    t = choose_threshold(probs, labels, OUTPUTS)
    assert 0.5 < t <= 0.9


def test_touching_parts_named_hand_are_one_hand():
    """Fingers and forearm split at depth jumps are one hand; a hand elsewhere stays its
    own, and other classes are untouched."""
    from tamp.sim.core.detector import _hands_joined

    def box(r0, r1, c0, c1):
        m = np.zeros((20, 30), bool)
        m[r0:r1, c0:c1] = True
        return m

    parts = [(box(0, 5, 0, 5), "hand", 0.9), (box(5, 9, 0, 5), "hand", 0.6),
             (box(0, 5, 20, 25), "hand", 0.8), (box(5, 9, 6, 9), "block", 0.9)]  # fmt: skip
    out = _hands_joined(parts)
    hands = sorted(int(m.sum()) for m, c, _ in out if c == "hand")
    assert hands == [25, 45] and [c for _, c, _ in out].count("block") == 1
    assert next(s for m, c, s in out if c == "hand" and m.sum() == 45) == 0.9


def test_parts_of_one_class_are_candidates_to_join_when_they_touch_or_share_a_proposal():
    """A tower's bottom seen round the body on it is split into strips on either side that
    do not touch: parts of one proposal are a group as touching parts are; parts of two
    proposals that do not touch are not, nor are parts of different classes."""
    from tamp.sim.core.detector import _related_groups

    def box(c0, c1):
        m = np.zeros((20, 40), bool)
        m[5:15, c0:c1] = True
        return m

    left, right, far = box(0, 5), box(15, 20), box(30, 35)
    groups = _related_groups([(left, "bottom", 0), (right, "bottom", 0), (far, "bottom", 1)])
    assert [sorted(int(m.nonzero()[1].min()) for m, _ in g) for g in groups] == [[0, 15]]
    assert _related_groups([(left, "bottom", 0), (right, "bottom", 1)]) == []
    assert _related_groups([(left, "bottom", 0), (right, "body", 0)]) == []
    touching = _related_groups([(box(0, 5), "saw", 0), (box(5, 9), "saw", 1), (far, "saw", 2)])
    assert [len(g) for g in touching] == [2]


def test_a_class_is_only_given_to_a_proposal_of_its_size():
    """The size gate: larger than the class ever was (with the 10 % slack) is no member of
    it; smaller is only judged when the proposal is wholly inside the image; the detector
    reports a sure class of the wrong size as ``unknown``."""
    sizes = {"low": [0.05, 0.02, 0.01], "high": [0.10, 0.04, 0.03]}
    f = np.array([0.0, 0.8, 0.3, 0.2, 2.0, 0.0])  # 8 x 3 x 2 cm, inside the image
    assert cropnet.size_gate(f, sizes) and cropnet.size_gate(f, None)
    assert not cropnet.size_gate(f + [0, 0.4, 0, 0, 0, 0], sizes)  # 12 cm long
    small = f - [0, 0.5, 0, 0, 0, 0]  # 3 cm long
    assert not cropnet.size_gate(small, sizes)
    assert cropnet.size_gate(small + [0, 0, 0, 0, 0, 1.0], sizes)  # cut by the image edge
    meta = {"classes": ["background", "table", *OBJECTS], "outputs": OUTPUTS,
            "unknown_below": 0.5, "sizes": {"block": sizes}}  # fmt: skip
    det = Detector(cropnet.CropNet(len(OUTPUTS)), meta)
    p = np.zeros(len(OUTPUTS))
    p[0] = 0.99
    assert det.label(p, f)[0] == "block" and det.label(p, f + [0, 0.4, 0, 0, 0, 0])[0] == "unknown"
