"""The object detector: colour + depth + camera pose in, objects out (torch).

Zhou et al. (IEEE T-ASE 2023, §IV-V) detect the workcell's objects with a network on the
wrist camera's RGB-D images. Ours is the classic tabletop pipeline (Rusu et al., RAS 56(11),
2008, §5-6), `Detector`:

1. instance proposals from geometry (`tamp.sim.core.instances.proposals`): the depth
   back-projected through the intrinsics and the camera pose from the arm's kinematics, the
   support plane estimated from the view, the pixels above it, their components split at
   depth jumps;
2. a small CNN per proposal (`tamp.sim.core.cropnet`) on its crop (colour, height above the
   plane, mask) and its metric size, giving a catalogue class, ``unknown``, ``hand``,
   ``several`` (touching objects: the proposal is split again at 8 mm depth steps, or at
   its height levels when one part stands on another, `instances.split_several`, and its
   parts classified; a proposal named ``unknown`` is tried at its levels too, and a split
   at levels is kept only when its parts are named as tower parts stacked, `_a_stack`) or
   ``none`` (dropped); a task class below the weights' threshold is reported ``unknown``,
   and so is one of a size its class never had in training (`cropnet.size_gate`); touching
   parts named alike are one object when their union is named so too (a saw's handle 3 cm
   over its blade is split by the depth jump, and each part looks like a saw), as touching
   parts named ``hand`` are one hand;
3. a part in the gripper's region (median depth under `IN_HAND_DEPTH`) that is not the
   person's hand is the held object: not reported (perception knows what the gripper holds).

Its inputs are only what a real camera and arm give: the colour and depth images, the
intrinsics and the camera pose. Its output per view is a list of `ObjectDetection` (class or
``unknown`` or ``hand``, score, mask, pixel centroid, 3-D centroid and world-frame points).
`SegmentationDetector` is the earlier detector (a segmentation network, `tamp.sim.core.segnet`,
then `tamp.sim.core.instances.extract`), kept to compare against: `Detector.load` returns
whichever a weights file holds.

Resolution: both work at the resolution they were trained at (the weights record it:
160 x 90, half the LOTS wrist camera's 320 x 180). A larger image whose size is an integer
multiple of it is subsampled; the masks are scaled back up (nearest), and points, centroids
and depths are taken from the image's own depth at its own resolution.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch
from scipy import ndimage
from scipy.sparse.csgraph import connected_components

from tamp.sim.core import cropnet
from tamp.sim.core.instances import (
    DEPTH_JUMP,
    FINE_JUMP,
    IN_HAND_DEPTH,
    MIN_PIXELS,
    UNKNOWN,
    UNKNOWN_BELOW,
    ObjectDetection,
    backproject_mask,
    extract,
    located,
    proposals,
    split_at_levels,
    split_several,
)
from tamp.sim.core.segdata import HAND, STACK_CLASSES, STUFF
from tamp.sim.core.segnet import SegNet, load, prepare


@functools.cache
def shipped(name: str = cropnet.WEIGHTS_FILE) -> Detector | SegmentationDetector:
    """The detector of a shipped weights file (``tamp/models/weights/NAME``; default: the
    LOTS wrist camera's), loaded once per process: the stations of a campaign share it (it
    holds no state between views)."""
    from tamp.sim.core.models import models_dir

    return Detector.load(models_dir() / "weights" / name)


def _factor(shape: tuple[int, int], size: tuple[int, int]) -> int:
    """k when an image of ``shape`` (h, w) is k times ``size`` (w, h), else 1."""
    h, w = shape
    W, H = size
    k = w // W
    if k >= 1 and w == k * W and h == k * H:
        return k
    return 1


def _upscaled(found, depth: np.ndarray, intrinsics, X_WC, k: int) -> list[ObjectDetection]:
    """Detections made on an image subsampled ``k`` times, at the full image's size: masks
    scaled up, points, centroids and depths from the full-size depth."""
    if k == 1:
        return found
    h, w = depth.shape
    depth = np.where(np.isfinite(depth), depth, 0.0)
    out = []
    for d in found:
        mask = d.mask.repeat(k, axis=0).repeat(k, axis=1)[:h, :w]
        where = located(mask, depth, intrinsics, X_WC)
        if where is not None:
            out.append(dataclasses.replace(d, mask=mask, **where))
    return out


def _scaled(intrinsics, k: int) -> tuple[float, float, float, float]:
    fx, fy, cx, cy = intrinsics
    return (fx / k, fy / k, cx / k, cy / k)


class Detector:
    """Proposals from geometry, each named by the crop classifier (module docstring)."""

    def __init__(
        self,
        model: cropnet.CropNet,
        meta: dict,
        *,
        min_pixels: int = MIN_PIXELS,
        jump: float = DEPTH_JUMP,
        fine_jump: float | None = None,
        unknown_below: float | None = None,
    ):
        self.model = model.eval()
        self.meta = meta
        self.classes: tuple[str, ...] = tuple(meta["classes"])
        self.outputs: list[str] = list(meta["outputs"])
        self.size: tuple[int, int] = tuple(meta.get("size", (160, 90)))  # (width, height)
        self.min_pixels = min_pixels
        self.jump = jump
        self.fine_jump = float(meta.get("fine_jump", FINE_JUMP) if fine_jump is None else fine_jump)
        self.unknown_below = float(
            meta.get("unknown_below", UNKNOWN_BELOW) if unknown_below is None else unknown_below
        )
        self.sizes: dict = dict(meta.get("sizes", {}))
        self._several = self.outputs.index(cropnet.SEVERAL)
        self._none = self.outputs.index(cropnet.NONE)
        self._task = {
            i for i, n in enumerate(self.outputs) if n not in (UNKNOWN, HAND, *_NOT_OBJECTS)
        }

    @classmethod
    def load(cls, path: str | Path | None = None, **kwargs) -> Detector | SegmentationDetector:
        """The detector of a weights file (default: the shipped weights): a `Detector` for a
        crop classifier's weights, a `SegmentationDetector` for a segmentation network's."""
        from tamp.grasp.train import read_weights

        if path is None:
            from tamp.sim.core.models import models_dir

            path = models_dir() / "weights" / cropnet.WEIGHTS_FILE
        if read_weights(path, "cpu")["meta"].get("kind") != "crop_classifier":
            return SegmentationDetector.load(path, **kwargs)
        model, meta = cropnet.load(path)
        return cls(model, meta, **kwargs)

    def label(self, p: np.ndarray, features: np.ndarray | None = None) -> tuple[str | None, float]:
        """(the class reported for a proposal of output probabilities ``p``, or None for
        ``none``; its score): a task class below ``unknown_below``, or one whose sizes the
        proposal's ``features`` do not fit (`cropnet.size_gate`), is ``unknown``."""
        i = int(p.argmax())
        if i == self._none:
            return None, float(p[i])
        score = float(p[i])
        if i in self._task and (
            score < self.unknown_below
            or (
                features is not None
                and not cropnet.size_gate(features, self.sizes.get(self.outputs[i]))
            )
        ):
            return UNKNOWN, score
        return self.outputs[i], score

    def _at_size(
        self, rgb, depth, intrinsics, X_WC, plane=None, exclude=None, above=None
    ) -> list[tuple[np.ndarray, str, float]]:
        """(mask, class, score) of the objects of an image at the trained size (module
        docstring, steps 1-3)."""
        depth = np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)
        prop = proposals(
            depth,
            intrinsics,
            X_WC,
            jump=self.jump,
            min_pixels=self.min_pixels,
            plane=plane,
            exclude=exclude,
            **({} if above is None else {"above": above}),
        )

        def named(masks):
            inputs = [
                cropnet.crop_input(
                    rgb, prop.heights, depth, m, backproject_mask(m, depth, intrinsics, X_WC)
                )
                for m in masks
            ]
            if not inputs:
                return []
            x = np.stack([a for a, _ in inputs])
            f = np.stack([b for _, b in inputs])
            return list(zip(masks, cropnet.classify(self.model, x, f), f, strict=True))

        final = []
        for origin, (m, p, f) in enumerate(named(prop.masks)):
            parts, stacked = [], False
            if int(p.argmax()) == self._several:
                parts, stacked = split_several(
                    m, depth, prop.heights, jump=self.fine_jump, min_pixels=self.min_pixels
                )
            elif self.label(p, f)[0] == UNKNOWN:  # a stack the classifier cannot name whole
                parts = split_at_levels(m, prop.heights, min_pixels=self.min_pixels)
                stacked = len(parts) > 1
            split = named(parts) if len(parts) > 1 else []
            if stacked and not self._a_stack(split):
                split = []
            for part, q, g in split or [(m, p, f)]:
                q = q.copy()
                q[self._several] = 0.0  # a part not split further is named as one object
                final.append((part, q / max(float(q.sum()), 1e-9), g, origin))
        named_parts = self._joined(
            [(m, *self.label(p, f)) for m, p, f, _ in final], [o for *_, o in final], named
        )
        out = []
        for m, cls, score in _hands_joined(named_parts):
            d = depth[m]
            d = d[d > 0]
            if cls is None or d.size == 0 or (cls != HAND and np.median(d) < IN_HAND_DEPTH):
                continue
            out.append((m, cls, score))
        return out

    def _a_stack(self, parts: list) -> bool:
        """Whether a proposal's levels (bottom up: (mask, probabilities, features)) are
        parts stacked as the training data stacks them (`segdata.STACK_CLASSES`, in that
        order, one class on itself allowed): one or more named so, any others ``unknown``.
        An object with faces at two heights side by side (a dumbbell's discs beside its bar)
        also shows levels; its parts named anything else keep it whole."""
        names = [self.label(q, g)[0] for _, q, g in parts]
        named = [c for c in names if c != UNKNOWN]
        if not named or any(c not in STACK_CLASSES for c in named):
            return False
        order = [STACK_CLASSES.index(c) for c in named]
        return order == sorted(order)

    def _joined(
        self, parts: list, origins: list[int], named
    ) -> list[tuple[np.ndarray, str | None, float]]:
        """(mask, class, score) of named parts with the parts of one task class that touch,
        or come from one proposal (``origins``: each part's proposal), joined when the
        classifier names their union that class too: one object of parts at different
        heights (a saw's handle over its flat blade) is split by the depth jumps into parts
        that each look like it, and a tower's bottom seen round the body on it into strips on
        either side that do not touch; two objects of a class are not joined, their union
        being too large for one (`label`'s size gate)."""
        groups = _related_groups(
            [
                (m, c, o)
                for (m, c, _), o in zip(parts, origins, strict=True)
                if c not in (None, UNKNOWN, HAND)
            ]
        )
        if not groups:
            return parts
        joined, used = [], set()
        for members in groups:
            union = np.logical_or.reduce([m for m, _ in members])
            ((_, p, f),) = named([union])
            cls, score = self.label(p, f)
            if cls == members[0][1]:
                joined.append((union, cls, score))
                used |= {id(m) for m, _ in members}
        return [q for q in parts if id(q[0]) not in used] + joined

    def detect(
        self,
        rgb: np.ndarray,
        depth: np.ndarray,
        intrinsics: Sequence[float],
        X_WC,
        *,
        plane: float | None = None,
        exclude: np.ndarray | None = None,
        above: float | None = None,
    ) -> list[ObjectDetection]:
        """The objects in one view: ``rgb`` (H x W x 3 or 4, uint8), ``depth`` (H x W,
        metres), ``intrinsics`` (fx, fy, cx, cy) of this image, ``X_WC`` the camera pose
        (4 x 4 or a Drake ``RigidTransform``) from the arm's kinematics; what the cell knows
        of its fixtures: ``plane``, the support's height when known (else estimated from the
        view), ``exclude`` (H x W), pixels of fixtures that are never objects, ``above``, how
        far over the support a pixel must be to be an object's (default `ABOVE_PLANE`; a far
        floor seen from a mast needs more). An image ``k``
        times the trained size is subsampled; masks come back at its own size."""
        k = _factor(depth.shape, self.size)
        small = None if exclude is None else exclude[::k, ::k]
        found = self._at_size(
            rgb[::k, ::k], depth[::k, ::k], _scaled(intrinsics, k), X_WC, plane, small, above
        )
        h, w = depth.shape
        depth = np.where(np.isfinite(depth), depth, 0.0)
        out = []
        for m, cls, score in found:
            if k > 1:
                m = m.repeat(k, axis=0).repeat(k, axis=1)[:h, :w]
            where = located(m, depth, intrinsics, X_WC)
            if where is not None:
                out.append(ObjectDetection(cls, score, m, **where))
        return out


