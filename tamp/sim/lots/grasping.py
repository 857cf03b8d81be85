"""Grasp candidates of one view (Zhou et al. §IV-B, Fig. 6), on top of `tamp.grasp.predict`.

Each view gives the network a square crop around the target; with post-processing on
(``grasp.post_process``, the default) its grasps are moved onto the target's mask along
their closing line (`snap_to_mask`), preferred where the pads can hold the target while
carrying it (`seated`: re-centred on the chord, within the opening, antipodal contacts, each
pad on one face) and checked for other objects in the open jaws' sweep (`clear_of_others`);
with it off, the network's grasps whose centre lies on the target's mask are taken as they
are. Either way they are mapped to the world through the crop's intrinsics and the camera
pose (the arm's own kinematics) and ranked clear first, then seated, then by quality. The
descent (`tamp.sim.lots.descent`) fuses the best grasp of each view over views.

``grasp.predictor: mask_axis`` replaces the network by the target mask's geometry
(`mask_axis_grasps`, a control with no network): closing across the mask's principal axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tamp.grasp.depth import valid_depth
from tamp.grasp.pinhole import pixel_to_camera
from tamp.grasp.predict import PredictedGrasp, to_world
from tamp.grasp.rect import GraspRect, angle_difference
from tamp.sim.core.messages import TargetCrop
from tamp.sim.core.models import models_dir
from tamp.sim.core.threads import INFERENCE_THREADS, torch_threads
from tamp.sim.core.timing import Stopwatch
from tamp.sim.lots.scenario import DEFAULT_WEIGHTS, GraspSettings

MAX_OPENING = 0.08  # the gripper's opening (2 x 0.04 m)
#: the object's top must stand this high above the table where the fingers close: the pads
#: stop 2 mm above the table, so a 6 mm saw blade gives them nothing to squeeze
MIN_TOP = 0.008
#: Where the pads meet the target (`seated`), seen from above. Objects are held by friction
#: alone; three ways a grasp holds through the lift and still lets go while carried (the
#: Fig. 10 run: a diagonal grasp on the peak's square base, 2.3 cm off its centre, turned
#: the peak 50 deg in the pads over 10 s of carrying until it fell):
#: - the closing direction may deviate this much from the target's outline normal at each
#:   contact (deg): pads (mu 1.0) on objects (mu 0.8) hold within a cone of about 42 deg
#:   (Drake combines them to 0.89); the margin covers the mask's pixel outline (Nguyen's
#:   antipodal condition);
MAX_CONTACT_ANGLE = 25.0
#: - each pad (2 cm wide along the jaws) must rest on the same face over its whole width: the
#:   closing lines half a pad to either side must meet the target where the centre line does
#:   (a grasp at the end of a face touches it with a corner of the pad);
PAD_WIDTH = 0.02
#: - the open pads must clear the target on both sides by this much (m): a chord longer than
#:   the opening less twice this lands a pad on the object's top (a body held by its 7 cm
#:   length tipped 66 deg in the pads).
PAD_CLEARANCE = 0.005
#: a grasp is *clear* when nothing but the target stands higher than `CLEAR_HEIGHT` above the
#: table in the open jaws' sweep: the fingers (open 8 cm, 1 cm thick, `FINGER_REACH` from the
#: centre) close from there and take whatever lies between them (in a Fig. 9 run the jaws
#: closed on the hammer and a wrench the person had put beside it; both went to W^B)
FINGER_REACH = 0.05
CLEAR_HEIGHT = 0.01


@dataclass(frozen=True)
class GraspCandidate:
    """A world-frame top grasp: centre on the object's top, closing yaw, opening, quality,
    and the camera height of the view it came from."""

    x: float
    y: float
    z: float
    yaw: float
    width: float
    quality: float
    view_height: float
    seated: bool = True  # passed `seated`; False: a fallback the pads may not hold carrying
    clear: bool = True  # no other object in the jaws' sweep (`clear_of_others`)


#: a retry's grasp differs from one that missed by this much at least (centre, m; closing
#: angle, rad): the network sees nearly the same crop again and would repeat itself
MISSED_DISTANCE = 0.01
MISSED_ANGLE = math.radians(20.0)


def near_grasp(c: GraspCandidate, missed: tuple[float, float, float]) -> bool:
    """Whether candidate ``c`` is (about) the grasp ``missed`` (x, y, closing yaw) again;
    closing angles are equal modulo 180 degrees (a parallel gripper is symmetric)."""
    x, y, yaw = missed
    close = math.hypot(c.x - x, c.y - y) < MISSED_DISTANCE
    return close and angle_difference(c.yaw, yaw) < MISSED_ANGLE


#: the network's best grasps a view considers: seated ones among the first `SEATED_BEST`;
#: when none of a pick's views has one, the snapped ones among the first `SNAPPED_BEST` (the
#: choice before `seated` existed: it may hold, and a pick without a grasp surely fails)
SEATED_BEST = 30
SNAPPED_BEST = 5


class GraspPlanner:
    """Loads the chosen network once (none for ``predictor: mask_axis``); turns a `TargetCrop`
    into world-frame candidates."""

    def __init__(self, settings: GraspSettings, intrinsics: tuple[float, float, float, float]):
        self.kind = settings.predictor
        self.predictor = None
        if self.kind == "network":
            from tamp.grasp.predict import GraspPredictor

            weights = settings.weights or str(models_dir() / DEFAULT_WEIGHTS[settings.network])
            self.weights: Path | None = Path(weights)
            self.predictor = GraspPredictor.load(self.weights)
            self.depth_range = self.predictor.depth_range
        else:
            self.weights = None
            from tamp.grasp.depth import DEFAULT_DEPTH_RANGE

            self.depth_range = DEFAULT_DEPTH_RANGE
        self.intrinsics = intrinsics
        self.calls = 0
        #: time spent in the network (pre-processing, inference, peak reading)
        self.network = Stopwatch()
        #: (crop, all predicted grasps, kept candidates) of every call when ``record`` is set:
        #: what notebooks and tests show of the descending views (not simulation state)
        self.record = False
        self.history: list[tuple[TargetCrop, list, list[GraspCandidate]]] = []
        #: move each grasp's centre along its closing line onto the target (see `snap_to_mask`)
        self.snap = settings.post_process
        #: prefer grasps the pads can hold while carrying, centred on the target's chord
        #: (see `seated`) and check the jaws' sweep (`clear_of_others`); off: the grasps
        #: on the mask as predicted
        self.seat = settings.post_process

    def _predict(self, crop: TargetCrop, K, X_WC: np.ndarray, n: int) -> list[PredictedGrasp]:
        if self.predictor is None:
            return mask_axis_grasps(np.asarray(crop.mask), n)
        with torch_threads(INFERENCE_THREADS):
            return self.predictor.predict(
                rgb=np.asarray(crop.rgb),
                depth=np.asarray(crop.depth, np.float32),
                intrinsics=K,
                X_WC=X_WC,
                n=n,
            )

    def candidates(
        self, crop: TargetCrop, X_WC: np.ndarray, view_height: float
    ) -> list[GraspCandidate]:
        """Grasps on the target's mask, best first: clear of other objects first, then
        seated, then by quality (a clear grasp is never ranked behind one that is not).
        Without post-processing every grasp counts as clear and seated."""
        n = SEATED_BEST if self.seat else SNAPPED_BEST
        fx, fy, cx, cy = self.intrinsics
        u0, v0 = crop.origin
        K = (fx, fy, cx - u0, cy - v0)
        with self.network:
            grasps = self._predict(crop, K, X_WC, n)
        self.calls += 1
        mask = dilate(np.asarray(crop.mask), 1)
        depth = np.where(crop.mask, crop.depth, 0.0).astype(np.float32)  # the target's top
        top = depth[crop.mask & valid_depth(depth, self.depth_range)]
        top = float(np.median(top)) if top.size else float("nan")
        opening = (MAX_OPENING - 2 * PAD_CLEARANCE) * fx / top  # in pixels at the top
        half_pad = PAD_WIDTH / 2 * fx / top
        out = []
        for i, g in enumerate(grasps):
            rect = snap_to_mask(g.rect(), mask) if self.snap else on_mask(g.rect(), mask)
            good = rect is not None and self.seat and seated(rect, mask, opening, half_pad)
            if good:
                rect = good
            elif rect is None or (self.seat and i >= SNAPPED_BEST):
                continue
            (x, y, z), yaw, width = to_world(rect, depth, K, X_WC)
            if not all(math.isfinite(v) for v in (x, y, z)) or z < MIN_TOP:
                continue  # no depth, or too thin there for the pads (a saw's blade)
            w = min(width, MAX_OPENING)
            clear = not self.seat or clear_of_others(
                rect, crop, K, X_WC, FINGER_REACH * fx / top, half_pad
            )
            out.append(
                GraspCandidate(
                    x,
                    y,
                    z,
                    yaw,
                    w,
                    g.quality,
                    view_height,
                    seated=bool(good) or not self.seat,
                    clear=clear,
                )
            )
        out = rank(out)
        if self.record:
            self.history.append((crop, grasps, out))
        return out


def rank(cands: list[GraspCandidate]) -> list[GraspCandidate]:
    """Best first: clear of other objects, then seated, then by quality (stable)."""
    return sorted(cands, key=lambda c: (not c.clear, not c.seated, -c.quality))


def mask_axis_grasps(mask: np.ndarray, n: int, samples: int = 9) -> list[PredictedGrasp]:
    """Grasps from the mask's geometry alone (a control with no network): closing across the
    principal axis of the mask's pixels, at ``samples`` points along it between 10 % and 90 %
    of its extent; each grasp's opening is its chord across the mask, its quality falls from
    1 at the centroid to 0.5 at the ends (best ``n`` returned, best first)."""
    vs, us = np.nonzero(mask)
    if len(us) < 5:
        return []
    pts = np.c_[us, vs].astype(float)
    c = pts.mean(axis=0)
    _, vecs = np.linalg.eigh(np.cov((pts - c).T))
    axis = vecs[:, -1]  # the principal (longest) direction
    across = np.array([-axis[1], axis[0]])
    along = (pts - c) @ axis
    lo, hi = np.percentile(along, 10), np.percentile(along, 90)
    angle = math.atan2(-across[1], across[0])  # GraspRect: direction (cos a, -sin a)
    ext = max(abs(lo), abs(hi), 1e-6)
    out = []
    for t in np.linspace(lo, hi, samples):
        p = c + t * axis
        rect = GraspRect(float(p[0]), float(p[1]), angle, 10.0, 5.0)
        ends = chord(rect, mask)
        if ends is None:
            continue
        mid = (ends[0] + ends[1]) / 2
        u, v = p + mid * across
        width = ends[1] - ends[0] + 1.0
        out.append(
            PredictedGrasp(float(u), float(v), angle, float(width), 1.0 - 0.5 * abs(t) / ext)
        )
    out.sort(key=lambda g: -g.quality)
    return out[:n]


def on_mask(rect: GraspRect, mask: np.ndarray) -> GraspRect | None:
    """``rect`` if its centre lies on the mask, else None (the strict reading)."""
    r, c = int(round(rect.y)), int(round(rect.x))
    ok = 0 <= r < mask.shape[0] and 0 <= c < mask.shape[1] and mask[r, c]
    return rect if ok else None


def snap_to_mask(rect: GraspRect, mask: np.ndarray, reach: float = 0.75) -> GraspRect | None:
    """The grasp moved along its closing line to the middle of the target run nearest its
    centre, or None when the line (``reach`` x the opening each side) misses the target.

    On the workcell's views the shipped weights put the quality peak beside thin objects with
    the right closing angle (the jaws straddle the object, the centre lies on the table); the
    closing line then crosses the object, and this keeps the network's angle and quality
    while centring the fingers on what they must close on. Without it, most views give no
    grasp on the target (docs/lots_workcell.md has the figures).
    """
    d = rect.direction
    half = max(rect.width, 12.0) * reach
    ts = np.arange(-half, half + 0.5, 0.5)
    us = np.round(rect.x + ts * d[0]).astype(int)
    vs = np.round(rect.y + ts * d[1]).astype(int)
    inside = (us >= 0) & (us < mask.shape[1]) & (vs >= 0) & (vs < mask.shape[0])
    hit = np.zeros(ts.shape, bool)
    hit[inside] = mask[vs[inside], us[inside]]
    if not hit.any():
        return None
    # contiguous runs of hits; take the one nearest t = 0
    idx = np.flatnonzero(hit)
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
    best = min(
        runs, key=lambda r: min(abs(ts[r[0]]), abs(ts[r[-1]])) if ts[r[0]] * ts[r[-1]] > 0 else 0
    )
    t = (ts[best[0]] + ts[best[-1]]) / 2
    return GraspRect(rect.x + t * d[0], rect.y + t * d[1], rect.angle, rect.width, rect.height)


def chord(rect: GraspRect, mask: np.ndarray) -> tuple[float, float] | None:
    """Where the closing line through the grasp's centre (on the mask) leaves the mask each
    way: ``(t_minus, t_plus)`` in pixels along `GraspRect.direction` (the last mask samples,
    half a pixel apart); None when the centre is off the mask."""
    d = rect.direction
    h, w = mask.shape

    def inside(t: float) -> bool:
        u, v = int(round(rect.x + t * d[0])), int(round(rect.y + t * d[1]))
        return 0 <= v < h and 0 <= u < w and bool(mask[v, u])

    if not inside(0.0):
        return None
    ends = []
    for sign in (-1.0, 1.0):
        t = 0.0
        while inside(t + sign * 0.5):
            t += sign * 0.5
        ends.append(t)
    return ends[0], ends[1]


def antipodal(rect: GraspRect, mask: np.ndarray, max_angle: float = MAX_CONTACT_ANGLE) -> bool:
    """Do both pads meet the target's outline within ``max_angle`` degrees of its normal?

    The contacts are the ends of the closing line's `chord`; the outline's outward normal
    there is the negative gradient of the mask smoothed over 5x5 pixels. A diagonal closing
    across a box's faces (normals 45 deg off) is rejected; one across parallel faces passes.
    A line exactly through two opposite corners reads the corners' diagonal normals and
    passes: one line stands for the pad (a check across the pad's width also rejected the
    Fig. 10 body's only good grasp, 24 deg off its faces, on the pixel outline's noise).
    """
    ends = chord(rect, mask)
    if ends is None:
        return False
    d = rect.direction
    gy, gx = np.gradient(box_blur(mask.astype(np.float32), 2))
    cos_max = math.cos(math.radians(max_angle))
    for sign, t in zip((-1.0, 1.0), ends, strict=True):
        v, u = int(round(rect.y + t * d[1])), int(round(rect.x + t * d[0]))
        n = -np.array([gx[v, u], gy[v, u]])  # outward
        norm = float(np.linalg.norm(n))
        if norm < 1e-6 or float(np.dot(sign * d, n)) / norm < cos_max:
            return False
    return True


def supported(
    rect: GraspRect, mask: np.ndarray, half_pad: float, max_angle: float = MAX_CONTACT_ANGLE
) -> bool:
    """Does each pad rest on the target over its width? The closing lines ``half_pad`` pixels
    to either side along the jaws must cross the mask and end within ``half_pad *
    tan(max_angle)`` (+2 px of outline) of the centre line's contacts: the same faces, not
    past a corner or off the target's end."""
    ends = chord(rect, mask)
    if ends is None:
        return False
    tol = half_pad * math.tan(math.radians(max_angle)) + 2.0
    across = rect.normal
    for off in (-half_pad, half_pad):
        side = GraspRect(
            rect.x + off * across[0], rect.y + off * across[1], rect.angle, rect.width, rect.height
        )
        e = chord(side, mask)
        if e is None or abs(e[0] - ends[0]) > tol or abs(e[1] - ends[1]) > tol:
            return False
    return True


