"""Object poses from the youBot's camera (``perception: camera``), not from the plant.

    RgbdSensor (mast camera on the base) ─► [DepthNoise] ─► Perception (the shared
    detector, `tamp.sim.core.perception`: label + depth image -> detections by class)
      ─► ObjectPoseEstimator ─► body_poses
    ObjectPoseEstimator.view_request ─► Perception          (one view every period)

`ObjectPoseEstimator` asks for one view per period and turns every detection into an
estimate of the object's pose: the detection's centroid pixel and median depth are
back-projected with the camera's pose at the time the view was rendered (the robot's own
kinematics; kept per render time), pushed away from the camera by 0.8 of the object's half width
(the pixels are on its near side), and, for an object resting on the floor (the centroid
below the top of the resting object), set to the known height of its model (a known object
on a known support plane); higher, the object is off the floor and the centroid's height is
kept (the pick check only compares it with the height before the lift). The run's pose noise (sigma,
m) is added to x and y, drawn from the seed and the frame. The estimate on the floor is the
median of the object's last `FUSED` whole views since it last moved (a filter over frames, as a
tracker's: a noisy detector's one-frame jump or a mask a pixel too wide does not move it);
its height is the last view's. Yaw is not estimated (it keeps the
prior): only the obstacle box has one that matters, and it appears with yaw 0. A detection
whose size (pixels x depth^2) is below `WHOLE` of the largest seen for that object is partly
hidden and is not used, except by the view that confirms the object moved: it is believed
there all the same, and its size is learnt anew from there (it may stand another way up).

Identity is the estimator's own: the detector reports each object's *class* (its model:
``bottle``, ``obstacle``), never which object it is, and `ObjectPoseEstimator._associate`
pairs a view's detections with the objects of their class by position (least total distance
to the current estimates, within a gate; then what is left of both by distance alone: an
object a person put somewhere else, believed once seen there in `CONFIRM` views in a row and
never where another object stands), as a tracker would.

Before the camera has seen an object its estimate is the prior: where the demonstration
showed it (the nominal pose, not the perturbed one); an object that appears later (Case 3's
O_a) is unknown (left outside the workspace) until seen. While the gripper reports holding
an object, its estimate follows the hand (kinematics), not the camera.

The output has the shape of the plant's ``body_poses`` (one `RigidTransform` per body
index): the robot's own bodies come from the plant (proprioception), the objects' entries
are the estimates. The skill controller and the world-state estimator read it instead of the
plant's port, so nothing that decides reads an object pose from the plant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import EventStatus, LeafSystem
from scipy.optimize import linear_sum_assignment

from tamp.perturbation import stream
from tamp.sim.core.camera import backproject
from tamp.sim.core.messages import GraspRequest, Observation, ViewRequest
from tamp.sim.smp.robot import ObjectKind

#: the detections' pixels lie on the object's near side: its centre is this many radii farther
#: (measured on bottles 1.1-1.8 m away: 0.78-0.90 r; lateral error below 1.5 mm)
NEAR_SIDE = 0.8
#: a detection counts only when its size (pixels x depth^2) is this share of the object's
#: largest so far: a partly hidden object's centroid is off by centimetres (measured 1.8 cm)
WHOLE = 0.8
#: how far (m, in the floor plane) a detection may lie from the estimate of an object seen
#: before and still be that object (between two views 0.1 s apart only a carried or falling
#: object moves; the nearest other object of a kind is farther in every packaged case)
GATE = 0.15
#: ... from the prior of an object not seen yet (its start is perturbed: 3 sigma of 3 cm)
FIRST_GATE = 0.25
#: a detection this near (m) another object's estimate is that object: no object moves there
OCCUPIED = 0.08
#: an object's place on the floor (x, y) is the per-axis median of its last this many whole
#: views since it last moved (its height is the last view's: a lift must show at once): one
#: view's error (a detector's mask a pixel off, a centroid that jumps for a frame) does not
#: move it
FUSED = 5
#: the name of what the mast camera looks at (perception's workspace: the cell's floor)
VIEW_SIDE = "floor"
#: views in a row an object must be seen away from its estimate before it is believed moved
#: there (a lone false detection or class swap moves nothing)
CONFIRM = 2
#: an object let go at most this high above its resting height is taken to rest on the floor
#: (a friction-held object slips up to ~2 cm in the fingers, so the hand is that much higher)
LET_GO = 0.04


@dataclass(frozen=True)
class EstimatorState:
    """Request counter, per-object estimates (x, y, z, yaw), camera poses by render time."""

    request: int = 0
    used: int = 0  # the last observation id turned into estimates
    estimates: dict = field(default_factory=dict)
    seen: dict = field(default_factory=dict)  # object -> sim time it was last detected
    cameras: dict = field(default_factory=dict)  # time key (us) -> X_WC
    following: str | None = None  # the object in the closed hand (its pose is the hand's)
    #: per object, the largest pixels x depth^2 seen: its size in a full view
    full: dict = field(default_factory=dict)
    #: per object seen away from its estimate: (x, y, views in a row there), until confirmed
    moving: dict = field(default_factory=dict)
    #: per object, its last `FUSED` whole views' places (x, y) since it last moved
    views: dict = field(default_factory=dict)

    def __deepcopy__(self, memo: dict) -> EstimatorState:
        return self  # replaced, never changed in place


class ObjectPoseEstimator(LeafSystem):
    """Object poses from camera detections (module docstring)."""

    def __init__(
        self,
        *,
        bodies: dict[str, int],
        kinds: dict[str, ObjectKind],
        prior: dict[str, tuple[float, float, float, float]],
        camera_body: int,
        X_BC: RigidTransform,
        intrinsics: tuple[float, float, float, float],
        palm_body: int,
        grasp_offset: float,
        period: float,
        pose_noise: float = 0.0,
        seed: int = 0,
    ):
        super().__init__()
        self.set_name("object_pose_estimator")
        self._bodies = dict(bodies)
        self._kinds = dict(kinds)
        self._camera_body = camera_body
        self._X_BC = X_BC
        self._K = intrinsics
        self._palm = palm_body
        self._grasp_offset = grasp_offset
        self._noise = float(pose_noise)
        self._seed = int(seed)
        self.body_poses_in = self.DeclareAbstractInputPort(
            "plant_body_poses", AbstractValue.Make([RigidTransform()])
        )
        self.observation_port = self.DeclareAbstractInputPort(
            "observation", AbstractValue.Make(Observation())
        )
        self.grasp_port = self.DeclareAbstractInputPort("grasp", AbstractValue.Make(GraspRequest()))
        init = EstimatorState(estimates=dict(prior))
        self._state = self.DeclareAbstractState(AbstractValue.Make(init))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        only_state = {self.abstract_state_ticket(self._state)}
        # the request carries the camera's pose when it is served (the base's pose and the
        # mast's mount: the robot's own kinematics), as a learned detector needs it
        self.view_request_port = self.DeclareAbstractOutputPort(
            "view_request",
            lambda: AbstractValue.Make(ViewRequest()),
            self._calc_request,
            prerequisites_of_calc=only_state
            | {self.input_port_ticket(self.body_poses_in.get_index())},
        )
        self.body_poses_port = self.DeclareAbstractOutputPort(
            "body_poses",
            lambda: AbstractValue.Make([RigidTransform()]),
            self._calc_poses,
            prerequisites_of_calc=only_state
            | {self.input_port_ticket(self.body_poses_in.get_index())},
        )

    def state(self, context) -> EstimatorState:
        return context.get_abstract_state(self._state).get_value()

    def _calc_request(self, context, output) -> None:
        X_WC = self.body_poses_in.Eval(context)[self._camera_body].multiply(self._X_BC)
        output.set_value(ViewRequest(self.state(context).request, VIEW_SIDE, camera_pose=X_WC))

    def _calc_poses(self, context, output) -> None:
        poses = list(self.body_poses_in.Eval(context))
        s = self.state(context)
        for uid, (x, y, z, yaw) in s.estimates.items():
            if uid == s.following:
                x, y, z, yaw = self._in_hand(poses, uid, yaw)
            poses[self._bodies[uid]] = RigidTransform(RotationMatrix.MakeZRotation(yaw), [x, y, z])
        output.set_value(poses)

    def _in_hand(self, plant_poses, uid: str, yaw: float) -> tuple[float, float, float, float]:
        """Where a held object is: at the grasp point of the hand (the arm's kinematics)."""
        X_G = plant_poses[self._palm].multiply(RigidTransform([0.0, 0.0, self._grasp_offset]))
        p = X_G.translation()
        return (float(p[0]), float(p[1]), float(p[2] - self._kinds[uid].grasp_height), yaw)

    def _update(self, context, state) -> EventStatus:
        s = self.state(context)
        t = context.get_time()
        plant_poses = self.body_poses_in.Eval(context)
        estimates = dict(s.estimates)
        seen = dict(s.seen)
        full = dict(s.full)
        moving = dict(s.moving)
        views = dict(s.views)
        cameras = {k: v for k, v in s.cameras.items() if k >= _key(t - 1.0)}
        X_WC = plant_poses[self._camera_body].multiply(self._X_BC)
        cameras[_key(t)] = X_WC
        obs: Observation = self.observation_port.Eval(context)
        used = s.used
        if obs.id and obs.id != s.used and _key(obs.time) in s.cameras:
            used = obs.id
            rng = stream(self._seed, "sensor", "pose", obs.id)
            X_view = s.cameras[_key(obs.time)]
            for uid, det, moved in self._associate(obs.detections, X_view, s):
                if moved:  # seen away from its estimate: believed once seen there again
                    xy = self._estimate(det, X_view, 0.0, self._kinds[uid])[:2]
                    moving[uid] = seen_moved(moving.get(uid), xy)
                    if moving[uid][2] < CONFIRM:
                        continue
                moving.pop(uid, None)
                if moved:  # it stands somewhere else now: the views before are of there
                    views.pop(uid, None)
                size = det.pixels * det.depth**2  # about constant over distance, unoccluded
                # an object confirmed moved is believed there even when partly hidden
                # (centimetres off beats where it was before), and its full size is learnt
                # anew: it may stand another way up, seen from another side
                full[uid] = size if moved else max(full.get(uid, 0.0), size)
                if size < WHOLE * full[uid]:
                    # partly hidden (by the arm, the held object, the image border): its
                    # centroid is off by centimetres
                    continue
                est = self._estimate(det, X_view, estimates[uid][3], self._kinds[uid])
                if self._noise > 0:
                    dx, dy = np.clip(rng.standard_normal(2), -3.0, 3.0) * self._noise
                    est = (est[0] + float(dx), est[1] + float(dy), est[2], est[3])
                views[uid] = (*views.get(uid, ()), est[:2])[-FUSED:]
                x, y = np.median(np.array(views[uid]), axis=0)
                estimates[uid] = (float(x), float(y), est[2], est[3])
                seen[uid] = obs.time
        grasp: GraspRequest = self.grasp_port.Eval(context)
        held = grasp.holding
        following = held if held is not None and grasp.obj == held else None
        # the held object, or the one just let go (the hand is still where it put it down:
        # release and opening take longer than one period), is where the hand is
        for uid in {following, s.following} - {None}:
            estimates[uid] = self._in_hand(plant_poses, uid, estimates[uid][3])
            views.pop(uid, None)  # carried: where it was seen is no longer where it is
        if s.following is not None and following is None:  # let go just above the floor:
            x, y, z, yaw = estimates[s.following]  # it rests on it (the arm lowered it there)
            hh = self._kinds[s.following].half_height
            estimates[s.following] = (x, y, hh if z < hh + LET_GO else z, yaw)
        state.get_mutable_abstract_state(self._state).set_value(
            EstimatorState(
                s.request + 1, used, estimates, seen, cameras, following, full, moving, views
            )
        )
        return EventStatus.Succeeded()

    def _associate(self, detections, X_WC, s: EstimatorState) -> list[tuple[str, object, bool]]:
        """Which object each detection of this view is (module docstring, "Identity"), and
        whether it was seen away from its estimate: per class, detections and the objects
        of that kind are paired by least total planar distance between the detection's
        position and the object's estimate, first within `GATE` of an object seen before or
        `FIRST_GATE` of one not seen yet (its prior, the demonstration's pose); then the
        detections left over and the objects of their kind that no detection of this view
        explains are paired by least total distance whatever it is (moved: an object a
        person put down elsewhere, as Case 3's O_a appears on a place), except where another
        object is believed to stand (within `OCCUPIED` of its estimate: a detection there
        is that object, seen as the wrong class; the object in the hand stands nowhere on
        the floor). A detection left over is no object the
        robot knows: it is ignored."""
        out: list[tuple[str, object, bool]] = []
        by_class: dict[str, list] = {}
        for det in detections:
            by_class.setdefault(det.cls, []).append(det)
        for cls, dets in by_class.items():
            uids = [u for u, k in self._kinds.items() if k.name == cls]
            if not uids:
                continue
            kind = self._kinds[uids[0]]
            where = np.array([self._estimate(d, X_WC, 0.0, kind)[:2] for d in dets])
            est = np.array([s.estimates[u][:2] for u in uids])
            dist = np.linalg.norm(where[:, None, :] - est[None, :, :], axis=2)
            gate = np.array([GATE if u in s.seen else FIRST_GATE for u in uids])
            near = _pair(np.where(dist <= gate[None, :], dist, np.inf))
            out += [(uids[j], dets[i], False) for i, j in near]
            free_d = [i for i in range(len(dets)) if i not in {i for i, _ in near}]
            free_u = [j for j in range(len(uids)) if j not in {j for _, j in near}]
            # the object in the hand is where the hand is (kinematics), above the floor: a
            # detection under it is another object (Case 3's O_a on the place being served)
            others = [xy[:2] for u, xy in s.estimates.items() if u not in uids and u != s.following]
            free_d = [
                i
                for i in free_d
                if all(math.dist(where[i], o) > OCCUPIED for o in others)
                and all(dist[i, j] > OCCUPIED for j in range(len(uids)) if j not in free_u)
            ]
            if free_d and free_u:
                far = _pair(dist[np.ix_(free_d, free_u)])
                out += [(uids[free_u[j]], dets[free_d[i]], True) for i, j in far]
        return out

    def _estimate(
        self, det, X_WC, yaw: float, kind: ObjectKind
    ) -> tuple[float, float, float, float]:
        # a detection's centroid is a mean of pixel indices; a pixel's centre is half a
        # pixel further (measured: a 0.5 px lateral bias, ~6 mm at 1.3 m, without it)
        p = backproject(det.u + 0.5, det.v + 0.5, det.depth, self._K, X_WC)
        c = X_WC.translation()
        d = np.array([p[0] - c[0], p[1] - c[1]])
        n = float(np.linalg.norm(d))
        if n > 1e-9:
            p[:2] += NEAR_SIDE * kind.half_width * d / n
        z = float(p[2])
        if z < 2 * kind.half_height:
            # the visible pixels' centroid lies below the top of a resting object (seen from
            # above, it is biased upward from the centre): resting, at its model's height
            z = kind.half_height
        return (float(p[0]), float(p[1]), z, yaw)


def seen_moved(
    before: tuple[float, float, int] | None, xy: tuple[float, float]
) -> tuple[float, float, int]:
    """(x, y, views in a row) of an object seen away from its estimate at ``xy``, after
    ``before`` (None: not so seen in the last view): one more view when within `GATE` of
    where it was seen then, else a first one here."""
    x, y = float(xy[0]), float(xy[1])
    if before is not None and math.hypot(x - before[0], y - before[1]) <= GATE:
        return (x, y, before[2] + 1)
    return (x, y, 1)


def _pair(cost: np.ndarray) -> list[tuple[int, int]]:
    """The (row, column) pairs of least total cost, none at an infinite cost."""
    if cost.size == 0:
        return []
    finite = np.isfinite(cost)
    rows, cols = linear_sum_assignment(np.where(finite, cost, 1e9))
    return [(int(i), int(j)) for i, j in zip(rows, cols, strict=True) if finite[i, j]]


def _key(t: float) -> int:
    return int(round(t * 1e6))


def prior_poses(objects, parking) -> dict[str, tuple[float, float, float, float]]:
    """Where the robot believes each object is before seeing it: the nominal start pose, or
    (an object that appears later) a parking spot outside the workspace."""
    out = {}
    for i, o in enumerate(objects):
        if o.appear is None and not math.isnan(o.xy[0]):
            out[o.id] = (o.xy[0], o.xy[1], o.kind.half_height, o.yaw)
        else:
            x, y = parking(i)
            out[o.id] = (x, y, o.kind.half_height, 0.0)
    return out
