"""Connect your own robot: a `tamp.world.World` adapter over an action server.

A real robot is usually driven through an *action interface* (ROS 2 actions, ROS 1
actionlib, a vendor SDK): a client sends a goal, the server accepts it after some latency,
streams feedback while it runs and ends it with a result (succeeded, aborted, canceled); the
client may cancel a goal at any time, and the robot's state is published separately
(odometry, an object tracker). `tamp`'s executors need only four methods of the world they
act on (`tamp.world.interface.World`): ``observe`` (the symbolic state now), ``start`` (begin
one skill, return a handle), ``poll`` (RUNNING, then SUCCESS or FAILURE) and ``cancel``.

This file has three parts:

1. `FakeActionServer`: a small in-process action server standing in for the robot. It runs
   one goal at a time on its own thread (navigate, pick, place), with acceptance latency,
   travel at a finite speed, feedback, cancellation, and a grasp that slips the first time
   (a goal aborted by the robot). A scripted person puts an object in the robot's way when
   it first comes near a place, as in SMP-MRO Case 3 (Nakamura & Sekiyama, IEEE Access,
   §V-D2).
2. `ActionServerWorld`: the adapter. It turns each symbolic action into a goal, the goal's
   status into a `Status`, and the published state into a `WorldState`. This is the part
   you write for your robot.
3. `run`: what ``tamp plan DEMO --execute`` does, through the Python API, against the
   adapter: plan the goal order (SMP-MRO §IV-B), pass the verification gate, then tick a
   behavior tree grown at run time (SMP-MRO §IV-C, `tamp.bt.PaBtExecutor`) at a fixed period
   until the goals hold.

Run it: ``python examples/robot_adapter.py [DEMO.yaml]`` (default ``case3.yaml``).
"""

from __future__ import annotations

import argparse
import itertools
import math
import threading
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from enum import Enum

from tamp.world import Action, Area, ObjectState, Pose, WorldState
from tamp.world.interface import Status

# --- 1. a fake action server (stands in for the robot) --------------------------------------


class GoalStatus(Enum):
    """A goal's life, as ROS 2 actions name it."""

    PENDING = "pending"  # sent, not accepted yet (latency)
    ACTIVE = "active"  # accepted and running; feedback arrives
    SUCCEEDED = "succeeded"
    ABORTED = "aborted"  # the robot gave up (a slipped grasp, an unreachable place)
    CANCELED = "canceled"  # the client asked it to stop

    @property
    def done(self) -> bool:
        return self in (GoalStatus.SUCCEEDED, GoalStatus.ABORTED, GoalStatus.CANCELED)


@dataclass
class Goal:
    """One goal: what to do, its status, its latest feedback and its result message."""

    id: int
    kind: str  # "navigate" | "pick" | "place"
    target: tuple[float, float] | None = None
    obj: str | None = None
    status: GoalStatus = GoalStatus.PENDING
    progress: float = 0.0  # feedback: the fraction done
    feedback_count: int = 0
    result: str = ""
    cancel_requested: bool = False


@dataclass
class RobotState:
    """What the robot publishes: base position, the held object, tracked objects."""

    xy: tuple[float, float]
    held: str | None = None
    objects: dict[str, tuple[float, float]] = field(default_factory=dict)