def seated(rect: GraspRect, mask: np.ndarray, opening: float, half_pad: float) -> GraspRect | None:
    """The grasp re-centred on its whole chord through the target, if the pads can hold it:
    the chord fits the ``opening`` (pixels, clearance included), both contacts are
    `antipodal` and each pad (``half_pad`` pixels to either side) is `supported`; else None.

    Our post-processing of the network's grasp, like `snap_to_mask` (which centres on the
    part of the chord within the predicted opening): the angle and quality stay the
    network's. Centring on the whole chord makes both open pads clear the target equally.
    """
    ends = chord(rect, mask)
    if ends is None or not math.isfinite(opening) or ends[1] - ends[0] + 1 > opening:
        return None
    t = (ends[0] + ends[1]) / 2
    d = rect.direction
    out = GraspRect(rect.x + t * d[0], rect.y + t * d[1], rect.angle, rect.width, rect.height)
    return out if antipodal(out, mask) and supported(out, mask, half_pad) else None


def clear_of_others(
    rect: GraspRect, crop: TargetCrop, K, X_WC: np.ndarray, reach: float, half_pad: float
) -> bool:
    """Whether the open jaws' sweep (``reach`` pixels to either side of the grasp centre along
    the closing line, ``half_pad`` across it) holds nothing but the target standing higher
    than `CLEAR_HEIGHT` above the table: the crop's depth back-projected through ``K`` and the
    camera pose ``X_WC`` (4 x 4)."""
    h, w = crop.mask.shape
    d = rect.direction
    n = np.array([-d[1], d[0]])
    t, s = np.meshgrid(np.arange(-reach, reach + 1.0), np.arange(-half_pad, half_pad + 1.0))
    us = np.round(rect.x + t * d[0] + s * n[0]).astype(int).ravel()
    vs = np.round(rect.y + t * d[1] + s * n[1]).astype(int).ravel()
    inside = (us >= 0) & (us < w) & (vs >= 0) & (vs < h)
    us, vs = us[inside], vs[inside]
    target = dilate(np.asarray(crop.mask), 2)
    z = np.asarray(crop.depth)[vs, us]
    other = ~target[vs, us] & valid_depth(z)
    if not other.any():
        return True
    X = np.asarray(X_WC)
    pts = X[:3, :3] @ pixel_to_camera(us[other], vs[other], z[other], K) + X[:3, 3:4]
    return not bool(np.any(pts[2] > CLEAR_HEIGHT))


def box_blur(img: np.ndarray, r: int) -> np.ndarray:
    """Mean over a (2r+1) square around each pixel (edge pixels repeated; numpy only)."""
    k = 2 * r + 1
    p = np.pad(img, r, mode="edge")
    s = np.cumsum(np.cumsum(p, axis=0), axis=1)
    s = np.pad(s, ((1, 0), (1, 0)))
    return (s[k:, k:] - s[:-k, k:] - s[k:, :-k] + s[:-k, :-k]) / (k * k)


def dilate(mask: np.ndarray, r: int) -> np.ndarray:
    """Binary dilation by a (2r+1) square (numpy only)."""
    out = mask.copy()
    h, w = mask.shape
    for dr in range(-r, r + 1):
        for dc in range(-r, r + 1):
            src = mask[max(-dr, 0) : h - max(dr, 0), max(-dc, 0) : w - max(dc, 0)]
            out[max(dr, 0) : h - max(-dr, 0), max(dc, 0) : w - max(-dc, 0)] |= src
    return out
