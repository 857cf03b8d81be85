"""Seeded perturbations of a simulation run: one concept for every workcell.

A scenario file (SMP-MRO ``tamp/scenarios/sim``, LOTS ``lots_sim``, refinement programs) may
carry a ``perturbation:`` section; it is parsed strictly here (`parse_perturbation`, errors
name file and field) into a `Perturbation`. ``Perturbation.sample(seed)`` draws one
`PerturbationSample` from ``numpy.random.default_rng``: the same seed gives the same sample
bit for bit. Each workcell applies a sample to its own scenario (a new scenario, nothing
mutated: `tamp.sim.smp.perturb.perturb`, `tamp.sim.lots.scenario.perturbed`,
`tamp.sim.refine.simulate.perturbed_program`) and records what it applied as an `Applied`
(JSON: the sampled values and the perturbation's ``size``, the largest start displacement
of an object, so a campaign can plot success against it). No Drake import here.

Format (every key optional; a spread is a standard deviation for ``normal``, clipped at
3 sigma so every draw is bounded, or the half-width of the range for ``uniform``)::

    perturbation:
      objects: {distribution: normal, xy: 0.02, yaw: 0.2}   # m per axis, rad
      robot: {distribution: uniform, xy: 0.05, yaw: 0.05}   # the robot's start pose
      friction: [0.5, 0.9]          # Coulomb coefficient of the objects, uniform in the range
      sensor: {depth_noise: 0.002, pose_noise: 0.005}       # m: per depth pixel, per estimate
      sensor: {detector: high}      # the seeded noisy detector's level (low or high)
      timing: {jitter: 0.5}         # s: sigma of the time of each of the person's actions
      skills: {Pick: 0.05}          # probability that one attempt of the action fails

Independent streams. Every quantity is drawn from its own generator keyed by the seed and a
stable name (``default_rng([seed, crc32(stream), crc32(key), index])``), so adding an object
to a scene or a field to the section does not change the other draws.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tamp.errors import InputError
from tamp.fileio import Fields

DISTRIBUTIONS = ("normal", "uniform")
#: a normal draw is clipped at this many standard deviations (every offset stays bounded)
NORMAL_CLIP = 3.0
#: bounds of the spreads a file may ask for (beyond them a start pose is not "perturbed")
MAX_XY = 0.5
MAX_YAW = math.pi
FRICTION_RANGE = (0.05, 2.0)
MAX_DEPTH_NOISE = 0.05
MAX_POSE_NOISE = 0.2
#: levels of the seeded noisy detector (`tamp.sim.core.detection_noise.LEVELS` defines them):
#: misses, class swaps, mask jitter, fresh identities and false positives in every view
DETECTOR_LEVELS = ("low", "high")
MAX_JITTER = 60.0
#: how many attempts of one action get a drawn failure flag (later attempts succeed)
MAX_ATTEMPTS = 32
SEED_RANGE = (0, 2**63 - 1)


def check_seed(seed: Any, field: str = "--seed") -> int:
    """A seed is a non-negative integer below 2^63 (`InputError` naming ``field``)."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise InputError(f"expected a non-negative integer, got {seed!r}", field=field)
    if not SEED_RANGE[0] <= int(seed) <= SEED_RANGE[1]:
        raise InputError(f"must lie within [0, 2^63 - 1], got {seed}", field=field)
    return int(seed)


def _key(text: str) -> int:
    return zlib.crc32(text.encode())


def stream(seed: int, name: str, key: str = "", index: int = 0) -> np.random.Generator:
    """The generator of one named quantity of run ``seed`` (independent of the others)."""
    return np.random.default_rng([int(seed), _key(name), _key(key), int(index)])


@dataclass(frozen=True)
class PoseSpread:
    """How far a start pose is moved: ``xy`` per axis (m) and ``yaw`` (rad) under
    ``distribution`` (normal: sigma, clipped at `NORMAL_CLIP` sigma; uniform: half-range)."""

    distribution: str = "normal"
    xy: float = 0.0
    yaw: float = 0.0

    @property
    def active(self) -> bool:
        return self.xy > 0.0 or self.yaw > 0.0

    def draw(self, rng: np.random.Generator) -> tuple[float, float, float]:
        """(dx, dy, dyaw); always three draws, so the stream is the same whatever is zero."""
        if self.distribution == "uniform":
            u = rng.uniform(-1.0, 1.0, size=3)
        else:
            u = np.clip(rng.standard_normal(3), -NORMAL_CLIP, NORMAL_CLIP)
        return (float(u[0] * self.xy), float(u[1] * self.xy), float(u[2] * self.yaw))

    def to_json(self) -> dict[str, Any]:
        return {"distribution": self.distribution, "xy": self.xy, "yaw": self.yaw}