class FakeActionServer:
    """An in-process action server for a mobile manipulator (one goal at a time).

    ``latency``: seconds before a goal is accepted; ``speed``: base speed [m/s];
    ``manipulation_time``: seconds per pick or place; ``reach``: how far the arm reaches
    from the base [m]; ``slips``: objects whose first pick aborts (the grasp slips);
    ``person``: (object, x, y) put there by a person when the robot first comes within
    ``reach`` of (x, y). Goals run on a worker thread; every method is thread-safe.
    """

    def __init__(
        self,
        state: RobotState,
        *,
        latency: float = 0.01,
        speed: float = 25.0,
        manipulation_time: float = 0.02,
        reach: float = 0.9,
        slips: Iterable[str] = (),
        person: Iterable[tuple[str, float, float]] = (),
        step: float = 0.005,
    ):
        self._state = state
        self.latency, self.speed, self.reach = latency, speed, reach
        self.manipulation_time, self._step = manipulation_time, step
        self._slips = set(slips)
        self._person = list(person)
        self._goals: dict[int, Goal] = {}
        self._ids = itertools.count(1)
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._queue: list[int] = []
        self._stop = False
        self.log: list[str] = []
        self._thread = threading.Thread(target=self._serve, name="fake-action-server", daemon=True)
        self._thread.start()

    # the client's side ---------------------------------------------------------------------

    def send_goal(self, kind: str, *, target=None, obj=None) -> int:
        """Queue a goal; returns its id at once (it is accepted after ``latency``)."""
        with self._wake:
            goal = Goal(next(self._ids), kind, target=target, obj=obj)
            self._goals[goal.id] = goal
            self._queue.append(goal.id)
            self._wake.notify()
            return goal.id

    def goal(self, goal_id: int) -> Goal:
        """A copy of the goal as the server sees it now (status, feedback, result)."""
        with self._lock:
            g = self._goals[goal_id]
            return Goal(**vars(g))

    def cancel_goal(self, goal_id: int) -> None:
        """Ask the server to stop the goal (it ends CANCELED at its next step)."""
        with self._lock:
            self._goals[goal_id].cancel_requested = True

    def snapshot(self) -> RobotState:
        """The robot's published state (odometry, the gripper, the object tracker)."""
        with self._lock:
            s = self._state
            return RobotState(s.xy, s.held, dict(s.objects))

    def shutdown(self) -> None:
        with self._wake:
            self._stop = True
            self._wake.notify()
        self._thread.join(timeout=5)

    # the robot's side ----------------------------------------------------------------------

    def _serve(self) -> None:
        while True:
            with self._wake:
                while not self._queue and not self._stop:
                    self._wake.wait()
                if self._stop:
                    return
                goal_id = self._queue.pop(0)
            time.sleep(self.latency)
            with self._lock:
                goal = self._goals[goal_id]
                if goal.cancel_requested:
                    self._end(goal, GoalStatus.CANCELED, "canceled before it started")
                    continue
                goal.status = GoalStatus.ACTIVE
            {"navigate": self._navigate, "pick": self._pick, "place": self._place}[goal.kind](goal)

    def _end(self, goal: Goal, status: GoalStatus, result: str) -> None:
        goal.status, goal.result = status, result
        what = goal.obj or "({:.2f}, {:.2f})".format(*(goal.target or (0.0, 0.0)))
        self.log.append(f"goal {goal.id} {goal.kind} {what}: {status.value} ({result})")

    def _wait(self, goal: Goal, seconds: float) -> bool:
        """Run for ``seconds`` publishing feedback; False when canceled meanwhile."""
        steps = max(1, math.ceil(seconds / self._step))
        for k in range(steps):
            time.sleep(self._step)
            with self._lock:
                if goal.cancel_requested:
                    self._end(goal, GoalStatus.CANCELED, "canceled")
                    return False
                goal.progress = (k + 1) / steps
                goal.feedback_count += 1
        return True

    def _navigate(self, goal: Goal) -> None:
        assert goal.target is not None
        with self._lock:
            (x0, y0), (x1, y1) = self._state.xy, goal.target
        steps = max(1, math.ceil(math.dist((x0, y0), (x1, y1)) / self.speed / self._step))
        for k in range(steps):
            time.sleep(self._step)
            with self._lock:
                if goal.cancel_requested:  # stop where the base is: the state it reached
                    self._end(goal, GoalStatus.CANCELED, "canceled")
                    return
                f = (k + 1) / steps
                self._move_base((x0 + f * (x1 - x0), y0 + f * (y1 - y0)))
                goal.progress, goal.feedback_count = f, goal.feedback_count + 1
        with self._lock:
            self._end(goal, GoalStatus.SUCCEEDED, "arrived")

    def _move_base(self, xy: tuple[float, float]) -> None:
        s = self._state
        s.xy = xy
        if s.held is not None:
            s.objects[s.held] = xy
        for entry in list(self._person):  # the person acts when the robot comes near
            obj, px, py = entry
            if math.dist(xy, (px, py)) <= self.reach:
                s.objects[obj] = (px, py)
                self._person.remove(entry)
                self.log.append(f"a person puts {obj} at ({px:g}, {py:g})")

    def _pick(self, goal: Goal) -> None:
        assert goal.obj is not None
        if not self._wait(goal, self.manipulation_time):
            return
        with self._lock:
            s = self._state
            where = s.objects.get(goal.obj)
            if s.held is not None or where is None or math.dist(where, s.xy) > self.reach:
                self._end(goal, GoalStatus.ABORTED, "nothing graspable within reach")
            elif goal.obj in self._slips:
                self._slips.discard(goal.obj)
                self._end(goal, GoalStatus.ABORTED, "the grasp slipped")
            else:
                s.held = goal.obj
                s.objects[goal.obj] = s.xy
                self._end(goal, GoalStatus.SUCCEEDED, "grasped")

    def _place(self, goal: Goal) -> None:
        assert goal.obj is not None and goal.target is not None
        if not self._wait(goal, self.manipulation_time):
            return
        with self._lock:
            s = self._state
            if s.held != goal.obj or math.dist(goal.target, s.xy) > self.reach:
                self._end(goal, GoalStatus.ABORTED, "not holding it, or the place is out of reach")
            else:
                s.objects[goal.obj] = goal.target
                s.held = None
                self._end(goal, GoalStatus.SUCCEEDED, "placed")


