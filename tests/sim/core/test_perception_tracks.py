"""`Perception` as a system (fixed image inputs, no plant): its detections carry its own track
ids, a grasp's track is followed or reported lost, the object in the gripper is found from
depth with the class of the track the grasp picked, and the seeded noisy detector, applied
before tracking, misses, swaps and adds as its probabilities say and makes fresh identities."""

from __future__ import annotations

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.analysis import Simulator
from pydrake.systems.sensors import ImageDepth32F, ImageLabel16I, ImageRgba8U

from tamp.sim.core.detection_noise import LEVELS, perturb
from tamp.sim.core.messages import ViewRequest
from tamp.sim.core.perception import DetectorNoise, LabelOracle, Perception, Region, detect
from tamp.sim.core.tracks import Tracks, update

EMPTY = 32766
W, H = 320, 180
K = (231.4, 231.4, 159.5, 89.5)
TABLE = 0.47
X_LOOK = RigidTransform(RotationMatrix(np.diag([1.0, -1.0, -1.0])), [0.5, -0.25, TABLE])
CLASSES = {5: "scissors", 6: "scissors", 7: "hammer", 8: "saw", 9: "hammer"}
BLOCKS = {
    5: (slice(20, 45), slice(30, 70)),  # two scissors 10 cm apart, a hammer, a small saw
    6: (slice(20, 45), slice(120, 160)),
    7: (slice(110, 150), slice(60, 140)),
    8: (slice(120, 129), slice(220, 230)),  # 90 px: below the high level's small_area
}


def images(blocks=BLOCKS, held=None):
    label = np.full((H, W), EMPTY, np.int16)
    depth = np.full((H, W), TABLE, np.float32)
    for value, block in blocks.items():
        label[block], depth[block] = value, TABLE - 0.02
    if held is not None:
        depth[held] = 0.08  # the held object, 8 cm from the camera
    return label, depth


class Rig:
    """A `Perception` with its inputs fixed; `look` serves ``views`` requests (a LOTS look
    takes `CONFIRM_VIEWS`) and returns the last observation."""

    def __init__(self, noise=None, regions=None):
        self.p = Perception(
            LabelOracle(CLASSES),
            width=W,
            height=H,
            period=0.02,
            intrinsics=K,
            noise=noise,
            regions=regions,
        )
        self.sim = Simulator(self.p)
        self.ctx = self.sim.get_mutable_context()
        self.p.color_port.FixValue(self.ctx, ImageRgba8U(W, H))
        self.n = 0

    def look(self, label, depth, target=None, track=None, side="B", views=1):
        lab, dep = ImageLabel16I(W, H), ImageDepth32F(W, H)
        lab.mutable_data[..., 0], dep.mutable_data[..., 0] = label, depth
        self.p.label_port.FixValue(self.ctx, lab)
        self.p.depth_port.FixValue(self.ctx, dep)
        for _ in range(views):
            self.n += 1
            request = ViewRequest(self.n, side, target, track, X_LOOK)
            self.p.request_port.FixValue(self.ctx, request)
            self.sim.AdvanceTo(self.ctx.get_time() + 0.02)
        return self.p.observation_port.Eval(self.ctx)


def test_tracks_persist_across_views_and_a_lost_target_is_reported_not_replaced():
    rig = Rig()
    first = rig.look(*images(), target="scissors")
    ids = {d.track for d in first.detections}
    assert len(ids) == 4 and 0 not in ids
    target = first.target.detection
    again = rig.look(*images(), target="scissors", track=target.track)
    assert {d.track for d in again.detections} == ids
    assert again.target.detection.track == target.track
    # the tracked scissors is taken away: the other scissors is in view, but it is not the
    # target; perception reports none (the skill says "target lost")
    assert target.u > 100  # the scissors nearer the image centre: label 6's
    gone = {k: v for k, v in BLOCKS.items() if k != 6}
    lost = rig.look(*images(gone), target="scissors", track=target.track)
    # one view without it is not yet an absence: still counted (reported occluded) ...
    assert lost.target is None and lost.counts["scissors"] == 2
    assert [m.track for m in lost.occluded] == [target.track]
    # ... the second is
    assert rig.look(*images(gone)).counts["scissors"] == 1
    # the mask in the crop is the target's own
    assert first.target.mask.sum() == target.pixels


