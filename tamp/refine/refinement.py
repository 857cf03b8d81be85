"""The refinement of a program, phase by phase, every phase accepted only if the task still works.

Figueroa Heredia et al. 2018 §3 (Fig. 3–6, Fig. 12): the program is modified "without
compromising the successful execution of the task" (§1.2). Every modified program is
executed (by the `Measure` the caller gives) and *accepted* only if its run finishes,
meets the scene's goal on the plant (`Run.outcome`) and has no collision the original run
did not have (`accept`). Phases:

1. **original**: the program as given. Its run is the reference; a program whose original
   run does not meet the goal has nothing to be refined against: the result stops there
   (``goal_met`` False, the reason in ``failure``; `tamp refine` exits 1).
2. **parallelized** (Step 1 + Step 2, §3.2, Fig. 4): Step 1 finds where each robot's
   manipulation starts in the original run (`steps.manipulation_starts`: its first
   gripper/object contact; a robot without one and without a marked behavior is refused);
   `steps.parallelize` on the original run's measured durations, and across the robots
   (§3.2(b)) `steps.slack_waits`: a cross-robot wait the original run shows held nothing
   back is relaxed. Each parallelization or relaxation first passes the ordering gate on
   its own (one the task's LTL property refuses is dropped with the counterexample,
   ``refused``); the program with the rest is executed once, and while it is not
   accepted the latest change is reverted (``reverted``, with the reason) and the
   program runs again. With nothing left the phase is the original program and run.
3. **speed-adjusted** (Fig. 6(c)): `adjust_base_speed` on the parallelized run's
   durations; a run that is not accepted undoes the change (the phase keeps the
   parallelized program and run, ``speed_undone`` says why).
4. **rate-refined** (Fig. 5): for each behavior of the speed-adjusted program, P rises
   on the architecture's queue model while the sensor that triggers its event delivers
   without delay under the behavior's command load (`behavior_searches`: the model the
   simulation's Channel runs, so no run is spent probing); with ``tune_online`` a tuning
   run searches online instead, per robot and trigger sensor. Each behavior gets its rate
   (`behavior_rates`; parallel behaviors share their group's lowest) and `apply_rate`
   writes it (Step 3: the base's speed by the same ratio, or every section's with
   ``scale="all"``). The run of the refined program confirms the rates: a trigger
   sensor's samples delayed past the threshold in it (`delayed`) make it not accepted,
   like a missed goal. A run that is not accepted backs every rate off one search step at
   a time until the task holds (our addition: the paper stops at the last rate without
   sensor delay and does not say what to do when the task fails there); at the starting
   rates nothing is kept.

Every attempt (program tried, measured task time, goal, new collisions, accepted or why
not) is kept in ``attempts`` in the order it ran, so the JSON lists what each phase tried,
measured and kept. The ordering property is checked by functions the caller gives (the
verification layer's `gate_program` and `check_run`): every program passes the ``gate``
before it is measured, and each measured run's event order is checked too
(`Phase.run_holds`). Nothing here simulates. The original program not finishing (or a
cycle, `check_can_finish`) is `InfeasibleError`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from tamp.errors import InfeasibleError
from tamp.refine.architecture import Architecture, behavior_loads, behavior_searches
from tamp.refine.measure import Measure, Run
from tamp.refine.order import check_can_finish
from tamp.refine.program import Program
from tamp.refine.steps import (
    Boundary,
    Parallelization,
    RateSearch,
    Relaxation,
    SpeedChange,
    adjust_base_speed,
    apply_rate,
    behavior_rates,
    join,
    manipulation_starts,
    parallelize,
    relax,
    restore,
    revert,
    slack_waits,
)


class Gate(Protocol):
    """Refuses ``program`` (raises an `InfeasibleError`, with the counterexample) when some
    execution of it breaks its ordering property; ``subject`` names it in the report
    (`tamp.verification.gate.gate_program`)."""

    def __call__(self, program: Program, *, subject: str) -> object: ...


class Verdict(Protocol):
    holds: bool


class RunCheck(Protocol):
    """The verdict of one measured event ``order`` against ``program``'s ordering property
    (`tamp.verification.refine.check_run`)."""

    def __call__(self, program: Program, order: Sequence[str]) -> Verdict: ...


PHASES = ("original", "parallelized", "speed-adjusted", "rate-refined")

Collision = tuple[str, str, float]  # (robot body, other body, first contact time)


def new_collisions(run: Run, reference: Run) -> list[Collision]:
    """Collisions of ``run`` whose pair the ``reference`` run did not have, with first times."""
    return [
        (*k, run.collisions[k]) for k in sorted(set(run.collisions) - set(reference.collisions))
    ]


def accept(run: Run, reference: Run) -> str | None:
    """Why ``run`` is not accepted (None: it is): it did not finish, it missed the goal on
    the plant, or it has a collision the ``reference`` (original) run did not."""
    if run.diverged is not None:
        return f"did not finish: {run.diverged}"
    if not run.finished:
        stuck = [r.event for r in run.timeline.records if r.end is None]
        return f"did not finish within {run.sim_time:.0f} s: {', '.join(stuck)} never fired"
    if not run.outcome.achieved:
        return "goal not met: " + "; ".join(run.outcome.failed())
    new = new_collisions(run, reference)
    if new:
        a, b, t = new[0]
        return f"new collision {a} with {b} at {t:.1f} s"
    return None


def delayed(run: Run, program: Program, architecture: Architecture) -> str | None:
    """Why the rates of ``program`` are not confirmed by its ``run`` (None: they are): a
    trigger sensor whose samples waited longer in the run's Channel than the architecture's
    threshold (Fig. 5: "arrive without delay"; the threshold of the heaviest command load
    the robot sends, `Architecture.wait_threshold`). A run that measured no waits (a
    prediction) confirms nothing and refuses nothing."""
    category = program.communication.category
    for key, wait in sorted(run.sensor_waits.items()):
        robot, _, sensor = key.partition(".")
        loads = set(behavior_loads(program, robot).values())
        threshold = max(architecture.wait_threshold(category, sensor, load=ld) for ld in loads)
        if wait > threshold:
            return (
                f"sensor samples delayed: {key} waited {1e3 * wait:.1f} ms "
                f"(> {1e3 * threshold:.1f} ms)"
            )
    return None


@dataclass
class Attempt:
    """One executed program of a phase: what it tried, the run, and why it was not
    accepted (``rejected`` None: accepted)."""

    phase: str
    tried: list[str]
    run: Run
    rejected: str | None
    new_collisions: list[Collision] = field(default_factory=list)

    def to_json(self) -> dict:
        return {
            "phase": self.phase,
            "tried": list(self.tried),
            "task_time": round(self.run.task_time, 3) if self.run.finished else None,
            "finished": self.run.finished,
            "goal_met": self.run.outcome.achieved,
            "outcome": self.run.outcome.summary(),
            "new_collisions": [[a, b, round(t, 3)] for a, b, t in self.new_collisions],
            "accepted": self.rejected is None,
            "rejected": self.rejected,
        }


@dataclass
class Phase:
    """One phase: its accepted program, the run that measured it, whether the run's event
    order satisfies the ordering property and what the phase kept (in words)."""

    name: str
    program: Program
    run: Run
    run_holds: bool
    kept: list[str] = field(default_factory=list)

    @property
    def task_time(self) -> float:
        return self.run.task_time


@dataclass
class Refinement:
    """All phases, what each step tried and kept, the tuning run and the kept rate."""

    phases: list[Phase]
    attempts: list[Attempt] = field(default_factory=list)
    boundaries: dict[str, Boundary] = field(default_factory=dict)  # Step 1, per robot
    parallelized: list[Parallelization] = field(default_factory=list)
    relaxed: list[Relaxation] = field(default_factory=list)  # cross-robot waits dropped
    # each parallelization or relaxation the ordering gate refused, with the gate's report
    refused: list[tuple[Parallelization | Relaxation, str]] = field(default_factory=list)
    # each reverted one with the reason and the new collisions of its run
    reverted: list[tuple[Parallelization | Relaxation, str, list[Collision]]] = field(
        default_factory=list
    )
    speed_changes: list[SpeedChange] = field(default_factory=list)
    speed_undone: str | None = None
    tuning: Run | None = None  # the online search's run (``tune_online``)
    # Fig. 5's searches: per behavior (``ROBOT.BEHAVIOR``, on the queue model) or, online,
    # per robot and trigger sensor (``ROBOT.SENSOR``)
    searches: dict[str, RateSearch | None] = field(default_factory=dict)
    rates_found: dict[str, float] = field(default_factory=dict)  # search key -> Hz
    rate_hz: float = 0.0  # the lowest rate kept (0: none)
    behavior_rates: dict[str, float] = field(default_factory=dict)  # event id -> Hz kept
    rates_tried: list[float] = field(default_factory=list)
    scale: str = "base"
    failure: str | None = None  # why no accepted program meets the goal
    verified: bool = True

    @property
    def rate_source(self) -> str:
        """Where the rates were searched: online in a tuning run, or on the queue model."""
        return "online" if self.tuning is not None else "queue model"

    @property
    def goal_met(self) -> bool:
        """The last accepted program meets the goal on the plant."""
        return self.failure is None

    @property
    def program(self) -> Program:
        """The refined program: the last accepted phase's."""
        return self.phases[-1].program

    @property
    def reduction(self) -> float:
        """Fraction of the original task time saved by the refined program."""
        first, last = self.phases[0].task_time, self.phases[-1].task_time
        return 1.0 - last / first if first > 0 else 0.0

    def _runs(self) -> list[Run]:
        return [a.run for a in self.attempts] + ([self.tuning] if self.tuning else [])

    @property
    def sim_time(self) -> float:
        return sum(r.sim_time for r in self._runs())

    @property
    def wall_time(self) -> float:
        return sum(r.wall_time for r in self._runs())

    @property
    def cpu_time(self) -> float:
        return sum(r.cpu_time for r in self._runs())

    def to_json(self) -> dict:
        return {
            "program": self.phases[0].program.name,
            "category": self.program.communication.category,
            "goal_met": self.goal_met,
            "failure": self.failure,
            "phases": [
                {
                    "name": p.name,
                    "task_time": round(p.task_time, 3),
                    "kept": list(p.kept),
                    "timeline": p.run.timeline.to_json()["behaviors"],
                    "max_wait": {k: round(v, 5) for k, v in p.run.max_wait.items()},
                    "run_satisfies_ordering": p.run_holds,
                    "collisions": [
                        [a, b, round(t, 3)] for (a, b), t in sorted(p.run.collisions.items())
                    ],
                    "outcome": p.run.outcome.to_json(),
                }
                for p in self.phases
            ],
            "attempts": [a.to_json() for a in self.attempts],
            "rate_hz": self.rate_hz,
            "rates_found": dict(self.rates_found),
            "behavior_rates": dict(self.behavior_rates),
            "rates_tried": list(self.rates_tried),
            "scale": self.scale,
            "rate_search": self.rate_source,
            "probes": {
                n: [[r, round(w, 5)] for r, w in s.probes]
                for n, s in self.searches.items()
                if s is not None
            },
            "reduction": round(self.reduction, 4),
            "manipulation_starts": [b.to_json() for b in self.boundaries.values()],
            "parallelized": [p.describe() for p in self.parallelized],
            "relaxed": [x.describe() for x in self.relaxed],
            "refused": [{"parallelization": p.describe(), "report": r} for p, r in self.refused],
            "reverted": [
                {
                    "parallelization": p.describe(),
                    "reason": why,
                    "collisions": [[a, b, round(t, 3)] for a, b, t in cs],
                }
                for p, why, cs in self.reverted
            ],
            "speed_changes": [c.describe() for c in self.speed_changes],
            "speed_undone": self.speed_undone,
            "verified": self.verified,
            "sim_time": round(self.sim_time, 3),
            "wall_time": round(self.wall_time, 3),
            "cpu_time": round(self.cpu_time, 3),
        }