# --- 2. the adapter: the four methods of tamp.world.World ------------------------------------


class ActionServerWorld:
    """`tamp.world.World` over an action server.

    ``areas``: the symbolic places of the task (from the demonstration); areas the executor
    finds at run time (free areas for moving an obstacle away) arrive through `add_area`.
    ``stand_off``: how far short of a target the base stops [m] (within the predicates'
    reach, 0.9 m, so ``IsRobotCloseTo`` holds on arrival).
    """

    def __init__(self, server: FakeActionServer, areas: Mapping[str, Area], stand_off: float = 0.5):
        self.server = server
        self.areas = dict(areas)
        self.stand_off = stand_off
        self._running: int | None = None

    def observe(self) -> WorldState:
        """The symbolic state now, from the robot's published state."""
        s = self.server.snapshot()
        objects = {
            uid: ObjectState(uid, Pose.at(x, y)) for uid, (x, y) in sorted(s.objects.items())
        }
        return WorldState(Pose.at(*s.xy), s.held, objects, self.areas)

    def start(self, action: Action) -> int:
        """Send the goal that carries out ``action``; the goal id is the handle."""
        if self._running is not None and not self.server.goal(self._running).status.done:
            raise RuntimeError(f"start({action}) while goal {self._running} runs")
        state = self.observe()
        if action.name == "MoveTo":
            goal = self.server.send_goal("navigate", target=self._stand_off(state, action.args[0]))
        elif action.name == "Pick":
            goal = self.server.send_goal("pick", obj=action.args[0])
        elif action.name == "Place":
            p = state.position_of(action.args[1])
            goal = self.server.send_goal("place", obj=action.args[0], target=(p.x, p.y))
        else:
            raise ValueError(f"this robot has no skill for {action}")
        self._running = goal
        return goal

    def poll(self, handle: int) -> Status:
        """RUNNING while the goal is pending or active, then SUCCESS or FAILURE."""
        status = self.server.goal(handle).status
        if not status.done:
            return Status.RUNNING
        return Status.SUCCESS if status is GoalStatus.SUCCEEDED else Status.FAILURE

    def cancel(self, handle: int, timeout: float = 5.0) -> None:
        """Cancel the goal and wait until the server ends it: the protocol's ``cancel``
        stops the skill now (a reactive tree halts a skill whose condition came true and
        starts the next one in the same tick). The world keeps the state the robot reached."""
        self.server.cancel_goal(handle)
        deadline = time.monotonic() + timeout
        while not self.server.goal(handle).status.done:
            if time.monotonic() > deadline:
                raise RuntimeError(f"goal {handle} did not stop within {timeout} s")
            time.sleep(0.001)

    def add_area(self, area: Area) -> None:
        """An area the executor found at run time (e.g. a free place for an obstacle)."""
        self.areas[area.name] = area

    def _stand_off(self, state: WorldState, ref: str) -> tuple[float, float]:
        p, here = state.position_of(ref), state.robot.pos
        d = here.planar_distance(p)
        if d <= self.stand_off:
            return (here.x, here.y)
        f = (d - self.stand_off) / d
        return (here.x + f * (p.x - here.x), here.y + f * (p.y - here.y))