def test_a_view_counts_and_remembers_only_what_lies_in_its_workspace():
    # W^B's rectangle as the LOTS cells have it: x in [0.33, 0.67]; the scissors of label 5
    # lies at x = 0.29 (beside the workspace, in view), the one of label 6 at x = 0.46
    rig = Rig(regions={"B": Region((0.5, -0.25), (0.34, 0.34))})
    first = rig.look(*images())
    assert len(first.detections) == 4 and first.counts == {}  # seen once: tentative
    obs = rig.look(*images())
    assert len(obs.detections) == 4  # seen and tracked ...
    assert obs.counts == {"scissors": 1, "hammer": 1, "saw": 1}  # ... counted only inside
    outside = min(obs.detections, key=lambda d: d.u)
    assert outside.cls == "scissors" and outside.u < 80
    remembered = {m.track for m in rig.p.state(rig.ctx).memory["B"]}
    assert outside.track not in remembered and len(remembered) == 3
    # no rectangle for the side looked at (or none at all): every instance counts
    assert Rig().look(*images(), views=2).counts["scissors"] == 2
    assert rig.look(*images(), side="A").counts["scissors"] == 2


def test_one_bad_view_changes_no_count():
    """A look's count rests on two views: one view whose detector named the scissors a
    hammer (a class swap: a new, tentative hammer track; the scissors missed in plain view
    once) counts what the views before it counted, and so does the view after it."""
    rig = Rig()
    before = rig.look(*images(), views=2).counts
    assert before == {"scissors": 2, "hammer": 1, "saw": 1}
    swapped = {**BLOCKS, 9: BLOCKS[6]}
    del swapped[6]
    bad = rig.look(*images(swapped))
    assert sorted(d.cls for d in bad.detections) == ["hammer", "hammer", "saw", "scissors"]
    assert bad.counts == before and [m.cls for m in bad.occluded] == ["scissors"]
    assert rig.look(*images()).counts == before
    # the same hammer in two views in a row is a fact: counted (the scissors is still
    # remembered: its place lies inside the hammer's mask at its own depth, which is how a
    # neighbour's detection that swallowed it looks: `merged_into_others`)
    rig.look(*images(swapped))
    assert rig.look(*images(swapped)).counts["hammer"] == 2


def test_in_hand_from_depth_with_the_class_of_the_track_the_grasp_picked():
    rig = Rig()
    obs = rig.look(*images(), target="hammer")
    hammer = obs.target.detection.track
    rest = {k: v for k, v in BLOCKS.items() if k != 7}
    band = (slice(120, 180), slice(0, 120))
    lifted = rig.look(*images(rest, held=band), track=hammer)  # the lift's view
    assert lifted.in_hand == ("hammer",) and lifted.hand_cover > 0.1
    assert hammer not in {d.track for d in lifted.detections}
    st = rig.p.state(rig.ctx)
    assert st.tracks.get(hammer) is None  # in the gripper: in no workspace
    assert all(m.track != hammer for m in st.memory["B"])
    # held while the region stays full (a look elsewhere); empty region: nothing in hand
    assert rig.look(*images(rest, held=band), side="A").in_hand == ("hammer",)
    assert rig.look(*images(rest)).in_hand == ()
    # something in the gripper that is not the grasp's track (none given, or still on the
    # table): unknown
    assert rig.look(*images(rest, held=band)).in_hand == ("unknown",)
    rig2 = Rig()
    obs = rig2.look(*images(), target="saw")
    saw = obs.target.detection.track
    assert rig2.look(*images(held=band), track=saw).in_hand == ("unknown",)


def _placed():
    return detect(*images(), CLASSES, intrinsics=K, X_WC=X_LOOK)


def _origin(d, dets):
    """The input detection an output one came from (its mask, maybe jittered by a pixel)."""
    return max(dets, key=lambda o: (o.mask & d.mask).sum() / (o.mask | d.mask).sum())