@dataclass(frozen=True)
class Perturbation:
    """A scenario's ``perturbation:`` section (module docstring); all zero = none."""

    objects: PoseSpread = PoseSpread()
    robot: PoseSpread = PoseSpread()
    friction: tuple[float, float] | None = None
    depth_noise: float = 0.0
    pose_noise: float = 0.0
    timing_jitter: float = 0.0
    skill_failure: Mapping[str, float] = field(default_factory=dict)
    source: str = ""
    detector: str | None = None  # noisy detector level (`DETECTOR_LEVELS`); None: exact

    def sample(self, seed: int) -> PerturbationSample:
        """Run ``seed``'s draw of this perturbation (same seed, same sample, bit for bit)."""
        seed = check_seed(seed)
        robot = self.robot.draw(stream(seed, "robot")) if self.robot.active else (0.0, 0.0, 0.0)
        friction = None
        if self.friction is not None:
            lo, hi = self.friction
            friction = float(stream(seed, "friction").uniform(lo, hi)) if hi > lo else lo
        return PerturbationSample(seed, self, robot, friction)

    def fields(self) -> set[str]:
        """The top-level keys this perturbation sets (for a workcell's "what I simulate")."""
        out = set()
        if self.objects.active:
            out.add("objects")
        if self.robot.active:
            out.add("robot")
        if self.friction is not None:
            out.add("friction")
        if self.depth_noise > 0 or self.pose_noise > 0 or self.detector is not None:
            out.add("sensor")
        if self.timing_jitter > 0:
            out.add("timing")
        if self.skill_failure:
            out.add("skills")
        return out

    def require(self, supported: Iterable[str], workcell: str) -> None:
        """Refuse a field the workcell does not simulate (`InputError` naming it)."""
        for name in sorted(self.fields() - set(supported)):
            raise InputError(
                f"not simulated by the {workcell} workcell (it simulates: "
                f"{', '.join(sorted(supported)) or 'nothing'})",
                file=self.source or None,
                field=f"perturbation.{name}",
            )

    def to_json(self) -> dict[str, Any]:
        return {
            "objects": self.objects.to_json(),
            "robot": self.robot.to_json(),
            "friction": None if self.friction is None else list(self.friction),
            "sensor": {
                "depth_noise": self.depth_noise,
                "pose_noise": self.pose_noise,
                "detector": self.detector,
            },
            "timing": {"jitter": self.timing_jitter},
            "skills": dict(self.skill_failure),
        }


NONE = Perturbation()


@dataclass(frozen=True)
class PerturbationSample:
    """One run's draw: the robot's start offset and the friction coefficient, drawn at once;
    per-object offsets, timing jitters, skill failures and sensor noise drawn on demand from
    their own keyed streams (`stream`), so they depend on the seed and their key only."""

    seed: int
    spec: Perturbation
    robot: tuple[float, float, float]
    friction: float | None

    def robot_offset(self, name: str, attempt: int = 0) -> tuple[float, float, float]:
        """(dx, dy, dyaw) of the start of robot ``name`` (workcells with several robots)."""
        if not self.spec.robot.active:
            return (0.0, 0.0, 0.0)
        return self.spec.robot.draw(stream(self.seed, "robot", name, attempt))

    def object_offset(self, uid: str, attempt: int = 0) -> tuple[float, float, float]:
        """(dx, dy, dyaw) of object ``uid``; ``attempt`` > 0 redraws (a start that collides)."""
        if not self.spec.objects.active:
            return (0.0, 0.0, 0.0)
        return self.spec.objects.draw(stream(self.seed, "object", uid, attempt))

    def jitter(self, key: str) -> float:
        """The time shift (s) of the person's action ``key`` (normal, clipped at 3 sigma)."""
        if self.spec.timing_jitter <= 0:
            return 0.0
        z = float(np.clip(stream(self.seed, "timing", key).standard_normal(), -3.0, 3.0))
        return z * self.spec.timing_jitter

    def skill_failures(self, action: str) -> tuple[bool, ...]:
        """For attempts 1..`MAX_ATTEMPTS` of ``action`` (all arguments together), whether the
        attempt fails by the drawn chance (``skills``); empty when the action has none."""
        p = self.spec.skill_failure.get(action, 0.0)
        if p <= 0:
            return ()
        u = stream(self.seed, "skill", action).uniform(size=MAX_ATTEMPTS)
        return tuple(bool(v < p) for v in u)

    def noise(self, name: str, index: int) -> np.random.Generator:
        """The generator of sensor frame ``index`` of sensor ``name`` (depth or pose noise)."""
        return stream(self.seed, "sensor", name, index)