def refine(
    program: Program,
    architecture: Architecture,
    measure: Measure,
    *,
    gate: Gate | None,
    check_run: RunCheck,
    category: str | None = None,
    scale: str = "base",
    record: str | Path | None = None,
    tune_online: bool = False,
    progress: Callable[[str], None] = lambda _: None,
) -> Refinement:
    """The four phases of ``program`` (module docstring), each run measured by ``measure``.

    ``gate``: the ordering gate every program passes before it is measured (None: no gate,
    the result says ``verified`` False); ``check_run``: the check of each measured event
    order; ``category`` replaces the program's architecture category; ``scale``: Step 3
    scales the base's speed (``"base"``, the paper's) or every section's (``"all"``);
    ``record`` asks each rate-refined run for an animation (the last one written is the
    last rate tried); ``tune_online``: Fig. 5 probes the rates in a tuning run of the
    speed-adjusted program (one more run; per robot and trigger sensor) instead of on the
    architecture's queue model (`behavior_searches`, per behavior)."""
    if category is not None:
        program = program.with_category(category)
    check_can_finish(program)

    def gated(p: Program, phase: str) -> Program:
        if gate is not None:
            gate(p, subject=f"{phase} program {p.name}")
        return p

    def run(p: Program, phase: str, **kw) -> Run:
        progress(f"measuring the {phase} program ...")
        r = measure(p, architecture, **kw)
        if r.finished:
            outcome = r.outcome.summary()
            outcome = f", {outcome}" if outcome else ""
            progress(f"  {phase}: {r.task_time:.1f} s{outcome} (wall {r.wall_time:.1f} s)")
        return r

    def phase(name: str, p: Program, r: Run, kept: list[str]) -> Phase:
        holds = check_run(p, r.timeline.order()).holds if r.finished else False
        return Phase(name, p, r, holds, kept)

    out = Refinement([], verified=gate is not None, scale=scale)

    def attempt(
        name: str,
        p: Program,
        tried: list[str],
        reference: Run | None,
        architecture: Architecture | None = None,
        **kw,
    ):
        r = run(gated(p, name), name, **kw)
        why = accept(r, reference or r)
        if why is None and architecture is not None:
            why = delayed(r, p, architecture)
        new = new_collisions(r, reference) if reference is not None else []
        out.attempts.append(Attempt(name, tried, r, why, new))
        if why is not None:
            progress(f"  {name} not accepted: {why}")
        return r, why

    # 1. original
    original, why = attempt("original", program, [], None)
    if not original.finished:
        raise InfeasibleError(f"the original program {why}")
    out.phases.append(phase("original", program, original, []))
    if why is not None:
        failed = "; ".join(original.outcome.failed())
        out.failure = f"the original program does not meet the goal on the plant: {failed}"
        return out

    # 2. parallelized: each parallelization gated on its own, then run once and reverted
    spans = {r.event: (r.start, r.end) for r in original.timeline.records}
    out.boundaries = manipulation_starts(
        program, original.touches, spans, has_goal=bool(original.outcome.goals)
    )
    starts = {name: b.index for name, b in out.boundaries.items()}
    _, found = parallelize(program, original.timeline.durations(), starts)
    candidates: list[Parallelization | Relaxation] = [*found, *slack_waits(program, spans)]
    p1, kept = program, []
    for c in candidates:
        trial = join(p1, c) if isinstance(c, Parallelization) else relax(p1, c)
        if gate is not None:
            try:
                gate(trial, subject=f"parallelized program {trial.name} ({c.describe()})")
            except InfeasibleError as e:
                out.refused.append((c, str(e)))
                progress(f"  refused by the ordering property: '{c.describe()}'")
                continue
        p1, kept = trial, kept + [c]
    r1 = original
    while kept:
        r, why = attempt("parallelized", p1, [c.describe() for c in kept], original)
        if why is None:
            r1 = r
            break
        bad = kept.pop()  # the latest first
        out.reverted.append((bad, why, new_collisions(r, original)))
        progress(f"  reverting '{bad.describe()}'")
        p1 = revert(p1, bad) if isinstance(bad, Parallelization) else restore(p1, bad)
    out.parallelized = [c for c in kept if isinstance(c, Parallelization)]
    out.relaxed = [c for c in kept if isinstance(c, Relaxation)]
    out.phases.append(phase("parallelized", p1, r1, [c.describe() for c in kept]))

    # 3. speed-adjusted (Fig. 6(c)); undone when its run is not accepted
    p2, r2 = p1, r1
    trial, changes = adjust_base_speed(p1, r1.timeline.durations())
    if changes:
        r, why = attempt("speed-adjusted", trial, [c.describe() for c in changes], original)
        if why is None:
            p2, r2, out.speed_changes = trial, r, changes
        else:
            out.speed_undone = why
    out.phases.append(phase("speed-adjusted", p2, r2, [c.describe() for c in out.speed_changes]))

    # 4. rate-refined (Fig. 5): the search per behavior, then back off one step while the
    # run of the refined program is not accepted
    if tune_online:
        progress("tuning the command rate online (Fig. 5) ...")
        tuning = measure(p2, architecture, tune=True)
        out.tuning = tuning
        out.searches = dict(tuning.searches)
        searches_ended = len(tuning.found_rates()) == len(p2.robots)
        if not searches_ended:
            progress(f"  the rate search did not end within {tuning.sim_time:.0f} s of sim time")
    else:  # the measure's own (a log's rates) or the queue model's
        known = getattr(measure, "rate_searches", None)
        searches = known(p2, architecture) if known else behavior_searches(p2, architecture)
        out.searches = dict(searches)
        searches_ended = True
    out.rates_found = {
        k: s.found for k, s in out.searches.items() if s is not None and s.found is not None
    }
    p3, r3, rate_kept = p2, r2, []
    if searches_ended:
        progress(f"  rates found (Fig. 5, {out.rate_source}): {out.rates_found}")
        back_off = 0.0
        while rates := behavior_rates(p2, out.rates_found, back_off=back_off):
            trial = p2
            for robot, rs in rates.items():
                trial = apply_rate(trial, robot, rs, scale=scale)
            flat = {f"{robot}.{b}": v for robot, rs in rates.items() for b, v in rs.items()}
            lo, hi = min(flat.values()), max(flat.values())
            span = f"{hi:g} Hz" if lo == hi else f"{lo:g}-{hi:g} Hz"
            words = f"{span} per behavior ({len(flat)} behaviors), {scale} speed scaled"
            out.rates_tried.append(hi)
            r, why = attempt(
                "rate-refined", trial, [words], original, record=record, architecture=architecture
            )
            if why is None:
                p3, r3, out.rate_hz, out.behavior_rates = trial, r, lo, flat
                rate_kept = [words]
                break
            back_off += architecture.rate_step_hz
            progress(f"  backing the rates off by {back_off:g} Hz")
    out.phases.append(phase("rate-refined", p3, r3, rate_kept))
    return out
