"""The refinement loop's decisions (Figueroa Heredia et al. 2018 §3), without Drake.

The loop is given a measuring function; here it is a timeline model (`Model`): a behavior
starts when the events it must follow have fired (`tamp.refine.order.start_predecessors`)
and lasts its motion's nominal time, so parallelizing, speeding up the base and raising
the rate shorten the measured task exactly as the steps intend. The model can also report
collisions, miss the goal, leave events unfired or searches unfinished, so every branch of
the loop is exercised: a parallelization kept or reverted, a speed change undone, a rate
backed off, the original missing its goal, the gate refusing a parallelization or a phase.
test_simulation and the CLI test run the loop on the Drake workcell.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import pytest

from tamp.errors import InfeasibleError
from tamp.refine import refinement
from tamp.refine.architecture import default_architecture
from tamp.refine.measure import Goal, Outcome, Run
from tamp.refine.order import direct_predecessors
from tamp.refine.program import Program, event_id
from tamp.refine.steps import RateSearch
from tamp.refine.timeline import BehaviorRecord, Timeline
from tamp.verification.gate import gate_program
from tamp.verification.refine import check_run
from tamp.verification.verdict import VerificationError
from tests.refine.helpers import task

ARCH = default_architecture()
OPEN = Goal("folding_chair.hinge", 0.35, "the chair is open")


def rate_of(program: Program, robot: str = "R1") -> float:
    return program.rate(program.robot(robot).behaviors[-1])


def timeline(program: Program, unfired: frozenset[str] = frozenset()) -> Timeline:
    """Start and end of every behavior when each lasts its nominal time and starts once its
    start predecessors have fired; events in ``unfired`` (and what follows them) never fire."""
    preds = direct_predecessors(program)
    end: dict[str, float | None] = {}
    start: dict[str, float | None] = {}
    pending = list(program.events())
    while pending:
        for eid in list(pending):
            before = preds[eid]
            if not before <= set(end):
                continue
            pending.remove(eid)
            robot, name = eid.split(".")
            b = program.robot(robot).behavior(name)
            gate = [e for e in before if e != b.event.after]  # what it starts after
            if any(end[e] is None for e in gate):
                start[eid] = end[eid] = None
                continue
            s = max((end[e] for e in gate), default=0.0)
            t = s + b.motion.nominal_time
            if b.event.after is not None:
                other = end[b.event.after]
                t = None if other is None else max(t, other)
            start[eid] = s
            end[eid] = None if eid in unfired else t
    records = []
    for r in program.robots:
        for i, b in enumerate(r.behaviors):
            eid = event_id(r.name, b.name)
            records.append(
                BehaviorRecord(r.name, b.name, b.section, start[eid], end[eid], r.gating(i))
            )
    return Timeline(tuple(records))


@dataclass
class Model:
    """A measuring function (`tamp.refine.measure.Measure`) over `timeline`.

        ``collide``: collisions (robot body, other) -> time, reported by runs of programs with a
        parallel group (``always``: by every run); ``unfired``: events that never fire in the
        n-th run that is not a tuning run (without reverts: 0 original, 1 parallelized, 2
        speed-adjusted, 3 rate-refined); ``misses``: the goal (the chair's hinge >= 0.35 rad)
        is missed by the runs of programs it says True for; ``found``: each robot's rate found
        by the tuning run for each of its trigger sensors, or (``ROBOT.SENSOR``) for one sensor
    (None: the search never ends). ``calls`` records (program, options)
        of every call.
    """

    collide: dict[tuple[str, str], float] = field(default_factory=dict)
    always: bool = False
    unfired: dict[int, frozenset[str]] = field(default_factory=dict)
    misses: Callable[[Program], bool] = lambda program: False
    touches: dict[str, tuple[float, str]] = field(default_factory=dict)
    found: dict[str, float | None] = field(default_factory=lambda: {"R1": 23.0, "R2": 23.0})
    calls: list[tuple[Program, dict]] = field(default_factory=list)

    def __call__(self, program, architecture, *, tune=False, max_sim_time=None, record=None):
        assert architecture is ARCH
        self.calls.append((program, {"tune": tune, "record": record}))
        phase = -1 if tune else sum(1 for _, o in self.calls if not o["tune"]) - 1
        run = Run(program, timeline(program, self.unfired.get(phase, frozenset())))
        run.sim_time = 200.0
        hinge = 0.2 if self.misses(program) else 0.48
        run.outcome = Outcome({"folding_chair.hinge": hinge}, (OPEN,))
        run.touches = dict(self.touches)
        parallel = any(b.parallel_with for _, _, b in program.behaviors())
        if self.always or parallel:
            run.collisions = dict(self.collide)
        if tune:  # one search per robot and trigger sensor, as the supervisor's
            run.searches = {
                f"{r.name}.{b.event.sensor}": RateSearch(
                    10.0,
                    3.0,
                    0.03,
                    200.0,
                    found=self.found.get(f"{r.name}.{b.event.sensor}", self.found[r.name]),
                )
                for r in program.robots
                for b in r.behaviors
                if b.event.sensor
            }
        return run


@dataclass
class Gate:
    """A gate that records its subjects and refuses the phase named ``refuse`` (the real
    gate on a property no execution of a parallelized task 4 satisfies)."""

    refuse: str | None = None
    subjects: list[str] = field(default_factory=list)

    def __call__(self, program, *, subject):
        self.subjects.append(subject)
        if self.refuse and subject.startswith(self.refuse):
            gate_program(replace(program, ordering="G(R1.approach -> R1.lower_arm)"))


def refine(program: Program, measure: Model, gate=gate_program, **kw):
    """The loop on the model; Fig. 5 searched online in a tuning run of the model (whose
    ``found`` rates exercise every branch) unless ``tune_online=False``."""
    kw.setdefault("tune_online", True)
    return refinement.refine(program, ARCH, measure, gate=gate, check_run=check_run, **kw)


def test_the_four_phases_shorten_the_task_as_each_step_intends():
    """Task 4 in the model: R1 lowers its lift (64.3 s) then approaches (66.7 s); Step 2 runs
    them together, Fig. 6(c) speeds the approach up to end with the lift, Step 3 applies the
    found rate (23 Hz) to every behavior and scales the bases' speeds by 2.3 (the arm and
    gripper keep theirs, as the paper's Step 3 says)."""
    model = Model()
    out = refine(task(4), model)
    assert [p.name for p in out.phases] == list(refinement.PHASES)
    assert [o["tune"] for _, o in model.calls] == [False, False, False, True, False]
    times = [p.task_time for p in out.phases]
    # R2 grips at 58.57 s; R1 pulls out (139.5 s) after its approach (130.95 s; 66.67 s
    # when parallel; 64.29 s when sped up) and R2 releases (37.5 s) after it. At 23 Hz only
    # the bases are faster: R1's approach keeps its speed (it ends with the lowering, which
    # the rate does not speed up): 64.29 s, the pull-out 139.5 / 2.3 s, the release 37.5 s
    assert times == pytest.approx([307.987, 243.702, 241.321, 162.453], abs=1e-3)
    # parallelization kept: the measured parallelized run was fine
    assert [p.describe() for p in out.parallelized] == [
        "R1: lower_arm runs in parallel with approach"
    ]
    # across the robots: R1's pull-out waited for R2's grip (66.1 s) though its own
    # approach ended later (126.7 s): a slack wait, but the task's property refuses it
    assert out.reverted == [] and out.relaxed == []
    ((refused, report),) = out.refused
    assert refused.describe() == "R1: pull_out no longer waits for R2.grip"
    assert "verification failed" in report
    approach = out.phases[1].program.robot("R1").behavior("approach")
    assert approach.parallel_with == "lower_arm"
    # speed phase: the approach's base speed grew by 66.7 / 64.3
    (change,) = out.speed_changes
    assert change.event == "R1.approach" and change.partner == "lower_arm"
    assert change.new == pytest.approx(0.7 / (0.45 / 7.0e-3))  # 0.7 m in the lift's 64.3 s
    adjusted = out.phases[2].program.robot("R1").behavior("approach")
    assert adjusted.motion.speed == pytest.approx(change.new)
    # rate phase: each behavior at its trigger sensor's found rate, base speeds scaled
    assert out.rate_hz == 23.0 and out.rates_found == {
        "R1.imu": 23.0,
        "R1.odometry": 23.0,
        "R2.odometry": 23.0,
        "R2.force": 23.0,
    }
    assert out.behavior_rates == {e: 23.0 for e in task(4).events()}
    assert model.calls[3][0] == out.phases[2].program  # the tuning run is of the adjusted one
    for r2, r3 in zip(out.phases[2].program.robots, out.program.robots, strict=True):
        for b2, b3 in zip(r2.behaviors, r3.behaviors, strict=True):
            assert b3.rate_hz == 23.0
            tied = b2.name in ("lower_arm", "approach") and r2.name == "R1"
            factor = 2.3 if b2.section == "base" and not tied else 1.0
            assert b3.motion.speed == pytest.approx(b2.motion.speed * factor)
    # every measured order respects the precedences, so it satisfies the ordering property
    assert [p.run_holds for p in out.phases] == [True] * 4
    assert out.verified and out.reduction == pytest.approx(1 - times[3] / times[0])
    assert out.goal_met and out.failure is None
    doc = out.to_json()
    assert doc["rate_hz"] == 23.0 and doc["category"] == "II" and doc["verified"] is True
    assert [p["name"] for p in doc["phases"]] == list(refinement.PHASES)
    assert [p["kept"] for p in doc["phases"]] == [
        [],
        ["R1: lower_arm runs in parallel with approach"],
        [change.describe()],
        ["23 Hz per behavior (7 behaviors), base speed scaled"],
    ]
    assert [(a["phase"], a["accepted"], a["goal_met"]) for a in doc["attempts"]] == [
        ("original", True, True),
        ("parallelized", True, True),
        ("speed-adjusted", True, True),
        ("rate-refined", True, True),
    ]
    assert doc["sim_time"] == 5 * 200.0 and doc["goal_met"] is True


def test_scaling_every_section_is_the_option_beside_the_papers_step_3():
    out = refine(task(4), Model(), scale="all")
    assert out.phases[3].task_time == pytest.approx(241.321 / 2.3, abs=1e-3)
    for r2, r3 in zip(out.phases[2].program.robots, out.program.robots, strict=True):
        for b2, b3 in zip(r2.behaviors, r3.behaviors, strict=True):
            assert b3.motion.speed == pytest.approx(b2.motion.speed * 2.3)
    assert out.to_json()["scale"] == "all"


def test_each_rate_run_is_recorded_and_each_phase_is_gated(tmp_path):
    model, gate = Model(), Gate()
    refine(task(4), model, gate=gate, record=tmp_path / "r.html")
    assert [o["record"] for _, o in model.calls] == [None] * 4 + [tmp_path / "r.html"]
    assert gate.subjects == [
        "original program task4",
        "parallelized program task4 (R1: lower_arm runs in parallel with approach)",
        "parallelized program task4 (R1: pull_out no longer waits for R2.grip)",
        "parallelized program task4",
        "speed-adjusted program task4",
        "rate-refined program task4",
    ]


def test_without_a_gate_nothing_is_gated_and_the_result_says_so():
    out = refine(task(4), Model(), gate=None)
    assert out.verified is False and out.to_json()["verified"] is False


def test_a_colliding_parallelization_is_reverted_and_the_original_run_stands():
    """The harmful parallelization (its run has a collision the original did not) is
    reverted; with nothing left the parallelized phase is the original program and run, so
    nothing is run again for it and there is no group left to balance."""
    model = Model(collide={("R1.arm_link", "folding_chair.frame_b"): 12.0})
    out = refine(task(4), model)
    assert out.parallelized == []
    ((bad, why, collisions),) = out.reverted
    assert bad.absorbed == "lower_arm" and bad.host == "approach"
    assert why == "new collision R1.arm_link with folding_chair.frame_b at 12.0 s"
    assert collisions == [("R1.arm_link", "folding_chair.frame_b", 12.0)]  # with its time
    assert out.phases[1].program == task(4) and out.phases[1].run is out.phases[0].run
    # original, parallelized (not accepted), tuning, rate-refined
    assert [o["tune"] for _, o in model.calls] == [False, False, True, False]
    assert out.speed_changes == []  # no group left to balance
    attempt = out.to_json()["attempts"][1]
    assert attempt["accepted"] is False and attempt["new_collisions"] == [
        ["R1.arm_link", "folding_chair.frame_b", 12.0]
    ]
    assert out.goal_met and out.rate_hz == 23.0


def test_a_collision_the_original_run_had_too_is_no_reason_to_revert():
    model = Model(collide={("R1.base_link", "floor.floor"): 1.0}, always=True)
    out = refine(task(4), model)
    assert out.reverted == [] and len(out.parallelized) == 1


def test_several_parallelizations_are_reverted_latest_first():
    """Task 3 parallelizes both robots' raise with their approach; while a collision stays
    new, the latest parallelization is reverted, then the one before."""
    program = task(3)
    model = Model(collide={("R2.gripper_base", "table.table"): 3.0})
    out = refine(program, model)
    assert [p.describe() for p, _, _ in out.reverted] == [
        "R2: raise_arm runs in parallel with approach",
        "R1: raise_arm runs in parallel with approach",
    ]
    assert out.parallelized == []
    assert out.phases[1].program == program
    # original, parallelized twice (two, one), tuning, rate-refined
    assert [o["tune"] for _, o in model.calls] == [False] * 3 + [True, False]


def test_a_parallelization_that_misses_the_goal_is_reverted():
    model = Model(misses=lambda p: any(b.parallel_with for _, _, b in p.behaviors()))
    out = refine(task(4), model)
    ((bad, why, collisions),) = out.reverted
    assert why.startswith("goal not met: the chair is open: folding_chair.hinge = 0.200 < 0.35")
    assert collisions == [] and out.goal_met


def test_a_speed_change_whose_run_misses_the_goal_is_undone():
    fast = 0.7 / (0.45 / 7.0e-3) - 1e-9
    model = Model(misses=lambda p: p.robot("R1").behavior("approach").motion.speed > fast)
    out = refine(task(4), model)
    assert out.speed_changes == [] and out.speed_undone.startswith("goal not met")
    assert out.phases[2].program == out.phases[1].program
    assert out.phases[2].run is out.phases[1].run
    assert len(out.parallelized) == 1 and out.goal_met


def test_a_harmful_rate_is_backed_off_one_step_at_a_time_until_the_task_holds():
    """Above 20 Hz the goal is missed: 23, 22, 21 Hz are tried and undone, 20 Hz is kept."""
    model = Model(misses=lambda p: rate_of(p) > 20.0)
    out = refine(task(4), model)
    assert out.rates_tried == [23.0, 22.0, 21.0, 20.0] and out.rate_hz == 20.0
    assert rate_of(out.program) == 20.0 and out.phases[3].run.outcome.achieved
    rate_attempts = [a for a in out.attempts if a.phase == "rate-refined"]
    assert [a.rejected is None for a in rate_attempts] == [False, False, False, True]
    assert out.goal_met


def test_the_rates_searched_on_the_queue_model_are_confirmed_by_the_run():
    """Without ``tune_online`` no run is spent probing: Fig. 5 runs per behavior on the
    architecture's queue model (23 Hz for each) and the run of the refined program confirms
    it. Here its Channel delays the IMU's samples above 22 Hz (a wait past the threshold):
    23 Hz is not accepted and backed off, 22 Hz kept."""
    threshold = ARCH.wait_threshold("II", "imu")

    class Delaying(Model):
        def __call__(self, program, architecture, **kw):
            run = super().__call__(program, architecture, **kw)
            late = rate_of(program) > 22.0
            run.sensor_waits = {"R1.imu": threshold + (0.01 if late else -0.01)}
            return run

    model = Delaying()
    out = refine(task(4), model, tune_online=False)
    assert [o["tune"] for _, o in model.calls] == [False] * 5  # no tuning run
    assert out.tuning is None and out.rate_source == "queue model"
    assert out.rates_found == {e: 23.0 for e in task(4).events()}
    assert out.rates_tried == [23.0, 22.0] and out.rate_hz == 22.0
    first = [a for a in out.attempts if a.phase == "rate-refined"][0]
    assert first.rejected.startswith("sensor samples delayed: R1.imu waited")
    assert out.to_json()["rate_search"] == "queue model"
    assert set(out.to_json()["probes"]) == set(task(4).events())


def test_a_rate_that_never_holds_keeps_the_speed_adjusted_program():
    model = Model(misses=lambda p: rate_of(p) > 10.0)
    out = refine(task(4), model)
    assert out.rate_hz == 0.0 and out.rates_tried == [float(r) for r in range(23, 10, -1)]
    assert out.program == out.phases[2].program and out.goal_met


def test_an_original_that_misses_the_goal_is_not_refined():
    model = Model(misses=lambda p: True)
    out = refine(task(4), model)
    assert [p.name for p in out.phases] == ["original"] and len(model.calls) == 1
    assert not out.goal_met
    assert out.failure == (
        "the original program does not meet the goal on the plant: "
        "the chair is open: folding_chair.hinge = 0.200 < 0.35"
    )
    assert out.to_json()["goal_met"] is False


def test_an_original_that_does_not_finish_is_infeasible():
    model = Model(unfired={0: frozenset({"R2.release"})})
    with pytest.raises(InfeasibleError, match="the original program did not finish") as e:
        refine(task(4), model)
    assert "R2.release never fired" in str(e.value)


@pytest.mark.parametrize("phase", [1, 2, 3])
def test_a_later_phase_that_does_not_finish_is_not_accepted(phase):
    model = Model(unfired={phase: frozenset({"R2.release"})})
    out = refine(task(4), model)
    (bad,) = [a for a in out.attempts if a.rejected is not None]
    assert bad.phase == refinement.PHASES[phase]
    assert "R2.release never fired" in bad.rejected and out.goal_met
    assert all(p.run.finished for p in out.phases)


def test_a_rate_search_that_does_not_end_keeps_no_rate():
    model = Model(found={"R1": 29.0, "R2": None})
    out = refine(task(4), model)
    assert out.rate_hz == 0.0 and out.rates_tried == []
    assert len(model.calls) == 4  # no rate-refined program was run
    assert out.program == out.phases[2].program


def test_a_program_that_cannot_finish_is_refused_before_any_run():
    """R2 approaches after R1 raises its arm, which follows R1's pull-out, which waits for
    R2's grip, which follows R2's approach: a cycle."""
    program = task(4)
    approach = replace(program.robot("R2").behavior("approach"), waits_for=("R1.raise_arm",))
    cyclic = program.with_behavior("R2", 0, approach)
    model = Model()
    with pytest.raises(InfeasibleError, match="cycle"):
        refine(cyclic, model)
    assert model.calls == []


def test_a_parallelization_that_breaks_the_ordering_is_refused_with_its_counterexample():
    """A property on the absorbed event (the fork is down before the approach ends): the
    parallelization lets the approach end first, so the gate refuses it before any run and
    the refinement goes on without it."""
    p = replace(task(4), ordering="G(R1.approach -> R1.lower_arm) & G(R1.pull_out -> R2.grip)")
    model = Model()
    out = refine(p, model)
    assert [c.describe() for c, _ in out.refused] == [
        "R1: lower_arm runs in parallel with approach",
        "R1: pull_out no longer waits for R2.grip",
    ]
    report = out.refused[0][1]
    assert "parallelized program task4" in report and "R1.approach" in report
    assert out.parallelized == [] and out.phases[1].program == p
    assert all(not b.parallel_with for _, _, b in out.program.behaviors())
    assert [o["tune"] for _, o in model.calls] == [False, True, False]  # never ran it


def test_the_gate_stops_the_loop_at_the_phase_it_refuses():
    model = Model()
    with pytest.raises(VerificationError):
        refine(task(4), model, gate=Gate(refuse="speed-adjusted"))
    assert len(model.calls) == 2  # original and parallelized


def test_measured_orders_that_break_the_property_are_reported():
    """Robots that ignore each other's events: R2 releases (96.1 s) before R1 pulls out
    (270.5 s; 206.2 s parallel, 203.8 s sped up, 124.95 s at 23 Hz), which the check of
    each measured order notices."""

    class Ignoring(Model):
        def __call__(self, program, architecture, **kw):
            run = super().__call__(program, architecture, **kw)
            loose = replace(
                program,
                robots=tuple(
                    replace(r, behaviors=tuple(replace(b, waits_for=()) for b in r.behaviors))
                    for r in program.robots
                ),
            )
            run.timeline = timeline(loose)
            return run

    out = refine(task(4), Ignoring())
    assert [p["run_satisfies_ordering"] for p in out.to_json()["phases"]] == [False] * 4


def test_the_category_option_replaces_the_programs():
    model = Model()
    out = refine(task(4), model, category="III")
    assert all(p.communication.category == "III" for p, _ in model.calls)
    assert out.to_json()["category"] == "III"


def unmarked(program: Program) -> Program:
    """``program`` without its ``manipulates`` marks."""
    return replace(
        program,
        robots=tuple(
            replace(r, behaviors=tuple(replace(b, manipulates=False) for b in r.behaviors))
            for r in program.robots
        ),
    )


def test_step_1_finds_the_manipulation_from_the_first_touch_of_the_object():
    """Without marks: R1's fork first touches the chair while its base approaches (64.3-131
    s: reaching it, so the pull-out manipulates), R2's fingers while they close (28.6-58.6
    s: the grip manipulates): the paper's parallelization again."""
    model = Model(touches={"R1": (120.0, "folding_chair.latch"), "R2": (45.0, "frame_a")})
    out = refine(unmarked(task(4)), model)
    assert {n: (b.behavior, b.source) for n, b in out.boundaries.items()} == {
        "R1": ("pull_out", "touch"),
        "R2": ("grip", "touch"),
    }
    assert [c.describe() for c in out.parallelized] == [
        "R1: lower_arm runs in parallel with approach"
    ]
    doc = out.to_json()["manipulation_starts"]
    assert doc[0] == {
        "robot": "R1",
        "behavior": "pull_out",
        "source": "touch",
        "touch": [120.0, "folding_chair.latch"],
        "marked": None,
    }


def test_a_marked_behavior_earlier_than_the_touch_is_kept():
    model = Model(touches={"R2": (280.0, "frame_a")})  # while R2 releases
    out = refine(task(4), model)
    assert out.boundaries["R2"].behavior == "grip" and out.boundaries["R2"].source == "marked"


def test_a_robot_without_a_touch_or_a_mark_is_refused():
    with pytest.raises(InfeasibleError, match="R1: where its manipulation starts is unknown"):
        refine(unmarked(task(4)), Model(touches={"R2": (45.0, "frame_a")}))


def test_the_packaged_property_refuses_a_wrong_parallelization_and_keeps_the_papers():
    """A wrong boundary: R2's first touch measured while it releases (as if its fingers
    closed on nothing), so Step 2 also proposes R2's grip with its approach; the task's
    property (the fingers close only after the approach) refuses it before any run, and
    R1's lowering with its approach (the paper's) is kept."""
    model = Model(touches={"R1": (120.0, "latch"), "R2": (280.0, "frame_a")})
    out = refine(unmarked(task(4)), model)
    assert out.boundaries["R2"].behavior == "release"
    assert [c.describe() for c, _ in out.refused] == [
        "R2: approach runs in parallel with grip",
        "R1: pull_out no longer waits for R2.grip",
    ]
    assert "R2.grip" in out.refused[0][1]
    assert [c.describe() for c in out.parallelized] == [
        "R1: lower_arm runs in parallel with approach"
    ]
    assert out.goal_met


def test_a_slack_cross_robot_wait_is_relaxed_and_restored_when_its_run_fails():
    """Without the property on it, R1's slack wait for R2's grip is relaxed (§3.2(b)); run
    once, a collision the original did not have restores it (the parallelization within
    R1 is kept)."""
    p = replace(task(4), ordering="G(R2.release -> R1.pull_out)")
    kept = refine(p, Model())
    assert [x.describe() for x in kept.relaxed] == ["R1: pull_out no longer waits for R2.grip"]
    assert kept.program.robot("R1").behavior("pull_out").waits_for == ()
    assert kept.to_json()["relaxed"] == ["R1: pull_out no longer waits for R2.grip"]

    class Bump(Model):
        def __call__(self, program, architecture, **kw):
            run = super().__call__(program, architecture, **kw)
            if not program.robot("R1").behavior("pull_out").waits_for:
                run.collisions = {("R1.base_link", "R2.base_link"): 70.0}
            return run

    out = refine(p, Bump())
    ((bad, why, _),) = out.reverted
    assert bad.describe() == "R1: pull_out no longer waits for R2.grip"
    assert why == "new collision R1.base_link with R2.base_link at 70.0 s"
    assert out.relaxed == [] and len(out.parallelized) == 1
    assert out.program.robot("R1").behavior("pull_out").waits_for == ("R2.grip",)


def test_a_run_whose_simulation_diverged_is_not_accepted():
    class Diverging(Model):
        def __call__(self, program, architecture, **kw):
            run = super().__call__(program, architecture, **kw)
            if rate_of(program) > 22.0:
                run.diverged = "the simulation diverged at 20.90 s (NaN)"
            return run

    out = refine(task(4), Diverging())
    bad = [a for a in out.attempts if a.rejected is not None]
    assert [a.rejected for a in bad] == ["did not finish: the simulation diverged at 20.90 s (NaN)"]
    assert out.rate_hz == 22.0 and out.goal_met
