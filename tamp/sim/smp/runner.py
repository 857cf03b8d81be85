"""SimRunner: runs the SMP-MRO diagram and does what must happen *between* steps.

It advances the simulator in chunks of one controller period (`tamp.sim.core.runner`).

Weld toggling. A weld constraint's active status lives in the plant's context and is not an
output of any system, so no LeafSystem event can switch it. Between chunks the runner reads
the `YouBotSkillController`'s ``grasp`` output and switches the matching weld on (or every weld
off) with `MultibodyPlant.SetConstraintActiveStatus`. The controller asks for a weld only
once the fingers have closed at the grasp pose, and waits a dwell longer than one chunk
before it lifts, so the weld is always on when the lift starts (a weld switched on with the
bodies apart snaps them together in one step).

Appearances. An object that "appears" (Case 3's O_a) waits outside the workspace; at its
WHEN (`tamp.world.events`: a tick, a time, right after a named skill succeeds, or, without
one, when the robot first comes within reach of the place) the runner puts it down at the
place (an area's centre or a point) and zeroes its velocity. This is a person putting an
object down (scripted), not the robot. A person does not put an object *into* another one:
when the place is occupied at that moment (`tamp.sim.smp.placement.blocker`: another
object's footprint, or the robot's base), the object is put down on the nearest free spot
outside every area (run-time ones included) and every footprint instead, and the run
carries a warning saying so (`SimResult.warnings`). Whether a place will be occupied can
only be known when the time comes, except at time 0, which the scenario checks refuse
(`tamp.sim.smp.scenario`, exit 2).

The run ends when the BtExecutor's tree returns SUCCESS or FAILURE, or at
``max_sim_time``. Its status is decided once, by `judge`, from the tree's result AND the
plant: SUCCESS only when the tree succeeded, every goal object rests in its final goal
area in 3-D (`tamp.sim.smp.placement.why_not_in`: inside the area in the plane and upright
on the floor, not on top of another object), and no object, goal or not, appeared ones
included, was left disturbed (`tamp.sim.smp.placement.disturbances`: knocked over, on top
of another object, or moved though the robot never picked it, measured from where the
scenario or the person last put it). `SimResult` (a `RunResult`: ``ok`` and the exit
code follow the status and nothing else) also has the executed actions with sim start/end
times, final plant poses of the objects, the disturbed objects, sim time, wall time and the
real-time factor.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.math import SpatialVelocity

from tamp.sim.core.executor import ActionLog
from tamp.sim.core.outcome import run_cause
from tamp.sim.core.runner import make_simulator, run_in_chunks
from tamp.sim.core.workcell import RunResult
from tamp.sim.smp.ik import grasp_transform
from tamp.sim.smp.placement import (
    Body,
    Disturbance,
    blocker,
    disturbances,
    free_spot,
    why_not_in,
)
from tamp.sim.smp.robot import ROBOT
from tamp.sim.smp.station import SmpStation
from tamp.world.events import AfterAction, Appear, AtTick, AtTime, format_call, parse_call
from tamp.world.interface import Status


@dataclass
class ObjectPose:
    x: float
    y: float
    z: float
    yaw: float

    def to_json(self) -> dict:
        return {k: round(v, 4) for k, v in vars(self).items()}


def judge(
    tree: Status | None,
    tree_reason: str,
    goal_failures: list[str],
    limit: float,
    disturbed: list[str] | None = None,
) -> tuple[str, str]:
    """The run's (status, reason), the one place that decides them: TIMEOUT when the tree
    gave no result within ``limit`` s, FAILURE when it failed, or when it succeeded but the
    plant disagrees (``goal_failures``: why goal objects do not rest in their areas;
    ``disturbed``: objects left knocked over, on top of another or moved unpicked,
    `tamp.sim.smp.placement.Disturbance.reason`), else SUCCESS."""
    if tree is None:
        return "TIMEOUT", f"no result within {limit:g} s of sim time"
    if tree is not Status.SUCCESS:
        return "FAILURE", tree_reason or "tree failed"
    wrong = [*goal_failures, *(disturbed or [])]
    if wrong:
        return "FAILURE", "the tree succeeded but on the plant " + "; ".join(wrong)
    return "SUCCESS", tree_reason or "every goal reached"


def picked_objects(actions: list[ActionLog]) -> set[str]:
    """The objects of the executed actions' successful ``Pick``s: what the robot moved on
    purpose (PA-BT's obstacle relocation included)."""
    out = set()
    for a in actions:
        if a.status == "SUCCESS":
            name, args = parse_call(a.action)
            if name == "Pick" and args:
                out.add(args[0])
    return out


@dataclass(kw_only=True)
class SimResult(RunResult):
    """What an SMP-MRO run did, read from the plant and the executor's state.

    The verdict, its cause and the times are the common `RunResult` (``status``, decided by
    `judge`, is the one verdict; ``ok`` and the exit code derive from it; ``task_time`` is
    the sim time the run took). The cell's own: the executed actions with sim start/end
    times, the objects' final plant poses, the robot's base path, when objects appeared,
    which goals hold on the plant, warnings, every skill failure, the grasp and perception
    modes, the RG's goal order (SMP-MRO §IV-B) and whether the scenario is perturbed.
    """

    workcell: str = "smp-mro"
    actions: list[ActionLog] = field(default_factory=list)
    final_poses: dict[str, ObjectPose] = field(default_factory=dict)
    base_path: list[tuple[float, float, float]] = field(default_factory=list)
    appeared: dict[str, float] = field(default_factory=dict)
    goals: dict[str, bool] = field(default_factory=dict)
    #: objects left knocked over, on top of another, or moved unpicked (`judge` fails on any)
    disturbed: list[Disturbance] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    #: every skill failure: (sim time, action, cause, detail), recovered ones included
    failures: list[tuple[float, str, str, str]] = field(default_factory=list)
    grasp: str
    perception: str
    #: what read the camera's views (``perception: camera``): oracle or learned
    detector: str = "oracle"
    order: list[str] = field(default_factory=list)
    #: the scenario has a perturbation section (the report says what this seed drew)
    perturbed: bool = False

    @property
    def executed(self) -> list[str]:
        return [a.action for a in self.actions if a.status == "SUCCESS"]

    def details_json(self) -> dict:
        cpu_rtf = self.cpu_realtime_factor
        return {
            "order": list(self.order),
            "actions": [a.to_json() for a in self.actions],
            "final_poses": {k: v.to_json() for k, v in sorted(self.final_poses.items())},
            "goals": self.goals,
            "disturbed": [d.to_json() for d in self.disturbed],
            "appeared": {k: round(v, 3) for k, v in self.appeared.items()},
            "cpu_realtime_factor": round(cpu_rtf, 2) if math.isfinite(cpu_rtf) else None,
            "warnings": list(self.warnings),
            "failures": [
                {"time": round(t, 3), "action": a, "cause": c, "detail": d}
                for t, a, c, d in self.failures
            ],
            "grasp": self.grasp,
            "perception": self.perception,
            # what read the camera (only with one: the truth cells' output is unchanged)
            **({"detector": self.detector} if self.perception == "camera" else {}),
        }

    def details_lines(self) -> list[str]:
        """The plan, the action table, the final plant poses, the goals on the plant, the
        disturbed objects, warnings, skill failures and, for a perturbed scenario, what the
        seed drew."""
        checks = f"(verified: {', '.join(self.verified)})" if self.verified else "(not verified)"
        lines = [
            f"scenario {self.scenario}: order {' -> '.join(self.order)}  {checks}",
            f"{'action':<22} {'start':>8} {'end':>8}  status",
        ]
        for a in self.actions:
            end = "-" if a.end is None else f"{a.end:8.2f}"
            lines.append(f"{a.action:<22} {a.start:8.2f} {end:>8}  {a.outcome}")
        lines.append("final object poses (plant, m / rad):")
        for uid, p in sorted(self.final_poses.items()):
            lines.append(f"  {uid:<4} x={p.x:7.3f} y={p.y:7.3f} z={p.z:6.3f} yaw={p.yaw:6.2f}")
        for goal, inside in self.goals.items():
            lines.append(f"  {goal}: {'inside' if inside else 'NOT inside'}")
        lines += [f"  disturbed: {d.reason}" for d in self.disturbed]
        lines += [f"warning: {w}" for w in self.warnings]
        for t, action, cause, detail in self.failures:
            lines.append(f"skill failure: t={t:.2f} s {action}: {cause} ({detail})")
        if self.perturbed and self.perturbation is not None:
            p = self.perturbation
            mu = "as modelled" if p["friction"] is None else f"{p['friction']:.3f}"
            lines.append(
                f"seed {self.seed}: perturbation size {p['size']:.3f} m (largest object "
                f"displacement), robot moved {p['robot_displacement']:.3f} m, friction "
                f"{mu}, grasp {self.grasp}, perception {self.perception}"
                + (f" ({self.detector} detector)" if self.perception == "camera" else "")
            )
        return lines


class SimRunner:
    """Runs a built `SmpStation` to the end of its task."""

    def __init__(self, system: SmpStation, *, realtime_rate: float = 0.0):
        """``realtime_rate``: 0 runs as fast as possible; 1.0 paces a live Meshcat view."""
        self.system = system
        self.simulator = make_simulator(system.diagram, realtime_rate=realtime_rate)
        root = self.simulator.get_mutable_context()
        self.root = root
        self.plant_context = system.plant.GetMyMutableContextFromRoot(root)
        for cid in system.welds.values():
            system.plant.SetConstraintActiveStatus(self.plant_context, cid, False)
        self.active: tuple[str, int] | None = None
        #: (time, object, variant, gap m, gap rad) each time a weld was switched on
        self.weld_log: list[tuple[float, str, int, float, float]] = []
        self.appeared: dict[str, float] = {}
        self.warnings: list[str] = []
        self._handled: set[str] = set()  # appearances done (or impossible)
        self.reach = system.scenario.demo.domain().reach  # IsRobotCloseTo's d (§V-A2)
        self.base_path: list[tuple[float, float, float]] = []
        #: object -> (x, y) where the scenario or the person last put it (`disturbances`)
        self.put: dict[str, tuple[float, float]] = {}

    # -- between-step work -------------------------------------------------------------------
    def _sync_grasp(self) -> None:
        s = self.system
        ctl_context = s.skills.GetMyContextFromRoot(self.root)
        req = s.skills.grasp_port.Eval(ctl_context)
        want = None if req.obj is None else (req.obj, req.variant)
        if want == self.active or not s.welds:  # friction grasps: nothing to switch
            return
        if self.active is not None:
            s.plant.SetConstraintActiveStatus(self.plant_context, s.welds[self.active], False)
        if want is not None:
            self.weld_log.append((self.root.get_time(), *want, *self._weld_gap(*want)))
            s.plant.SetConstraintActiveStatus(self.plant_context, s.welds[want], True)
        self.active = want

    def _weld_gap(self, obj: str, variant: int) -> tuple[float, float]:
        """How far the object is from where the weld will hold it (m, rad): the snap."""
        s = self.system
        palm = s.plant.GetBodyByName(ROBOT.palm_body, s.robot)
        X_WG = s.plant.EvalBodyPoseInWorld(self.plant_context, palm)
        X_target = X_WG.multiply(grasp_transform(s.scenario.object(obj).kind, variant))
        X_WO = s.plant.EvalBodyPoseInWorld(self.plant_context, s.bodies[obj])
        X_err = X_target.inverse().multiply(X_WO)
        angle = float(X_err.rotation().ToAngleAxis().angle())
        return float(np.linalg.norm(X_err.translation())), angle

    def _appearances(self, t: float, log: list[ActionLog]) -> None:
        s = self.system
        done = {a.action for a in log if a.status == "SUCCESS"}
        for obj in s.scenario.objects:
            if obj.appear is None or obj.id in self._handled:
                continue
            if not self._due(obj.appear, t, done):
                continue
            self._handled.add(obj.id)
            spot = self._where_to_put(obj, t)
            if spot is None:
                continue
            X = RigidTransform([spot[0], spot[1], obj.kind.half_height + 0.003])
            body = s.bodies[obj.id]
            s.plant.SetFreeBodyPose(self.plant_context, body, X)
            s.plant.SetFreeBodySpatialVelocity(self.plant_context, body, SpatialVelocity.Zero())
            self.appeared[obj.id] = t
            self.put[obj.id] = spot

    def _where_to_put(self, obj, t: float) -> tuple[float, float] | None:
        """The appearance's place, or the nearest free spot when something occupies it (with
        a warning); None (with a warning) when no free spot is left."""
        s = self.system
        p = s.scenario.place_of(obj.appear)
        bodies = [b for b in self.bodies_now() if b.id != obj.id]
        x, y, _ = self.robot_pose()
        robot = (x, y, ROBOT.footprint_radius)
        who = blocker(p.x, p.y, obj.kind, bodies, robot)
        if who is None:
            return (p.x, p.y)
        ex_context = s.executor.GetMyContextFromRoot(self.root)
        areas = {**s.areas, **s.executor.state(ex_context).extra_areas}
        spot = free_spot(
            p.x,
            p.y,
            obj.kind,
            bodies=bodies,
            areas=areas,
            workspace=s.scenario.workspace,
            robot=robot,
        )
        what = f"t={t:.2f} s: {obj.appear}: the place is occupied by {who}"
        if spot is None:
            self.warnings.append(f"{what}; no free spot near it, {obj.id} was not put down")
        else:
            d = math.hypot(spot[0] - p.x, spot[1] - p.y)
            self.warnings.append(
                f"{what}; {obj.id} was put down {d:.2f} m away at ({spot[0]:.2f}, "
                f"{spot[1]:.2f}), outside every area"
            )
        return spot

    def _due(self, appear: Appear, t: float, done: set[str]) -> bool:
        """Whether ``appear``'s WHEN has come (`tamp.world.events`: tick, time, after, reach)."""
        when = appear.when
        if isinstance(when, AtTime):
            return t >= when.seconds
        if isinstance(when, AtTick):
            return t >= when.tick * self.system.scenario.executor.bt_period - 1e-9
        if isinstance(when, AfterAction):
            return format_call(when.name, when.args) in done
        x, y, _ = self.robot_pose()  # no WHEN: when the robot first comes within reach
        p = self.system.scenario.place_of(appear)
        return math.hypot(p.x - x, p.y - y) <= self.reach

    def bodies_now(self) -> list[Body]:
        """The objects inside the workspace as the plant has them now (3-D centres)."""
        s = self.system
        out = []
        for uid, p in self.object_poses().items():
            if s.scenario.in_workspace(p.x, p.y):
                out.append(Body(uid, p.x, p.y, p.z, s.scenario.object(uid).kind))
        return out

    def object_poses(self) -> dict[str, ObjectPose]:
        s = self.system
        out = {}
        for uid, body in s.bodies.items():
            X = s.plant.EvalBodyPoseInWorld(self.plant_context, body)
            p = X.translation()
            yaw = RollPitchYaw(X.rotation()).yaw_angle()
            out[uid] = ObjectPose(float(p[0]), float(p[1]), float(p[2]), float(yaw))
        return out

    def object_tilts(self) -> dict[str, float]:
        """Each object's tilt now (rad between its own vertical axis and the world's)."""
        s = self.system
        out = {}
        for uid, body in s.bodies.items():
            R = s.plant.EvalBodyPoseInWorld(self.plant_context, body).rotation().matrix()
            out[uid] = float(math.acos(max(-1.0, min(1.0, R[2, 2]))))
        return out

    def robot_pose(self) -> tuple[float, float, float]:
        q = self.system.plant.GetPositions(self.plant_context, self.system.robot)
        return float(q[0]), float(q[1]), float(q[2])

    # -- main loop ---------------------------------------------------------------------------
    def run(
        self,
        *,
        max_sim_time: float | None = None,
        on_chunk: Callable[[float], None] | None = None,
        path_every: float = 0.1,
    ) -> SimResult:
        s = self.system
        limit = s.scenario.executor.max_sim_time if max_sim_time is None else max_sim_time
        ex_context = s.executor.GetMyContextFromRoot(self.root)
        start = self.object_poses()
        self.put = {
            o.id: (start[o.id].x, start[o.id].y) for o in s.scenario.objects if o.appear is None
        }
        self._appearances(self.root.get_time(), [])  # what is there from the start (tick 0)
        next_path = self.root.get_time()

        def between(t: float) -> bool:
            nonlocal next_path
            self._sync_grasp()
            ex = s.executor.state(ex_context)
            self._appearances(t, ex.log)
            if t >= next_path:
                self.base_path.append(self.robot_pose())
                next_path += path_every
            if on_chunk is not None:
                on_chunk(t)
            return ex.result is not None

        run = run_in_chunks(
            self.simulator,
            chunk=s.scenario.executor.controller_period,
            limit=limit,
            between=between,
        )
        ex = s.executor.state(ex_context)
        tree_reason = ""
        if ex.result is not None:
            tree_reason = getattr(s.executor.policy(ex_context), "reason", "") or ""
        poses = self.object_poses()
        why = self.goal_check(poses)
        failures = [w for w in why.values() if w is not None]
        disturbed = self.disturbance_check(poses, picked_objects(ex.log))
        status, reason = judge(
            ex.result, tree_reason, failures, limit, [d.reason for d in disturbed]
        )
        skill_failures = list(s.skills.failures(s.skills.GetMyContextFromRoot(self.root)))
        cause = run_cause(
            status,
            [c for _, _, c, _ in skill_failures],
            plant_disagrees=ex.result is Status.SUCCESS and bool(failures),
            disturbed=ex.result is Status.SUCCESS and bool(disturbed),
        )
        if run.diverged is not None:  # the plant's last state is not a result
            status, reason, cause = "FAILURE", run.diverged, "sim_diverged"
        return SimResult(
            scenario=s.scenario.name,
            status=status,
            reason=reason,
            actions=[a for a in ex.log],
            final_poses=poses,
            task_time=run.sim_time,
            sim_time=run.sim_time,
            wall_time=run.wall_time,
            cpu_time=run.cpu_time,
            base_path=list(self.base_path),
            appeared=dict(self.appeared),
            goals={k: w is None for k, w in why.items()},
            disturbed=disturbed,
            warnings=list(self.warnings),
            cause=cause,
            failures=skill_failures,
            grasp=s.scenario.grasp,
            perception=s.scenario.perception,
            detector=s.scenario.detector,
            perturbed=bool(s.scenario.perturbation.fields()),
        )

    def goal_check(self, poses: dict[str, ObjectPose] | None = None) -> dict[str, str | None]:
        """For each goal object ``O@L`` (its *final* goal area): None when it rests in L on
        the plant in 3-D (`why_not_in`), else why not."""
        s = self.system
        poses = poses or self.object_poses()
        final: dict[str, str] = {}
        for g in s.scenario.demo.goals:
            final[g.object] = g.area.name
        bodies = self._bodies(poses)
        by_id = {b.id: b for b in bodies}
        return {
            f"{uid}@{area}": why_not_in(by_id[uid], s.areas[area], bodies)
            for uid, area in final.items()
        }

    def disturbance_check(
        self, poses: dict[str, ObjectPose], picked: set[str]
    ) -> list[Disturbance]:
        """Every object present (put somewhere by the scenario or the person, or inside the
        workspace), goal or not, left disturbed (`tamp.sim.smp.placement.disturbances`);
        ``picked``: the objects the robot picked (`picked_objects`)."""
        s = self.system
        present = [
            b for b in self._bodies(poses) if b.id in self.put or s.scenario.in_workspace(b.x, b.y)
        ]
        return disturbances(present, self.put, picked)

    def _bodies(self, poses: dict[str, ObjectPose]) -> list[Body]:
        """``poses`` as `Body`s with the objects' tilts now."""
        kind = self.system.scenario.object
        tilts = self.object_tilts()
        return [Body(u, p.x, p.y, p.z, kind(u).kind, tilts[u]) for u, p in poses.items()]

    def goals_on_plant(self, poses: dict[str, ObjectPose] | None = None) -> dict[str, bool]:
        """For each goal object, whether it rests in its final goal area (`goal_check`)."""
        return {k: w is None for k, w in self.goal_check(poses).items()}
