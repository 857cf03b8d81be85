"""The refinement of a program, phase by phase, every task time measured by execution.

Figueroa Heredia et al. 2018 §3 (Fig. 3, Fig. 12). Phases:

1. **original**: the program as given.
2. **parallelized** (Step 1 + Step 2): `tamp.refine.steps.parallelize` on the durations
   the original run measured. The result is executed once; a parallelization after which
   a collision appears that the original run did not have (in the workcell: a chassis
   touching anything, a robot touching the other or the table) is reverted (`revert`,
   latest first) and the program runs again without it.
3. **speed-adjusted** (Fig. 6(c)): `adjust_base_speed` on the parallelized run's
   durations.
4. **rate-refined** (Fig. 5): a tuning run of the speed-adjusted program, each robot's
   rate searched online; the lower of the robots' found rates is applied to both
   (`apply_rate`, Step 3: every speed scales by the same ratio, the base's included), as in
   the paper, and the program runs again.

Nothing here simulates: every run comes from the `Measure` the caller gives
(`tamp.refine.measure`; the Drake workcell's is `tamp.sim.refine.simulate.simulate`). The
ordering property is checked the same way, by functions the caller gives (the verification
layer's `gate_program` and `check_run`): every program passes the ``gate`` before it is
measured (a refinement that lets some execution break the task's ordering property is
refused with the counterexample: the gate raises), and each measured run's event order is
checked too (`Phase.run_holds`). A program that cannot finish (`check_can_finish`, or an
event that did not fire in a measured run, or a rate search that did not end) is
`InfeasibleError`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from tamp.errors import InfeasibleError
from tamp.refine.architecture import Architecture
from tamp.refine.measure import Measure, Run
from tamp.refine.order import check_can_finish
from tamp.refine.program import Program
from tamp.refine.steps import (
    Parallelization,
    SpeedChange,
    adjust_base_speed,
    apply_rate,
    parallelize,
    revert,
)


class Gate(Protocol):
    """Refuses ``program`` (raises, with the counterexample) when some execution of it breaks
    its ordering property; ``subject`` names it in the report
    (`verification.gate.gate_program`)."""

    def __call__(self, program: Program, *, subject: str) -> object: ...


class Verdict(Protocol):
    holds: bool


class RunCheck(Protocol):
    """The verdict of one measured event ``order`` against ``program``'s ordering property
    (`verification.refine.check_run`)."""

    def __call__(self, program: Program, order: Sequence[str]) -> Verdict: ...


PHASES = ("original", "parallelized", "speed-adjusted", "rate-refined")


@dataclass
class Phase:
    """One phase: its program, the (finished) run that measured it and whether the run's
    event order satisfies the ordering property."""

    name: str
    program: Program
    run: Run
    run_holds: bool

    @property
    def task_time(self) -> float:
        return self.run.task_time


@dataclass
class Refinement:
    """All phases, what each step changed, the tuning run and the found rate."""

    phases: list[Phase]
    parallelized: list[Parallelization] = field(default_factory=list)
    # each reverted parallelization with the new collisions (robot body, other, first time)
    reverted: list[tuple[Parallelization, list[tuple[str, str, float]]]] = field(
        default_factory=list
    )
    speed_changes: list[SpeedChange] = field(default_factory=list)
    tuning: Run | None = None
    rate_hz: float = 0.0
    verified: bool = True

    @property
    def program(self) -> Program:
        """The refined program (the last phase's)."""
        return self.phases[-1].program

    @property
    def reduction(self) -> float:
        """Fraction of the original task time saved by the refined program."""
        first, last = self.phases[0].task_time, self.phases[-1].task_time
        return 1.0 - last / first if first > 0 else 0.0

    @property
    def sim_time(self) -> float:
        runs = [p.run for p in self.phases] + ([self.tuning] if self.tuning else [])
        return sum(r.sim_time for r in runs)

    @property
    def wall_time(self) -> float:
        runs = [p.run for p in self.phases] + ([self.tuning] if self.tuning else [])
        return sum(r.wall_time for r in runs)

    def to_json(self) -> dict:
        return {
            "program": self.phases[0].program.name,
            "category": self.program.communication.category,
            "phases": [
                {
                    "name": p.name,
                    "task_time": round(p.task_time, 3),
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
            "rate_hz": self.rate_hz,
            "rates_found": {k: v for k, v in self.tuning.found_rates().items()}
            if self.tuning
            else {},
            "probes": {
                n: [[r, round(w, 5)] for r, w in s.probes]
                for n, s in (self.tuning.searches.items() if self.tuning else [])
                if s is not None
            },
            "reduction": round(self.reduction, 4),
            "parallelized": [p.describe() for p in self.parallelized],
            "reverted": [
                {
                    "parallelization": p.describe(),
                    "collisions": [[a, b, round(t, 3)] for a, b, t in cs],
                }
                for p, cs in self.reverted
            ],
            "speed_changes": [c.describe() for c in self.speed_changes],
            "verified": self.verified,
            "sim_time": round(self.sim_time, 3),
            "wall_time": round(self.wall_time, 3),
        }


def _not_finished(run: Run, what: str) -> InfeasibleError:
    stuck = [r.event for r in run.timeline.records if r.end is None]
    return InfeasibleError(
        f"the {what} program did not finish within {run.sim_time:.0f} s of sim time: "
        f"{', '.join(stuck)} never fired"
    )


def refine(
    program: Program,
    architecture: Architecture,
    measure: Measure,
    *,
    gate: Gate | None,
    check_run: RunCheck,
    category: str | None = None,
    record: str | Path | None = None,
    progress: Callable[[str], None] = lambda _: None,
) -> Refinement:
    """The four phases of ``program`` (module docstring), each run measured by ``measure``.

    ``gate``: the ordering gate every program passes before it is measured (None: no gate,
    the result says ``verified`` False); ``check_run``: the check of each measured event
    order; ``category`` replaces the program's architecture category; ``record`` asks the
    refined program's run for an animation."""
    if category is not None:
        program = program.with_category(category)
    check_can_finish(program)

    def gated(p: Program, phase: str) -> Program:
        if gate is not None:
            gate(p, subject=f"{phase} program {p.name}")
        return p

    def run(p: Program, phase: str, **kw) -> Run:
        progress(f"simulating the {phase} program ...")
        r = measure(p, architecture, **kw)
        progress(f"  {phase}: {r.task_time:.1f} s (wall {r.wall_time:.1f} s)")
        return r

    def phase(name: str, p: Program, r: Run) -> Phase:
        if not r.finished:
            raise _not_finished(r, name)
        return Phase(name, p, r, check_run(p, r.timeline.order()).holds)

    original = run(gated(program, "original"), "original")
    phases = [phase("original", program, original)]
    out = Refinement(phases, verified=gate is not None)

    p1, done = parallelize(program, original.timeline.durations())
    out.parallelized = list(done)
    r1 = run(gated(p1, "parallelized"), "parallelized")
    while True:
        new = [
            (*k, r1.collisions[k]) for k in sorted(set(r1.collisions) - set(original.collisions))
        ]
        if not new or not out.parallelized:
            break
        bad = out.parallelized.pop()  # the latest parallelization first
        out.reverted.append((bad, new))
        a, b, t = new[0]
        progress(f"  collision ({a}, {b}) at {t:.1f} s: reverting '{bad.describe()}'")
        p1 = revert(p1, bad)
        r1 = run(gated(p1, "parallelized"), "parallelized")
    phases.append(phase("parallelized", p1, r1))

    p2, changes = adjust_base_speed(p1, r1.timeline.durations())
    out.speed_changes = changes
    r2 = run(gated(p2, "speed-adjusted"), "speed-adjusted")
    phases.append(phase("speed-adjusted", p2, r2))

    progress("tuning the command rate (Fig. 5) ...")
    tuning = measure(p2, architecture, tune=True)
    found = tuning.found_rates()
    if len(found) != len(p2.robots):
        raise InfeasibleError(
            f"the rate search did not end within {tuning.sim_time:.0f} s of sim time"
        )
    out.tuning = tuning
    out.rate_hz = min(found.values())
    progress(f"  rates found {found}: applying {out.rate_hz:g} Hz to both robots")
    p3 = p2
    for r in p2.robots:
        p3 = apply_rate(p3, r.name, out.rate_hz)
    r3 = run(gated(p3, "rate-refined"), "rate-refined", record=record)
    phases.append(phase("rate-refined", p3, r3))
    return out