# --- 3. tamp plan --execute, through the API, against the adapter ----------------------------


@dataclass
class AdapterRun:
    """What `run` reports: the executor's outcome, its attempts and the server's goal log.

    ``attempts``: (action, how it ended for the tree). The robot's state is published while
    goals run, so the tree often sees a skill's effect (the object in the hand, the base
    within reach) before the goal's result arrives; a reactive tree then halts the skill
    because its condition holds, and the attempt ends CANCELLED although the goal itself
    succeeded (``goals`` is the server's own account).
    """

    status: Status
    reason: str
    attempts: list[tuple[str, str]]
    growth: list[str]
    goals: list[str]
    final: WorldState
    ticks: int


def server_for(demo, *, slips: Iterable[str] = (), **options) -> FakeActionServer:
    """A fake robot standing where the demonstration starts, the demonstration's objects
    where they are, and its scripted appearances (``appear:``) done by a person."""
    from tamp.world.events import Appear

    state = demo.initial_world()
    person = []
    for a in demo.appear:
        assert isinstance(a, Appear)
        p = state.area(a.place).pos if isinstance(a.place, str) else a.place
        person.append((a.obj, p.x, p.y))
    robot = RobotState(
        (state.robot.pos.x, state.robot.pos.y),
        objects={uid: (o.pos.x, o.pos.y) for uid, o in state.objects.items()},
    )
    return FakeActionServer(robot, slips=slips, person=person, **options)


def run(
    demo_name: str = "case3.yaml",
    *,
    slips: Iterable[str] = ("O0",),
    period: float = 0.005,
    max_ticks: int = 20_000,
    verify: bool = True,
) -> AdapterRun:
    """Plan, verify and execute ``demo_name`` on the fake robot (what ``tamp plan DEMO
    --execute`` does on the symbolic world). ``period``: the BT tick period [s]."""
    from tamp.bt import PaBtExecutor
    from tamp.demo import load_demonstration
    from tamp.rg import plan
    from tamp.scenarios import resolve

    demo = load_demonstration(resolve(demo_name))
    result = plan(demo)  # SMP-MRO §IV-B: the cheapest goal order
    if verify:  # the gate tamp plan runs: the order, then every execution of its tree
        from tamp.verification.bt import executor_for
        from tamp.verification.gate import gate_order, gate_tree

        gate_order(result)
        gate_tree(executor_for(demo, list(result.order)), demo.initial_world(), events=demo.appear)
    server = server_for(demo, slips=slips)
    world = ActionServerWorld(server, demo.initial_world().areas)
    executor = PaBtExecutor(result.c_goal, free_areas=[a.name for a in demo.free_areas])
    try:
        status = executor.run(world, max_ticks=max_ticks, step=lambda: time.sleep(period))
    finally:
        server.shutdown()
    return AdapterRun(
        status=status,
        reason=executor.reason,
        attempts=[(str(r.action), str(r.status)) for r in executor.attempts],
        growth=[str(e) for e in executor.log],
        goals=list(server.log),
        final=world.observe(),
        ticks=executor.stats.ticks,
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("demo", nargs="?", default="case3.yaml", help="demonstration file")
    parser.add_argument(
        "--slip", action="append", default=None, help="object whose first grasp slips"
    )
    args = parser.parse_args(argv)
    report = run(args.demo, slips=args.slip if args.slip is not None else ("O0",))
    print(f"execution: {report.status} after {report.ticks} ticks")
    for line in report.goals:
        print(f"  {line}")
    print("tree growth:")
    for line in report.growth:
        print(f"  {line}")
    print("final world:")
    for uid, o in report.final.objects.items():
        print(f"  {uid}: ({o.pos.x:.2f}, {o.pos.y:.2f})")
    return 0 if report.status is Status.SUCCESS else 1


if __name__ == "__main__":
    raise SystemExit(main())