_NOT_OBJECTS = (cropnet.SEVERAL, cropnet.NONE)


def _related_groups(
    parts: list[tuple[np.ndarray, str, int]],
) -> list[list[tuple[np.ndarray, str]]]:
    """The groups of two or more (mask, class) of one class that are related: their masks
    touch (8-connected once each is grown by a pixel) or they come from one proposal (the
    third item), directly or through other members."""
    groups = []
    for cls in {c for _, c, _ in parts}:
        mine = [(m, o) for m, c, o in parts if c == cls]
        if len(mine) < 2:
            continue
        grown = [ndimage.binary_dilation(m, structure=np.ones((3, 3), bool)) for m, _ in mine]
        related = np.array(
            [
                [oi == oj or bool((gi & mj).any()) for mj, oj in mine]
                for gi, (_, oi) in zip(grown, mine, strict=True)
            ]
        )
        n, label = connected_components(related, directed=False)
        for k in range(n):
            group = [(m, cls) for (m, _), lk in zip(mine, label, strict=True) if lk == k]
            if len(group) > 1:
                groups.append(group)
    return groups


def _hands_joined(parts: list[tuple[np.ndarray, str | None, float]]) -> list:
    """(mask, class, score) of named parts with the touching parts named ``hand`` joined
    into one: fingers and forearm at different depths are split by the depth jumps, but a
    hand is one thing (its score: the largest part's)."""
    hands = [(m, s) for m, c, s in parts if c == HAND]
    if len(hands) < 2:
        return parts
    union = np.zeros(hands[0][0].shape, bool)
    for m, _ in hands:
        union |= m
    labels, n = ndimage.label(ndimage.binary_dilation(union), structure=np.ones((3, 3), bool))
    joined = []
    for k in range(1, n + 1):
        mine = [(m, s) for m, s in hands if (labels[m] == k).any()]
        mask = np.logical_or.reduce([m for m, _ in mine])
        joined.append((mask, HAND, max(mine, key=lambda t: t[0].sum())[1]))
    return [p for p in parts if p[1] != HAND] + joined


