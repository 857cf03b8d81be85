"""The refinement loop's decisions (Figueroa Heredia et al. 2018 §3), without Drake.

The loop is given a measuring function; here it is a timeline model (`Model`): a behavior
starts when the events it must follow have fired (`tamp.refine.order.start_predecessors`)
and lasts its motion's nominal time, so parallelizing, speeding up the base and raising
the rate shorten the measured task exactly as the steps intend. The model can also report
collisions, leave events unfired or searches unfinished, so every branch of the loop is
exercised: a parallelization kept or reverted, the speed and rate phases, each
`InfeasibleError`, the gate refusing a phase. test_simulation and the CLI test run the
loop on the Drake workcell.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import pytest

from tamp.errors import InfeasibleError
from tamp.refine import refinement
from tamp.refine.architecture import default_architecture
from tamp.refine.measure import Run
from tamp.refine.order import direct_predecessors
from tamp.refine.program import Program, event_id
from tamp.refine.steps import RateSearch
from tamp.refine.timeline import BehaviorRecord, Timeline
from tests.refine.helpers import task
from verification.gate import gate_program
from verification.refine import check_run
from verification.verdict import VerificationError

ARCH = default_architecture()


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
    speed-adjusted, 3 rate-refined); ``found``: each robot's rate found by the tuning run
    (None: the search never ends). ``calls`` records (program, options) of every call.
    """

    collide: dict[tuple[str, str], float] = field(default_factory=dict)
    always: bool = False
    unfired: dict[int, frozenset[str]] = field(default_factory=dict)
    found: dict[str, float | None] = field(default_factory=lambda: {"R1": 29.0, "R2": 23.0})
    calls: list[tuple[Program, dict]] = field(default_factory=list)

    def __call__(self, program, architecture, *, tune=False, max_sim_time=None, record=None):
        assert architecture is ARCH
        self.calls.append((program, {"tune": tune, "record": record}))
        phase = -1 if tune else sum(1 for _, o in self.calls if not o["tune"]) - 1
        run = Run(program, timeline(program, self.unfired.get(phase, frozenset())))
        run.sim_time = 200.0
        parallel = any(b.parallel_with for _, _, b in program.behaviors())
        if self.always or parallel:
            run.collisions = dict(self.collide)
        if tune:
            run.searches = {
                r.name: RateSearch(10.0, 3.0, 0.03, 200.0, found=self.found[r.name])
                for r in program.robots
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
    return refinement.refine(program, ARCH, measure, gate=gate, check_run=check_run, **kw)


def test_the_four_phases_shorten_the_task_as_each_step_intends():
    """Task 4 in the model: R1 lowers its lift (60 s) then approaches (66.7 s); Step 2 runs
    them together, Fig. 6(c) speeds the approach up to end with the lift, Step 3 applies the
    lower found rate (23 Hz) to both robots, 2.3 times the speeds."""
    model = Model()
    out = refine(task(4), model)
    assert [p.name for p in out.phases] == list(refinement.PHASES)
    assert [o["tune"] for _, o in model.calls] == [False, False, False, True, False]
    times = [p.task_time for p in out.phases]
    # R2 grips at 66.07 s; R1 pulls out then: after its approach (126.67 s; 66.67 s when
    # parallel; 60 s when sped up, where it waits for the grip) and R2 releases after it
    assert times == pytest.approx([192.738, 132.738, 132.143, 132.143 / 2.3], abs=1e-3)
    # parallelization kept: the measured parallelized run was fine
    assert [p.describe() for p in out.parallelized] == [
        "R1: lower_arm runs in parallel with approach"
    ]
    assert out.reverted == []
    approach = out.phases[1].program.robot("R1").behavior("approach")
    assert approach.parallel_with == "lower_arm"
    # speed phase: the approach's base speed grew by 66.7 / 60
    (change,) = out.speed_changes
    assert change.event == "R1.approach" and change.partner == "lower_arm"
    assert change.new == pytest.approx(0.7 / 60.0)  # 0.7 m in the lift's 60 s
    adjusted = out.phases[2].program.robot("R1").behavior("approach")
    assert adjusted.motion.speed == pytest.approx(change.new)
    # rate phase: the lower of the two found rates, on both robots, every speed scaled
    assert out.rate_hz == 23.0 and out.tuning.found_rates() == {"R1": 29.0, "R2": 23.0}
    assert model.calls[3][0] == out.phases[2].program  # the tuning run is of the adjusted one
    for r2, r3 in zip(out.phases[2].program.robots, out.program.robots, strict=True):
        for b2, b3 in zip(r2.behaviors, r3.behaviors, strict=True):
            assert b3.rate_hz == 23.0
            assert b3.motion.speed == pytest.approx(b2.motion.speed * 2.3)
    # every measured order respects the precedences, so it satisfies the ordering property
    assert [p.run_holds for p in out.phases] == [True] * 4
    assert out.verified and out.reduction == pytest.approx(1 - times[3] / times[0])
    doc = out.to_json()
    assert doc["rate_hz"] == 23.0 and doc["category"] == "II" and doc["verified"] is True
    assert [p["name"] for p in doc["phases"]] == list(refinement.PHASES)
    assert doc["sim_time"] == 5 * 200.0


def test_only_the_refined_run_is_recorded_and_each_phase_is_gated(tmp_path):
    model, gate = Model(), Gate()
    refine(task(4), model, gate=gate, record=tmp_path / "r.html")
    assert [o["record"] for _, o in model.calls] == [None] * 4 + [tmp_path / "r.html"]
    assert gate.subjects == [
        "original program task4",
        "parallelized program task4",
        "speed-adjusted program task4",
        "rate-refined program task4",
    ]


def test_without_a_gate_nothing_is_gated_and_the_result_says_so():
    out = refine(task(4), Model(), gate=None)
    assert out.verified is False and out.to_json()["verified"] is False


def test_a_colliding_parallelization_is_reverted_and_the_program_runs_again():
    model = Model(collide={("R1.arm_link", "folding_chair.frame_b"): 12.0})
    out = refine(task(4), model)
    assert out.parallelized == []
    ((bad, collisions),) = out.reverted
    assert bad.absorbed == "lower_arm" and bad.host == "approach"
    assert collisions == [("R1.arm_link", "folding_chair.frame_b", 12.0)]  # with its time
    assert out.phases[1].program == task(4)  # run again without it
    assert [o["tune"] for _, o in model.calls] == [False, False, False, False, True, False]
    assert out.phases[1].task_time == pytest.approx(out.phases[0].task_time)
    assert out.speed_changes == []  # no group left to balance


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
    assert [p.describe() for p, _ in out.reverted] == [
        "R2: raise_arm runs in parallel with approach",
        "R1: raise_arm runs in parallel with approach",
    ]
    assert out.parallelized == []
    assert out.phases[1].program == program
    # original, parallelized three times (two, one, none), speed-adjusted, tuning, rate-refined
    assert [o["tune"] for _, o in model.calls] == [False] * 5 + [True, False]


@pytest.mark.parametrize(
    "phase,name",
    [(0, "original"), (1, "parallelized"), (2, "speed-adjusted"), (3, "rate-refined")],
)
def test_a_phase_that_does_not_finish_is_infeasible(phase, name):
    model = Model(unfired={phase: frozenset({"R2.release"})})
    with pytest.raises(InfeasibleError, match=f"the {name} program did not finish") as e:
        refine(task(4), model)
    assert "R2.release never fired" in str(e.value)


def test_a_rate_search_that_does_not_end_is_infeasible():
    model = Model(found={"R1": 29.0, "R2": None})
    with pytest.raises(InfeasibleError, match="rate search did not end"):
        refine(task(4), model)
    assert len(model.calls) == 4  # the rate-refined program was never run


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


def test_a_refinement_that_breaks_the_ordering_is_refused():
    p = replace(task(4), ordering="G(R1.approach -> R1.lower_arm)")
    model = Model()
    with pytest.raises(VerificationError) as exc:
        refine(p, model)
    assert "parallelized program task4" in str(exc.value)
    assert exc.value.report.counterexample is not None
    assert len(model.calls) == 1  # only the original ran


def test_the_gate_stops_the_loop_at_the_phase_it_refuses():
    model = Model()
    with pytest.raises(VerificationError):
        refine(task(4), model, gate=Gate(refuse="speed-adjusted"))
    assert len(model.calls) == 2  # original and parallelized


def test_measured_orders_that_break_the_property_are_reported():
    """Robots that ignore each other's events: in the original run R2 releases (103.6 s)
    before R1 pulls out (155.2 s), which the check of the measured order notices; once R1's
    approach is parallel it pulls out first (95.2 s), and the property holds again."""

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
    assert [p["run_satisfies_ordering"] for p in out.to_json()["phases"]] == [
        False,
        True,
        True,
        True,
    ]


def test_the_category_option_replaces_the_programs():
    model = Model()
    out = refine(task(4), model, category="III")
    assert all(p.communication.category == "III" for p, _ in model.calls)
    assert out.to_json()["category"] == "III"
