"""The LOTS controller is tick-based on the `tamp.world.World` contract.

It starts one skill of the ``lots_arm`` domain at a time, polls it, never blocks; the only
thing it reads from the world is what the camera sees (`visible_counts`); its state copies
with `snapshot`/`restore`; every table passes the gate before a skill is started with it.
"""

from __future__ import annotations

import copy

import pytest

from tamp.lots.cell import SIDES, camera_side, lots_domain, view_state, visible_counts
from tamp.lots.controller import LotsController
from tamp.lots.person import ScriptedPerson
from tamp.lots.run import lots_world, run_task
from tamp.lots.task import Event, load_task
from tamp.world.events import Appear, Fail
from tamp.world.interface import Status
from tamp.world.outcomes import ScriptedOutcomes

from .helpers import events

PACKAGED = [
    ("example1.yaml", None),
    ("example1.yaml", "example1_interference.yaml"),
    ("model_building.yaml", "model_building_fig8.yaml"),
    ("model_building.yaml", "model_building_fig9.yaml"),
    ("tower.yaml", None),
    ("tower.yaml", "tower_interference.yaml"),
]


def summary(report):
    return (
        [a.to_json() for a in report.actions],
        report.counts(),
        [(n, phase, e.describe()) for n, phase, e in report.person.log],
        report.replans,
        report.satisfied,
    )


def setup(task_name, ev_name, **world_kw):
    task = load_task(task_name)
    evs = events(ev_name, task) if ev_name else []
    c = LotsController(task)
    c.max_actions = c.default_limit(len(evs) + 4)
    world = lots_world(task, **world_kw)
    person = ScriptedPerson(evs)

    def step():
        world.step()
        person.act(world)

    return c, world, person, step


@pytest.mark.parametrize("task_name, ev_name", PACKAGED)
def test_the_run_does_not_depend_on_how_long_skills_take(task_name, ev_name):
    task = load_task(task_name)
    evs = events(ev_name, task) if ev_name else []
    runs = [summary(run_task(task, evs, skill_ticks=k)) for k in (0, 1, 3)]
    assert runs[0][-1] is True
    assert runs[0] == runs[1] == runs[2]
    slow = run_task(task, evs, skill_ticks={"Pick": 4, "LookAt": 2, "Place": 0})
    assert summary(slow) == runs[0]


@pytest.mark.parametrize("skill_ticks", [0, 2])
def test_one_skill_at_a_time_and_each_tick_starts_or_polls_at_most_one(skill_ticks):
    c, world, _, step = setup("tower.yaml", "tower_interference.yaml", skill_ticks=skill_ticks)
    ticks = 0
    while True:
        step()
        before = len(world.history)
        status = c.tick(world)
        ticks += 1
        kinds = [e.kind for e in world.history[before:] if e.kind in ("start", "success")]
        assert kinds.count("start") <= 1 and kinds.count("success") <= 1
        if kinds == ["success"] or kinds == ["start", "success"]:
            assert not world.busy  # a finished skill; the next one starts on the next tick
        if status is not Status.RUNNING:
            break
    assert status is Status.SUCCESS and world.violations == 0
    names = {a.name for a in world.executed()}
    assert names <= set(lots_domain().templates) and names == {"LookAt", "Pick", "Place"}
    assert c.skills == len(world.executed()) and ticks == c.ticks
    assert ticks >= c.skills * (1 + skill_ticks)  # skills took their ticks: nothing blocked


class CameraOnly:
    """A world that answers `observe` with what its camera sees and nothing else (as the
    Drake workcell does), wrapping the symbolic one that really executes the skills."""

    def __init__(self, world, *, noise: bool = False):
        self.world = world
        self.noise = noise
        self.observed = 0

    def observe(self):
        self.observed += 1
        state = self.world.observe()
        side = camera_side(state)
        if side is None:  # the camera over neither workspace: it sees an empty table
            return view_state("A", {}).with_robot_at(state.robot)
        seen = view_state(side, visible_counts(state, side))
        if self.noise:  # objects the camera cannot see must not matter
            other = SIDES[1 - SIDES.index(side)]
            for k in range(5):
                seen = seen.with_object_at(f"ghost{k}", view_state(other, {}).robot, "hammer")
        return seen

    def start(self, action):
        return self.world.start(action)

    def poll(self, handle):
        return self.world.poll(handle)

    def cancel(self, handle):
        self.world.cancel(handle)


@pytest.mark.parametrize("task_name, ev_name", PACKAGED)
@pytest.mark.parametrize("noise", [False, True])
def test_the_controller_reads_only_what_the_camera_sees(task_name, ev_name, noise):
    c_ref, world_ref, _, step_ref = setup(task_name, ev_name)
    assert c_ref.run(world_ref, step=step_ref) is Status.SUCCESS
    c, world, _, step = setup(task_name, ev_name)
    camera = CameraOnly(world, noise=noise)
    assert c.run(camera, step=step) is Status.SUCCESS
    assert [a.to_json() for a in c.actions] == [a.to_json() for a in c_ref.actions]
    assert [str(a) for a in world.executed()] == [str(a) for a in world_ref.executed()]
    # it observes once per view, when a LookAt ends, and at no other time
    assert camera.observed == sum(1 for a in world.executed() if a.name == "LookAt")


