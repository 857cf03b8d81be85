"""One seeded run of an SMP-MRO scenario: its perturbation sample applied (no Drake import).

`perturb(scenario, seed)` draws ``scenario.perturbation`` for ``seed``
(`tamp.perturbation`) and returns a new `SimScenario` with
- every object standing at the start moved by its drawn offset (x, y, yaw); an offset that
  would put it outside the workspace, onto another object (moved or still nominal) or under
  the robot is redrawn (up to `REDRAWS` times, then the object keeps its nominal pose, with
  a note), so the start stays valid;
- the robot's start pose moved likewise (drawn first, so objects avoid it);
- appearances at a time or tick shifted by the person's timing jitter (never below 0);
- `RunConditions`: the seed, the objects' friction coefficient, the camera's depth noise and
  the perceived pose noise, and the Pick attempts that fail by the drawn chance;
and the `Applied` record the run's JSON carries. Nothing is mutated. The demonstration (and
so the plan and its verification) stays nominal: the robot was shown the nominal poses.
"""

from __future__ import annotations

import dataclasses
import math

from tamp.perturbation import Applied, check_seed
from tamp.sim.smp.robot import ROBOT
from tamp.sim.smp.scenario import RunConditions, SimObject, SimScenario
from tamp.world.events import AtTick, AtTime

#: how often a colliding start offset is redrawn before the nominal pose is kept
REDRAWS = 20


def perturb(scenario: SimScenario, seed: int) -> tuple[SimScenario, Applied]:
    """``scenario`` as run ``seed`` sees it, and what was applied (module docstring)."""
    seed = check_seed(seed)
    spec = scenario.perturbation
    sample = spec.sample(seed)
    applied = Applied(seed=seed)
    rx, ry, ryaw = scenario.robot_start
    standing = [o for o in scenario.objects if o.appear is None]
    dx, dy, dyaw = sample.robot
    if (dx, dy) != (0.0, 0.0) and not _robot_fits(scenario, rx + dx, ry + dy, standing):
        applied.notes.append("robot: the drawn start overlaps an object; nominal start kept")
        dx, dy = 0.0, 0.0
    robot = (rx + dx, ry + dy, ryaw + dyaw)
    applied.robot = (dx, dy, dyaw)

    placed: list[SimObject] = []
    objects: list[SimObject] = []
    for i, o in enumerate(scenario.objects):
        later = [p for p in scenario.objects[i + 1 :] if p.appear is None]
        if o.appear is not None:
            objects.append(_jittered(o, sample.jitter(o.id), applied, scenario.executor.bt_period))
            continue
        moved = None
        if spec.objects.active:
            for attempt in range(REDRAWS):
                ox, oy, oyaw = sample.object_offset(o.id, attempt)
                cand = dataclasses.replace(o, xy=(o.xy[0] + ox, o.xy[1] + oy), yaw=o.yaw + oyaw)
                if _object_fits(scenario, cand, placed + later, robot):
                    moved, offset = cand, (ox, oy, oyaw)
                    break
            if moved is None:
                applied.notes.append(f"{o.id}: no free start in {REDRAWS} draws; nominal kept")
        if moved is None:
            moved, offset = o, (0.0, 0.0, 0.0)
        applied.objects[o.id] = offset
        placed.append(moved)
        objects.append(moved)

    failures = []
    for action in spec.skill_failure:
        draws = sample.skill_failures(action)
        failures.append((action, draws))
        applied.skill_failures[action] = [i + 1 for i, fails in enumerate(draws) if fails]
    applied.friction = sample.friction
    applied.depth_noise = spec.depth_noise
    applied.pose_noise = spec.pose_noise
    applied.detector = spec.detector
    conditions = RunConditions(
        seed=seed,
        friction=sample.friction,
        depth_noise=spec.depth_noise,
        pose_noise=spec.pose_noise,
        detector=spec.detector,
        chance_failures=tuple(failures),
        nominal=tuple((o.id, o.xy[0], o.xy[1], o.yaw) for o in standing),
    )
    out = dataclasses.replace(
        scenario, robot_start=robot, objects=tuple(objects), conditions=conditions
    )
    return out, applied


def _robot_fits(s: SimScenario, x: float, y: float, objects: list[SimObject]) -> bool:
    if not s.in_workspace(x, y, margin=ROBOT.footprint_radius):
        return False
    return all(
        math.dist((x, y), o.xy) >= ROBOT.footprint_radius + o.kind.radius + 0.01 for o in objects
    )


def _object_fits(
    s: SimScenario, o: SimObject, placed: list[SimObject], robot: tuple[float, float, float]
) -> bool:
    """Inside the workspace, apart from the objects placed so far and from the robot."""
    if not s.in_workspace(*o.xy, margin=o.kind.radius):
        return False
    if math.dist(o.xy, robot[:2]) < ROBOT.footprint_radius + o.kind.radius + 0.01:
        return False
    return all(math.dist(o.xy, p.xy) >= o.kind.radius + p.kind.radius + 0.01 for p in placed)


def _jittered(o: SimObject, shift: float, applied: Applied, bt_period: float) -> SimObject:
    """An appearance at a time or tick moved by the person's jitter (``after:``/reach ones
    depend on the robot and stay)."""
    when = o.appear.when
    if shift == 0.0 or not isinstance(when, AtTime | AtTick):
        return o
    t0 = when.seconds if isinstance(when, AtTime) else when.tick * bt_period
    if t0 == 0.0:
        return o  # there from the start: checked against the start places, kept
    t = max(0.0, t0 + shift)
    applied.timing[o.id] = t - t0
    return dataclasses.replace(o, appear=dataclasses.replace(o.appear, when=AtTime(t)))
