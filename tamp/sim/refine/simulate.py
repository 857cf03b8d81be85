"""The refinement workcell's runs: one program measured in simulation, and seeded runs.

`simulate` is the workcell's `tamp.refine.measure.Measure`: it builds the station of a
program in its scene and runs it to the end. The simulator advances in chunks
(`tamp.sim.core.runner.run_in_chunks`); between chunks the loop reads the plant's contact
results (SceneGraph's contact surfaces and point pairs; `RefineStation.collision` says
which are collisions: a robot's chassis or lever touching anything, a robot touching the
other robot or the fixed scenery), with the first time of each (Step 2 reverts a
parallelization that causes one), and stops when both state machines have fired every
event, or, in a tuning run, when the supervisor's searches have ended. Nothing is computed
from the program's numbers: start and end times are when the machines started behaviors
and fired events in sim time. At the end it measures what the objects did
(`tamp.sim.refine.outcome`: the chair's hinge angle, the scale's tilt) against the scene's
goals.

Seeded runs (``tamp refine --seed N``, campaigns): the program file's ``perturbation``
section (`Program.perturbation`, read by the loader) drawn for one seed and applied to the
program. The workcell simulates the ``robot`` field only (`PERTURBED`): each robot's start
pose ``(x, y, yaw)`` is moved by its own draw (`PerturbationSample.robot_offset`, keyed by
the robot's name). The scene's objects lie where the scene puts them; a section asking for
more is refused naming the field. A start moved onto the object shows as a collision or an
unfinished run, which is what a perturbation is for.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from tamp.perturbation import Applied, Perturbation, check_seed
from tamp.refine.architecture import Architecture
from tamp.refine.measure import Run
from tamp.refine.program import Program
from tamp.refine.timeline import Timeline
from tamp.sim.core.runner import make_simulator, run_in_chunks
from tamp.sim.refine.outcome import measure, start_heights
from tamp.sim.refine.scenario import Scene, load_scene
from tamp.sim.refine.station import RefineStation, build_station, search_of

CHUNK = 0.05  # s of sim time between the run loop's checks
#: the ``perturbation`` fields this workcell simulates
PERTURBED = ("robot",)


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
) -> Run:
    """Build the station of ``program`` in its scene (``scene``: already loaded, else
    `load_scene` of ``program.scene``) and run it to the end (module docstring)."""
    if scene is None:
        scene = load_scene(program.scene)
    meshcat = None
    if record is not None:
        from tamp.sim.core.recording import new_meshcat

        meshcat = new_meshcat()
    cell = build_station(program, architecture, scene, tune=tune, meshcat=meshcat)
    simulator = make_simulator(cell.diagram)
    root = simulator.get_mutable_context()
    plant_ctx = cell.plant.GetMyContextFromRoot(root)
    ex_ctx = {n: e.GetMyContextFromRoot(root) for n, e in cell.executors.items()}
    sup_ctx = cell.supervisor.GetMyContextFromRoot(root)
    collisions: dict[tuple[str, str], float] = {}
    contacts = cell.plant.get_contact_results_output_port()

    inspector = None

    def body_of(geometry) -> int:
        return int(cell.plant.GetBodyFromFrameId(inspector.GetFrameId(geometry)).index())

    def between(t: float) -> bool:
        nonlocal inspector
        results = contacts.Eval(plant_ctx)
        pairs = []
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            pairs.append((int(info.bodyA_index()), int(info.bodyB_index())))
        if results.num_hydroelastic_contacts():
            if inspector is None:
                query = cell.plant.get_geometry_query_input_port().Eval(plant_ctx)
                inspector = query.inspector()
            for i in range(results.num_hydroelastic_contacts()):
                surface = results.hydroelastic_contact_info(i).contact_surface()
                pairs.append((body_of(surface.id_M()), body_of(surface.id_N())))
        for a, b in pairs:
            key = cell.collision(a, b)
            if key is not None:
                collisions.setdefault(key, t)
        if tune:
            return cell.supervisor.state(sup_ctx).done
        return all(
            e.machine.progress_of(e.state(ex_ctx[n])).done for n, e in cell.executors.items()
        )

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
    return _result(cell, root, chunked, collisions, recording, outcome)


def _result(cell: RefineStation, root, chunked, collisions, recording, outcome) -> Run:
    records = []
    rates = {}
    for name, e in cell.executors.items():
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
        sim_time=chunked.sim_time,
        wall_time=chunked.wall_time,
        cpu_time=chunked.cpu_time,
        recording=recording,
        outcome=outcome,
    )


def program_perturbation(program: Program) -> Perturbation:
    """``program``'s ``perturbation`` section, refused (`InputError` naming the field) when
    it asks for what this workcell does not simulate."""
    program.perturbation.require(PERTURBED, "refinement")
    return program.perturbation


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


def run_seeded(
    program: str | Path,
    seed: int,
    *,
    verify: bool = True,
    max_sim_time: float | None = None,
    record: str | None = None,
) -> dict[str, Any]:
    """ONE seeded simulation of the program file (or packaged name) ``program`` as given
    (no refinement): ``status`` (SUCCESS when every event fired and the measured event order
    satisfies the ordering property; TIMEOUT when some event never fired within the time
    limit; FAILURE when the order breaks the property), ``cause``, ``task_time`` (sim s;
    the time limit when unfinished), ``seed``, ``perturbation``, ``wall_time``,
    ``collisions``. The entry point of ``tamp campaign --kind refine``."""
    from tamp.refine.architecture import default_architecture, load_architecture
    from tamp.refine.loader import load_program
    from tamp.sim.core.outcome import run_cause
    from verification.refine import check_run

    loaded = load_program(program)
    arch = load_architecture(loaded.architecture) if loaded.architecture else default_architecture()
    moved, applied = perturbed_program(loaded, program_perturbation(loaded), seed)
    if verify:
        from verification.gate import gate_program

        gate_program(moved, subject=f"program {moved.name}")
    run = simulate(moved, arch, max_sim_time=max_sim_time, record=record)
    holds = check_run(moved, run.timeline.order()).holds if run.finished else None
    if not run.finished:
        status = "TIMEOUT"
    elif holds:
        status = "SUCCESS"
    else:
        status = "FAILURE"
    cause = run_cause(status, ["order_violated"] if holds is False else [], False)
    return {
        "program": moved.name,
        "status": status,
        "cause": cause,
        "task_time": round(run.task_time if run.finished else run.sim_time, 3),
        "sim_time": round(run.sim_time, 3),
        "wall_time": round(run.wall_time, 3),
        "run_satisfies_ordering": holds,
        "collisions": [[a, b, round(t, 3)] for (a, b), t in sorted(run.collisions.items())],
        "seed": applied.seed,
        "perturbation": applied.to_json(),
        "recording": run.recording,
    }