def test_high_noise_misses_swaps_and_adds_at_its_rates():
    dets = _placed()
    lv = LEVELS["high"]
    saw = next(d for d in dets if d.cls == "saw")
    classes = sorted(set(CLASSES.values()))
    views, saws, real, swapped, extra = 400, 0, 0, 0, 0
    for f in range(views):
        out = perturb(dets, seed=3, frame=f, level="high", classes=classes,
                      depth=images()[1], intrinsics=K, X_WC=X_LOOK)  # fmt: skip
        for d in out:
            if d.score < 1.0:  # a false positive (the label image's score is 1)
                extra += 1
                continue
            o = _origin(d, dets)
            real += 1
            swapped += d.cls != o.cls
            saws += o is saw
    # the small saw (90 px) is missed with probability 0.7 * (1 - 90/120) = 0.175 (and by
    # occlusion never: nothing covers it, it is off the image's edge)
    assert abs(saws / views - (1 - lv.miss_small * (1 - saw.pixels / lv.small_area))) < 0.06
    assert abs(swapped / real - lv.swap) < 0.04  # class swaps
    assert abs(extra / views - lv.false_positives) < 0.12  # Poisson false positives


def test_the_tracker_sees_fresh_identities_under_noise_and_none_without():
    dets = _placed()
    classes = sorted(set(CLASSES.values()))
    depth = images()[1]
    for level, fresh in ((None, False), ("high", True)):
        tracks, seen = Tracks(), set()
        for f in range(30):
            out = dets
            if level is not None:
                out = perturb(dets, seed=3, frame=f, level=level, classes=classes, depth=depth,
                              intrinsics=K, X_WC=X_LOOK)  # fmt: skip
            tracks, ids = update(tracks, [(d.cls, d.centroid) for d in out], 0.1 * f)
            seen |= set(ids)
        assert (len(seen) > len(dets)) is fresh


def test_perception_applies_the_seeded_noise_before_tracking():
    same = [Rig(DetectorNoise("high", 11)) for _ in range(2)]
    runs = [[r.look(*images()).detections for _ in range(15)] for r in same]
    assert runs[0] == runs[1]  # same seed, same views: the same errors, the same tracks
    clean = Rig().look(*images()).detections
    noisy = [d for view in runs[0] for d in view]
    assert len({d.track for d in noisy}) > len(clean)  # fresh identities, false positives
    assert any(len(view) != len(clean) for view in runs[0])


def test_a_regions_fixtures_give_the_detector_its_floor_and_the_rims_pixels():
    """`Region.fixtures`: a tray's floor height as the detector's support plane and the
    pixels whose world point lies on its walls (the rim's square ring) as excluded."""
    tray = Region((0.5, -0.25), (0.34, 0.34), floor=0.01, rim=(0.24, 0.26))
    depth = np.full((H, W), TABLE, np.float32)
    known = tray.fixtures(depth, K, X_LOOK)
    assert known["plane"] == 0.01
    ex = known["exclude"]
    # the camera looks straight down at the centre: 1 px = TABLE / fx metres on the table
    px = TABLE / K[0]
    u_wall = int(round(K[2] + 0.125 / px))  # 12.5 cm beside the centre: on the wall
    assert ex[int(K[3]), u_wall] and not ex[int(K[3]), int(K[2])]  # the floor is not a wall
    assert not ex[int(K[3]), int(round(K[2] + 0.15 / px))]  # beyond the wall: the table
    assert Region((0.5, -0.25), (0.34, 0.34)).fixtures(depth, K, X_LOOK) == {}


def test_a_place_view_keeps_clear_of_what_stands_on_the_floor_detected_or_not():
    """A place's view (no target): ``occupied`` holds the detections' pixels and every pixel
    above the floor that is not the gripper's, so an object the detector missed (no label
    here) is not taken for bare floor; the held object's pixels are neither."""
    rig = Rig(regions={"B": Region((0.5, -0.25), (0.34, 0.34))})
    label, depth = images()
    missed = (slice(60, 90), slice(200, 260))
    depth[missed] = TABLE - 0.03  # 3 cm tall, no label: the detector does not report it
    held = (slice(150, 180), slice(0, 40))
    depth[held] = 0.08
    obs = rig.look(label, depth)
    assert obs.floor is not None and obs.occupied is not None
    assert obs.occupied[missed].all() and not obs.floor[missed].any()
    assert not obs.occupied[held].any() and not obs.floor[held].any()
    assert obs.occupied[BLOCKS[7]].all()  # the hammer, detected
    assert obs.floor[100:110, 200:300].all()  # the bare table is floor
