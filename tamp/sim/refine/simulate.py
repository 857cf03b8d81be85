"""The refinement workcell's runs: one program measured in simulation, and seeded runs.

`simulate` is the workcell's `tamp.refine.measure.Measure`: it builds the station of a
program in its scene and runs it to the end. The simulator advances in chunks
(`tamp.sim.core.runner.run_in_chunks`) and stops when both state machines have fired every
event, or, in a tuning run, when the supervisor's searches have ended. The collisions are
the station's `ContactMonitor`'s (`tamp.sim.refine.contacts`: contacts judged at every
plant step; a pair in contact for `MIN_CONTACT_STEPS` steps in all is a collision), each with its
first time. Nothing is computed
from the program's numbers: start and end times are when the machines started behaviors
and fired events in sim time. At the end it measures what the objects did
(`tamp.sim.refine.outcome`: the chair's hinge angle, the scale's tilt) against the scene's
goals.

Seeded runs (``tamp refine --seed N``, ``tamp simulate refine``, campaigns): the program
file's ``perturbation`` section (`Program.perturbation`, read by the loader) drawn for one
seed and applied to the program (`perturbed_program`). The workcell simulates the
``robot`` field only (`tamp.sim.refine.scenario.PERTURBED`): each robot's start pose
``(x, y, yaw)`` is moved by its own draw (`PerturbationSample.robot_offset`, keyed by the
robot's name). The scene's objects lie where the scene puts them. A start moved onto the
object shows as a collision or an unfinished run, which is what a perturbation is for.

`RefineWorkcell` (``WORKCELL``) is the cell's `tamp.sim.core.workcell.Workcell`: ONE
seeded run of a program as given (no refinement), judged (`judge`) by its events, its
measured event order, the scene's goal read on the plant and its collisions against the
unperturbed run's (`reference_run`): SUCCESS only when the goal is met and no new
collision occurred. Drake is imported only inside functions, so listing the workcells builds
nothing.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tamp.perturbation import Applied, Perturbation, check_seed
from tamp.refine.architecture import Architecture
from tamp.refine.measure import Run
from tamp.refine.program import Program
from tamp.refine.timeline import Timeline
from tamp.sim.core.workcell import Option, RunResult
from tamp.sim.refine.scenario import RefineScenario, Scene, load_scenario, load_scene

if TYPE_CHECKING:
    from tamp.sim.refine.station import RefineStation

CHUNK = 0.05  # s of sim time between the run loop's checks
#: plant steps of accumulated contact after which a colliding pair is a collision of the run
#: (`tamp.sim.refine.contacts`: one step's graze is noise)
MIN_CONTACT_STEPS = 2


def time_limit(program: Program, architecture: Architecture, tune: bool) -> float:
    """Sim time after which the run stops: every motion twice at its rate, plus (tuning)
    every probe the searches could need."""
    total = 20.0 + 2.0 * sum(b.motion.nominal_time for _, _, b in program.behaviors())
    if tune:
        c = program.communication
        lowest = min(program.rate(b) for _, _, b in program.behaviors())
        probes = (c.sensor_rate_hz - lowest) / architecture.rate_step_hz + 1
        total += probes * architecture.probe_window
    return total


def simulate(
    program: Program,
    architecture: Architecture,
    *,
    tune: bool = False,
    max_sim_time: float | None = None,
    record: str | Path | None = None,
    scene: Scene | None = None,
    meshcat: Any = None,
) -> Run:
    """Build the station of ``program`` in its scene (``scene``: already loaded, else
    `load_scene` of ``program.scene``) and run it to the end (module docstring);
    ``meshcat``: draw the run there (a live view), else only a recording makes a viewer."""
    from tamp.sim.core.runner import make_simulator, run_in_chunks
    from tamp.sim.refine.outcome import measure, start_heights
    from tamp.sim.refine.station import build_station

    if scene is None:
        scene = load_scene(program.scene)
    if record is not None and meshcat is None:
        from tamp.sim.core.recording import new_meshcat

        meshcat = new_meshcat()
    cell = build_station(program, architecture, scene, tune=tune, meshcat=meshcat)
    simulator = make_simulator(cell.diagram)
    root = simulator.get_mutable_context()
    plant_ctx = cell.plant.GetMyContextFromRoot(root)
    ex_ctx = {n: e.GetMyContextFromRoot(root) for n, e in cell.machines.items()}
    sup_ctx = cell.supervisor.GetMyContextFromRoot(root)

    def between(t: float) -> bool:
        if tune:
            return cell.supervisor.state(sup_ctx).done
        return all(e.machine.progress_of(e.state(ex_ctx[n])).done for n, e in cell.machines.items())

    heights = start_heights(cell.plant, plant_ctx, cell.objects)
    if record is not None:
        from tamp.sim.core.recording import start_recording

        start_recording(cell.visualizer)
    limit = max_sim_time if max_sim_time is not None else time_limit(program, architecture, tune)
    chunked = run_in_chunks(simulator, chunk=CHUNK, limit=limit, between=between)
    recording = None
    if record is not None:
        from tamp.sim.core.recording import save_recording

        recording = save_recording(cell.visualizer, meshcat, record)
    outcome = measure(cell.plant, plant_ctx, cell.objects, heights, scene.goals)
    contacts = cell.monitor.log(cell.monitor.GetMyContextFromRoot(root))
    run = _result(
        cell,
        root,
        chunked,
        contacts.collisions(MIN_CONTACT_STEPS * cell.time_step),
        recording,
        outcome,
    )
    run.touches = dict(contacts.touches)
    run.diverged = chunked.diverged
    return run


def _result(cell: RefineStation, root, chunked, collisions, recording, outcome) -> Run:
    from tamp.sim.refine.station import search_of

    records = []
    rates = {}
    for name, e in cell.machines.items():
        s = e.state(e.GetMyContextFromRoot(root))
        records += e.machine.records(s)
        rates[name] = s.rate
    sup = cell.supervisor.state(cell.supervisor.GetMyContextFromRoot(root))
    return Run(
        program=cell.program,
        timeline=Timeline(tuple(records), rates),
        collisions=dict(collisions),
        searches=search_of(cell, root),
        max_wait={n: w.max_wait for n, w in sup.robots.items()},
        sensor_waits={
            f"{n}.{k}": v for n, w in sup.robots.items() for k, v in w.sensor_waits.items()
        },
        sim_time=chunked.sim_time,
        wall_time=chunked.wall_time,
        cpu_time=chunked.cpu_time,
        recording=recording,
        outcome=outcome,
    )


def perturbed_program(
    program: Program, perturbation: Perturbation, seed: int
) -> tuple[Program, Applied]:
    """``program`` with each robot's start moved by run ``seed``'s draw (nothing mutated)."""
    seed = check_seed(seed)
    sample = perturbation.sample(seed)
    applied = Applied(seed=seed)
    robots = []
    for r in program.robots:
        dx, dy, dyaw = sample.robot_offset(r.name)
        applied.robots[r.name] = (dx, dy, dyaw)
        x, y, yaw = r.start
        robots.append(dataclasses.replace(r, start=(x + dx, y + dy, yaw + dyaw)))
    return dataclasses.replace(program, robots=tuple(robots)), applied


@dataclass(kw_only=True)
class RefineResult(RunResult):
    """One seeded run of a program: the common `RunResult` and the measured `Run`."""

    run: Run | None = None
    run_satisfies_ordering: bool | None = None

    def details_json(self) -> dict[str, Any]:
        r = self.run
        if r is None:
            return {}
        return {
            "program": r.program.name,
            "category": r.program.communication.category,
            "run_satisfies_ordering": self.run_satisfies_ordering,
            "timeline": r.timeline.to_json()["behaviors"],
            "collisions": [[a, b, round(t, 3)] for (a, b), t in sorted(r.collisions.items())],
            "max_wait": {k: round(v, 5) for k, v in r.max_wait.items()},
            "outcome": r.outcome.to_json(),
        }

    def details_lines(self) -> list[str]:
        r = self.run
        if r is None:
            return []
        cat = r.program.communication.category
        lines = [f"program {r.program.name} (Category {cat})"]
        for rec in r.timeline.records:
            start = "-" if rec.start is None else f"{rec.start:.2f}"
            end = "never" if rec.end is None else f"{rec.end:.2f}"
            lines.append(f"  {rec.event:<22} {start:>8} .. {end:>8} s")
        if r.outcome.goals:
            lines.append(f"  outcome: {r.outcome.summary()}")
        for (a, b), t in sorted(r.collisions.items()):
            lines.append(f"  collision {a} with {b} at {t:.1f} s")
        return lines


def judge(
    program: Program, run: Run, check_run, reference: Run | None = None
) -> tuple[str, str | None, str, bool | None]:
    """(status, cause, reason, run_satisfies_ordering) of one run: TIMEOUT (cause
    ``timeout``) when some event never fired within the time limit; FAILURE when the
    measured event order breaks the ordering property (``order_violated``), when the
    scene's goal is not met on the plant (``goal_missed``) or when the run has a collision
    the ``reference`` run (the program as given, unperturbed; None: none to compare) did not
    have (``new_collision``); when the simulation diverged, FAILURE (``sim_diverged``); else
    SUCCESS."""
    from tamp.refine.refinement import new_collisions
    from tamp.sim.core.outcome import run_cause

    if run.diverged is not None:
        return "FAILURE", run_cause("FAILURE", ["sim_diverged"], False), run.diverged, None
    if not run.finished:
        stuck = ", ".join(r.event for r in run.timeline.records if r.end is None)
        return "TIMEOUT", run_cause("TIMEOUT", [], False), f"{stuck} never fired", None
    holds = check_run(program, run.timeline.order()).holds
    if not holds:
        cause = run_cause("FAILURE", ["order_violated"], False)
        return "FAILURE", cause, "the measured event order breaks the ordering property", False
    if not run.outcome.achieved:
        reason = "goal not met on the plant: " + "; ".join(run.outcome.failed())
        return "FAILURE", run_cause("FAILURE", ["goal_missed"], False), reason, True
    new = new_collisions(run, reference) if reference is not None else []
    if new:
        a, b, t = new[0]
        reason = f"a collision the unperturbed run did not have: {a} with {b} at {t:.1f} s"
        return "FAILURE", run_cause("FAILURE", ["new_collision"], False), reason, True
    return (
        "SUCCESS",
        None,
        "the goal is met, in an order the property allows, no new collision",
        True,
    )


#: the unperturbed run of each program a process has judged runs of (`RefineWorkcell.run`)
_REFERENCE: dict[tuple[Program, str | None], Run] = {}


def reference_run(program: Program, architecture: Architecture, scene: Scene) -> Run:
    """The run of ``program`` as given (no perturbation), simulated once per process: what a
    seeded run's collisions are compared with."""
    key = (program, architecture.file)
    if key not in _REFERENCE:
        _REFERENCE[key] = simulate(program, architecture, scene=scene)
    return _REFERENCE[key]