def test_snapshot_and_restore_continue_the_same_run():
    c, world, person, step = setup("tower.yaml", "tower_interference.yaml")
    for _ in range(25):  # part-way: an action or two done, a skill running
        step()
        c.tick(world)
    assert c.actions and c.result is None
    snap = c.snapshot()
    w2, p2 = copy.deepcopy(world), copy.deepcopy(person)
    assert c.run(world, step=step) is Status.SUCCESS
    assert snap.result is None and len(snap.actions) < len(c.actions)  # independent copy
    other = LotsController(load_task("tower.yaml"))
    other.restore(snap)

    def step2():
        w2.step()
        p2.act(w2)

    assert other.run(w2, step=step2) is Status.SUCCESS
    assert [a.to_json() for a in other.actions] == [a.to_json() for a in c.actions]
    assert [str(a) for a in w2.executed()] == [str(a) for a in world.executed()]
    assert other.aut is c.aut and other.tree is not c.tree  # shared automaton, own tree


def test_every_table_is_gated_before_a_skill_is_started_with_it():
    task = load_task("tower.yaml")
    peak_early = [Event(after=1, kind="add", cls="peak", side="B")]
    world = lots_world(task)
    seen = []

    def check(c):
        seen.append((c.build.label, len(world.history), world.busy, c.pending))

    c = LotsController(task, check=check)
    person = ScriptedPerson(peak_early)

    def step():
        world.step()
        person.act(world)

    assert c.run(world, step=step) is Status.SUCCESS
    (first, n0, busy0, _), (label, _, busy1, pending) = seen
    assert first == "initial" and n0 == 0 and not busy0  # before anything happened
    assert label.startswith("replan 1") and not busy1 and pending is None


def test_a_failed_skill_is_tried_again_and_the_round_completes():
    task = load_task("model_building.yaml")
    c = LotsController(task)
    world = lots_world(task)
    world.outcomes = ScriptedOutcomes([Fail("Pick", ("scissors", "A"), 2), Fail("Place", None)])
    assert c.run(world, step=world.step) is Status.SUCCESS
    failed = [e.subject for e in world.history if e.kind == "failure"]
    assert failed == ["Place(B)", "Pick(scissors, A)", "Pick(scissors, A)"]  # saw placed first
    assert [a.key() for a in c.actions] == [("move", "p1"), ("move", "p2"), ("move", "p3")]


def test_a_skill_that_keeps_failing_stops_the_controller_with_the_reason():
    task = load_task("tower.yaml")
    c = LotsController(task, max_retries=2)
    world = lots_world(task)
    world.outcomes = ScriptedOutcomes([Fail("Place", ("B",), 10)])
    assert c.run(world, step=world.step) is Status.FAILURE
    assert c.reason == "Place(B) failed 3 times in a row"
    assert c.tick(world) is Status.FAILURE  # sticky


def test_a_pick_that_keeps_failing_stops_the_controller_although_the_looks_between_succeed():
    """The Drake cell's Fig. 10 run: after the peak fell beside it, no grasp was found on the
    body, Pick after Pick. Each retry starts with a look that succeeds; counted as progress,
    it reset the row and the robot retried until the action bound (752 failed picks here,
    94 waits "observations of W^A and W^B disagree"), in the cell past any time limit."""
    task = load_task("tower.yaml")
    c = LotsController(task, max_retries=2)
    world = lots_world(task)
    world.outcomes = ScriptedOutcomes([Fail("Pick", ("body", "A"), 1000)])
    assert c.run(world, step=world.step) is Status.FAILURE
    assert c.reason == "Pick(body, A) failed 3 times in a row"
    assert [e.subject for e in world.history if e.kind == "failure"] == ["Pick(body, A)"] * 3
    assert [a.key() for a in c.actions] == [("move", "p1")]  # no waits, no other action


def test_halt_cancels_the_running_skill():
    task = load_task("tower.yaml")
    c, world = LotsController(task), lots_world(task, skill_ticks=5)
    world.step()
    assert c.tick(world) is Status.RUNNING and str(c.running) == "LookAt(A)"
    c.halt(world)
    assert c.running is None and not world.busy
    assert world.history[-1].kind == "cancel"
    assert c.run(world, step=world.step) is Status.SUCCESS  # starts again with a look


def test_a_place_that_lost_its_object_continues_from_what_the_camera_sees():
    """The saw slips out on the way and lands in W^B (the Drake cell's "dropped ... while
    carrying it"): the camera sees the gripper empty, so the controller does not place again
    with an empty hand; it looks and continues from what it sees (the saw is in W^B)."""
    task = load_task("model_building.yaml")
    c = LotsController(task)
    world = lots_world(task)
    dropped: list[str] = []

    def step():
        world.step()
        running = [e for e in world.history if e.kind == "start"][-1:]
        if not dropped and running and running[0].subject == "Place(B)":
            dropped.append(world.state.held)
            world.happen(Appear(world.state.held, "B"))  # it falls into W^B on the way

    assert c.run(world, step=step) is Status.SUCCESS
    assert dropped == ["saw_1"]
    starts = [e.subject for e in world.history if e.kind == "start"]
    i = starts.index("Place(B)")
    assert starts[i + 1] == "LookAt(A)"  # not Place(B) again with an empty hand
    assert c.belief.held is None
    assert [a.key() for a in c.actions] == [("move", "p2"), ("move", "p3")]
    assert world.state.kinds_in(world.state.area("B")) == {"hammer": 1, "saw": 1, "scissors": 1}
