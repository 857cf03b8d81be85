"""Runs one program in the workcell and measures it: a `Run` with the `Timeline`.

The simulator advances in chunks (`tamp.sim.core.runner.run_in_chunks`); between chunks
the runner reads the plant's contact results (SceneGraph's contact surfaces and point
pairs; `Workcell.collision` says which are collisions: a robot's chassis or lever touching
anything, a robot touching the other robot or the fixed scenery), with the first time of
each (Step 2 reverts a parallelization that causes one), and stops when both executors
have fired every event, or, in a tuning run, when the supervisor's searches have ended.
Nothing is computed from the program's numbers: start and end times are when the
executors started behaviors and fired events in sim time. At the end it measures what
the objects did (`tamp.sim.refine.outcome`: the chair's hinge angle, the scale's tilt).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from tamp.refine.architecture import Architecture
from tamp.refine.program import Program
from tamp.refine.steps import RateSearch
from tamp.refine.timeline import Timeline
from tamp.sim.core.runner import make_simulator, run_in_chunks
from tamp.sim.refine.builder import Workcell, build_workcell, search_of
from tamp.sim.refine.outcome import Outcome, measure, start_heights

CHUNK = 0.05  # s of sim time between the runner's checks


@dataclass
class Run:
    """One simulated execution of a program."""

    program: Program
    timeline: Timeline
    collisions: dict[tuple[str, str], float] = field(default_factory=dict)
    searches: dict[str, RateSearch | None] = field(default_factory=dict)
    max_wait: dict[str, float] = field(default_factory=dict)  # robot -> longest sensor wait
    sim_time: float = 0.0
    wall_time: float = 0.0
    cpu_time: float = 0.0
    recording: str | None = None
    outcome: Outcome = field(default_factory=Outcome)  # what the objects did (the plant's)

    @property
    def finished(self) -> bool:
        return self.timeline.finished

    @property
    def task_time(self) -> float:
        return self.timeline.task_time

    @property
    def realtime_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf

    def found_rates(self) -> dict[str, float]:
        return {n: s.found for n, s in self.searches.items() if s is not None and s.done}


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
) -> Run:
    """Build the workcell of ``program`` and run it to the end (module docstring)."""
    meshcat = None
    if record is not None:
        from tamp.sim.core.recording import new_meshcat

        meshcat = new_meshcat()
    cell = build_workcell(program, architecture, tune=tune, meshcat=meshcat)
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
    outcome = measure(cell.plant, plant_ctx, cell.objects, heights, cell.program.scene)
    return _result(cell, root, chunked, collisions, recording, outcome)


def _result(cell: Workcell, root, chunked, collisions, recording, outcome) -> Run:
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