class SegmentationDetector:
    """A trained segmentation network and the rules that make objects of its output."""

    def __init__(
        self,
        model: SegNet,
        meta: dict,
        *,
        min_pixels: int = MIN_PIXELS,
        jump: float = DEPTH_JUMP,
        unknown_below: float = UNKNOWN_BELOW,
        device: str = "cpu",
    ):
        self.model = model.to(device).eval()
        self.meta = meta
        self.classes: tuple[str, ...] = tuple(meta["classes"])
        self.size: tuple[int, int] = tuple(meta.get("size", (160, 90)))  # (width, height)
        self.objects = [i for i, n in enumerate(self.classes) if n not in STUFF]
        self.min_pixels = min_pixels
        self.jump = jump
        self.unknown_below = unknown_below
        self.device = device

    @classmethod
    def load(cls, path: str | Path, **kwargs) -> SegmentationDetector:
        """The detector of a segmentation network's weights file."""
        model, meta = load(path, kwargs.get("device", "cpu"))
        return cls(model, meta, **kwargs)

    @torch.no_grad()
    def _network(self, rgb: np.ndarray, depth: np.ndarray, k: int) -> np.ndarray:
        """Class probabilities (C x H/k x W/k) of the image subsampled by ``k``."""
        x = prepare(rgb[::k, ::k], depth[::k, ::k])
        logits = self.model(torch.from_numpy(x)[None].to(self.device))[0]
        return torch.softmax(logits, dim=0).cpu().numpy()

    def probabilities(self, rgb: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """Class probabilities (C x H x W) at the image's resolution."""
        k = _factor(depth.shape, self.size)
        probs = self._network(rgb, depth, k)
        if k > 1:
            probs = probs.repeat(k, axis=1).repeat(k, axis=2)
        return probs

    def detect(
        self, rgb: np.ndarray, depth: np.ndarray, intrinsics: Sequence[float], X_WC
    ) -> list[ObjectDetection]:
        """The objects in one view: ``rgb`` (H x W x 3 or 4, uint8), ``depth`` (H x W,
        metres), ``intrinsics`` (fx, fy, cx, cy) of this image, ``X_WC`` the camera pose
        (4 x 4 or a Drake ``RigidTransform``) from the arm's kinematics.

        An image ``k`` times the network's size is segmented and split into instances at the
        network's size (on the subsampled depth); each mask is then scaled up ``k`` times and
        its points and centroid are taken from the full-size depth."""
        k = _factor(depth.shape, self.size)
        probs = self._network(rgb, depth, k)
        fx, fy, cx, cy = intrinsics
        found = extract(
            probs,
            depth[::k, ::k],
            self.classes,
            self.objects,
            (fx / k, fy / k, cx / k, cy / k),
            X_WC,
            jump=self.jump,
            min_pixels=self.min_pixels,
            unknown_below=self.unknown_below,
        )
        return _upscaled(found, depth, intrinsics, X_WC, k)