class RefineWorkcell:
    """The two-robot refinement workcell as a `tamp.sim.core.workcell.Workcell`: what
    ``tamp simulate refine`` and ``tamp campaign --kind refine`` run (one program as given;
    ``tamp refine`` runs the refinement)."""

    name = "refine"
    title = "two-robot refinement programs (Figueroa Heredia et al. 2018), one run as given"
    folder = "refine"
    key = "robots"
    main = Option(
        "program",
        "refinement program file or packaged name (task4)",
        flag="program",
        required=True,
        folder="refine",
    )
    options: tuple[Option, ...] = ()
    replay = "tamp simulate refine {scenario} --seed {seed}"

    def load(self, name_or_path: str | Path) -> RefineScenario:
        return load_scenario(name_or_path)

    def perturbed(self, scenario: RefineScenario, seed: int) -> tuple[RefineScenario, Applied]:
        program, applied = perturbed_program(scenario.program, scenario.program.perturbation, seed)
        return dataclasses.replace(scenario, program=program), applied

    def build(self, scenario: RefineScenario, *, tune: bool = False, meshcat: Any = None) -> Any:
        """The Drake Diagram of the scenario's program in its scene; its exported ports are
        listed in `tamp.sim.refine.station`. The run loop uses `build_station`, which also
        returns the handles it needs."""
        from tamp.sim.refine.station import build_station

        station = build_station(
            scenario.program, scenario.architecture, scenario.scene, tune=tune, meshcat=meshcat
        )
        return station.diagram

    def run(
        self,
        scenario: RefineScenario,
        *,
        seed: int = 0,
        record: str | Path | None = None,
        max_sim_time: float | None = None,
        verify: bool = True,
        meshcat: bool = False,
    ) -> RefineResult:
        """Gate the ordering property, perturb by ``seed``, simulate and judge (`judge`);
        ``meshcat``: draw the run in a local Meshcat (the command line's live view,
        `tamp.sim.core.recording.new_meshcat`)."""
        from tamp.verification.refine import check_run

        moved, applied = self.perturbed(scenario, seed)
        program = moved.program
        verified = {}
        if verify:
            from tamp.verification.gate import gate_program

            gate_program(program, subject=f"program {program.name}")
            verified["ordering"] = True
        run = simulate(
            program,
            moved.architecture,
            max_sim_time=max_sim_time,
            record=record,
            scene=moved.scene,
            **({"meshcat": _live_meshcat()} if meshcat else {}),
        )
        reference = run
        moved_robots = any(any(v) for v in applied.robots.values())
        if moved_robots and run.finished and run.outcome.achieved:  # else judged without it
            reference = reference_run(scenario.program, scenario.architecture, scenario.scene)
        status, cause, reason, holds = judge(program, run, check_run, reference)
        return RefineResult(
            workcell=self.name,
            scenario=program.file or program.name,
            status=status,
            reason=reason,
            cause=cause,
            task_time=run.task_time if run.finished else run.sim_time,
            sim_time=run.sim_time,
            wall_time=run.wall_time,
            cpu_time=run.cpu_time,
            seed=applied.seed,
            perturbation=applied.to_json(),
            recording=run.recording,
            verified=verified,
            run=run,
            run_satisfies_ordering=holds,
        )


WORKCELL = RefineWorkcell()


def _live_meshcat() -> Any:
    """The command line's live view (`tamp.sim.core.recording.new_meshcat`)."""
    from tamp.sim.core.recording import new_meshcat

    return new_meshcat()
