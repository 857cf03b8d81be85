"""Two readings of a learned detector's view that one mask at a time cannot make.

*An object in pieces.* Something nearer than an object (the object the gripper holds, a
person's arm) can cut its visible pixels in two, and the detector then reports two instances
of its class. The label oracle reports one body, whatever hides its middle; perception joins
such fragments back into one object (`joined_fragments`) when together they are no larger
than one object of their class (its footprint's diagonal, the cell's ``spans``), lie at one
height, and what separates them in the image is nearer than both (an occluder: the held
object, an arm, or an object lying across this one; two objects of one class either side of
a third would span more than one of them).

*An object in a person's hand.* The person moves objects by hand: one the hand touches is
being taken or put down, and where it will rest is not settled. Perception sees and tracks
it but neither counts nor remembers it in a workspace until the hand lets go
(`touched_by_hand`): a wrench carried over W^A is no hammer of W^A, even when the detector
names it so. Touch is read from depth, class-agnostic: the object's mask borders the hand's
and the two surfaces there lie within `HAND_CONTACT` of each other (an arm reaching over an
object passes centimetres above it).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np
from scipy import ndimage

from tamp.sim.core.instances import ObjectDetection, located

#: a hand's mask borders an object's within this many pixels (a finger's edge)
HAND_BORDER = 2
#: ... and their surfaces there lie within this depth of each other to be in contact (m)
HAND_CONTACT = 0.02
#: fragments of one object lie at one height: their median world heights within this (m)
FRAGMENT_HEIGHT = 0.02
#: an occluder between fragments is this much nearer the camera than both of them (m)
OCCLUDER_NEARER = 0.02
#: the share of the pixels between two fragments that must show the occluder
OCCLUDER_SHARE = 0.8
#: slack on a class's span when two fragments are taken for one object (m)
SPAN_SLACK = 0.01
#: points of a fragment used to measure the joined extent (a sample: O(n^2) distances)
EXTENT_SAMPLE = 200


def _surface(depth: np.ndarray) -> np.ndarray:
    """Depth with no return (NaN, 0, +inf) read as nearest: whatever is there is nearer
    than the clipping plane or covers the view."""
    return np.where(np.isfinite(depth) & (depth > 0), depth, 0.0)


def touched_by_hand(
    found: Sequence[ObjectDetection], hands: Sequence[np.ndarray], depth: np.ndarray
) -> list[bool]:
    """For each detection of ``found``: whether a hand mask of ``hands`` touches it (module
    docstring): within `HAND_BORDER` pixels of its mask, the hand's median depth there
    and the object's median depth along that border within `HAND_CONTACT`."""
    if not hands:
        return [False] * len(found)
    hand = np.logical_or.reduce(list(hands))
    near_hand = ndimage.binary_dilation(hand, iterations=HAND_BORDER)
    d = _surface(depth)
    out = []
    for det in found:
        edge = det.mask & near_hand & ~hand
        if not edge.any():
            out.append(False)
            continue
        ring = ndimage.binary_dilation(edge, iterations=HAND_BORDER) & hand
        obj, hnd = d[edge], d[ring]
        obj, hnd = obj[obj > 0], hnd[hnd > 0]
        out.append(
            bool(obj.size and hnd.size and abs(np.median(obj) - np.median(hnd)) < HAND_CONTACT)
        )
    return out


def _extent(a: np.ndarray, b: np.ndarray) -> float:
    """The largest horizontal distance (m) between two point sets (3 x N world points,
    each sampled to `EXTENT_SAMPLE`)."""
    pts = []
    for p in (a, b):
        step = max(1, p.shape[1] // EXTENT_SAMPLE)
        pts.append(p[:2, ::step].T)
    q = np.vstack(pts)
    diff = q[:, None, :] - q[None, :, :]
    return float(np.sqrt((diff**2).sum(-1)).max())


def _occluded_between(a: np.ndarray, b: np.ndarray, depth: np.ndarray) -> bool:
    """Whether the pixels on the shortest segment from mask ``a`` to mask ``b`` show an
    occluder: at least `OCCLUDER_SHARE` of them nearer than both masks' median depth by
    `OCCLUDER_NEARER` (or without a return), whatever shows there (the held object, an
    arm, an object lying across this one); False when the masks touch (the detector split
    them itself)."""
    dist, (iy, ix) = ndimage.distance_transform_edt(~a, return_indices=True)
    vs, us = np.nonzero(b)
    k = int(np.argmin(dist[vs, us]))
    v1, u1 = int(vs[k]), int(us[k])
    v0, u0 = int(iy[v1, u1]), int(ix[v1, u1])
    n = int(max(abs(v1 - v0), abs(u1 - u0)))
    if n < 2:
        return False
    t = np.linspace(0.0, 1.0, n + 1)[1:-1]
    rows = np.rint(v0 + t * (v1 - v0)).astype(int)
    cols = np.rint(u0 + t * (u1 - u0)).astype(int)
    d = _surface(depth)
    da, db = d[a], d[b]
    far = min(float(np.median(da[da > 0])), float(np.median(db[db > 0])))
    between = d[rows, cols]
    return float(np.mean(between < far - OCCLUDER_NEARER)) >= OCCLUDER_SHARE


def joined_fragments(
    found: Sequence[ObjectDetection],
    depth: np.ndarray,
    spans: Mapping[str, float],
    intrinsics: Sequence[float],
    X_WC,
) -> list[ObjectDetection]:
    """``found`` with the fragments of one object joined (module docstring): two detections
    of one class with a span whose points lie at one height (`FRAGMENT_HEIGHT`), span
    together no more than the class's ``spans`` (+ `SPAN_SLACK`), and are separated by an
    occluder (`_occluded_between`). Joined greedily, pair by pair, until none is left; the
    joined mask is placed anew (`located`)."""
    out = list(found)
    joined = True
    while joined:
        joined = False
        for i in range(len(out)):
            for j in range(i + 1, len(out)):
                a, b = out[i], out[j]
                span = spans.get(a.cls)
                if a.cls != b.cls or span is None or a.points.size == 0 or b.points.size == 0:
                    continue
                if abs(np.median(a.points[2]) - np.median(b.points[2])) > FRAGMENT_HEIGHT:
                    continue
                if _extent(a.points, b.points) > span + SPAN_SLACK:
                    continue
                if not _occluded_between(a.mask, b.mask, depth):
                    continue
                mask = a.mask | b.mask
                where = located(mask, depth, intrinsics, X_WC)
                if where is None:
                    continue
                whole = dataclasses.replace(
                    a, score=max(a.score, b.score), mask=mask, extra={**b.extra, **a.extra}, **where
                )
                out[i] = whole
                del out[j]
                joined = True
                break
            if joined:
                break
    return out