@dataclass
class Applied:
    """What a workcell applied from a sample: the JSON of a run's ``perturbation``."""

    seed: int
    objects: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    robot: tuple[float, float, float] = (0.0, 0.0, 0.0)
    robots: dict[str, tuple[float, float, float]] = field(default_factory=dict)  # several
    friction: float | None = None
    depth_noise: float = 0.0
    pose_noise: float = 0.0
    detector: str | None = None  # the noisy detector's level, drawn from this seed per view
    timing: dict[str, float] = field(default_factory=dict)
    skill_failures: dict[str, list[int]] = field(default_factory=dict)  # failing attempts
    notes: list[str] = field(default_factory=list)

    @property
    def size(self) -> float:
        """The perturbation's size: the largest start displacement of an object (m)."""
        return max((math.hypot(dx, dy) for dx, dy, _ in self.objects.values()), default=0.0)

    def to_json(self) -> dict[str, Any]:
        def r(v: tuple[float, ...]) -> list[float]:
            return [round(x, 6) for x in v]

        return {
            "seed": self.seed,
            "size": round(self.size, 6),
            "robot_displacement": round(
                max(math.hypot(*v[:2]) for v in [self.robot, *self.robots.values()]), 6
            ),
            "objects": {k: r(v) for k, v in sorted(self.objects.items())},
            "robot": r(self.robot),
            "robots": {k: r(v) for k, v in sorted(self.robots.items())},
            "friction": None if self.friction is None else round(self.friction, 6),
            "depth_noise": self.depth_noise,
            "pose_noise": self.pose_noise,
            "detector": self.detector,
            "timing": {k: round(v, 6) for k, v in sorted(self.timing.items())},
            "skill_failures": {k: list(v) for k, v in sorted(self.skill_failures.items())},
            "notes": list(self.notes),
        }


def unperturbed(seed: int) -> Applied:
    """The record of a run without a perturbation section (its seed only)."""
    return Applied(seed=check_seed(seed))


# -- parsing --------------------------------------------------------------------------------
def parse_perturbation(f: Fields, key: str = "perturbation") -> Perturbation:
    """The ``key`` section of a scenario mapping (absent: `NONE`), validated strictly."""
    if not f.has(key):
        return NONE
    p = f.sub(key)
    p.check_keys({"objects", "robot", "friction", "sensor", "timing", "skills"})
    objects = _spread(p, "objects")
    robot = _spread(p, "robot")
    friction = None
    if p.has("friction"):
        lo, hi = p.vector("friction", 2)
        for i, v in enumerate((lo, hi)):
            if not FRICTION_RANGE[0] <= v <= FRICTION_RANGE[1]:
                raise p.error(
                    f"friction[{i}]",
                    f"a friction coefficient must lie within {list(FRICTION_RANGE)}, got {v}",
                )
        if hi < lo:
            raise p.error("friction", f"expected [low, high] with low <= high, got {[lo, hi]}")
        friction = (lo, hi)
    s = p.sub("sensor", {})
    s.check_keys({"depth_noise", "pose_noise", "detector"})
    depth_noise = s.float("depth_noise", 0.0, min=0.0, max=MAX_DEPTH_NOISE)
    pose_noise = s.float("pose_noise", 0.0, min=0.0, max=MAX_POSE_NOISE)
    detector = s.str("detector", choices=DETECTOR_LEVELS) if s.has("detector") else None
    t = p.sub("timing", {})
    t.check_keys({"jitter"})
    jitter = t.float("jitter", 0.0, min=0.0, max=MAX_JITTER)
    k = p.sub("skills", {})
    skills = {}
    for name in k.data:
        if not isinstance(name, str) or not name.isidentifier():
            raise k.error(str(name), "expected an action name (e.g. Pick)")
        prob = k.float(name, min=0.0, max=1.0)
        if prob >= 1.0:
            raise k.error(name, f"a failure probability must be below 1, got {prob}")
        skills[name] = prob
    return Perturbation(
        objects=objects,
        robot=robot,
        friction=friction,
        depth_noise=depth_noise,
        pose_noise=pose_noise,
        timing_jitter=jitter,
        skill_failure=skills,
        source=f.file,
        detector=detector,
    )


def _spread(p: Fields, key: str) -> PoseSpread:
    s = p.sub(key, {})
    s.check_keys({"distribution", "xy", "yaw"})
    return PoseSpread(
        distribution=s.str("distribution", "normal", choices=DISTRIBUTIONS),
        xy=s.float("xy", 0.0, min=0.0, max=MAX_XY),
        yaw=s.float("yaw", 0.0, min=0.0, max=MAX_YAW),
    )
