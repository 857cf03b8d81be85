"""ADAPTER (issue 18), to be deleted: one-run functions over today's simulate functions.

The perturbation work adds, per workcell, ``run_seeded(scenario, seed, **options) -> dict``
(seeded perturbations of poses, friction, sensor noise, timing). Until it is on main these
wrappers give the campaign the same contract (`tamp.campaign.kinds`): ``simulate_lots``
already takes the seed (its tree update); the SMP-MRO and refinement simulations are
deterministic and ignore it, with perturbation size 0. Switch `tamp.campaign.kinds.KINDS`
to the real functions and delete this module.

Each ``check_*`` loads and validates the file on the driver (an `InputError` is exit 2
before any run starts); each ``run_*`` loads it again where it runs, then simulates.
"""

from __future__ import annotations

from typing import Any


def _result(status: str, cause: str | None, task_time: float, seed: int, **extra) -> dict:
    return {
        "status": status,
        "cause": cause,
        "task_time": round(task_time, 3),
        "seed": seed,
        "perturbation": 0.0,
        **extra,
    }


def check_smp_mro(scenario: str) -> None:
    from tamp.sim.smp.scenario import load_scenario

    load_scenario(scenario)


def run_smp_mro(
    scenario: str, seed: int, *, record: str | None = None, max_sim_time: float | None = None
) -> dict[str, Any]:
    """One SMP-MRO run (plan, verification gate, Drake); the seed is not used yet."""
    from tamp.sim.smp.scenario import load_scenario
    from tamp.sim.smp.simulate import simulate_smp_mro

    result, _, _ = simulate_smp_mro(
        load_scenario(scenario), record=record, max_sim_time=max_sim_time
    )
    cause = None if result.ok else result.reason
    return {**result.to_json(), **_result(result.status, cause, result.sim_time, seed)}


def _lots_inputs(scenario: str):
    from tamp.lots.task import load_task
    from tamp.sim.lots.scenario import load_cell_scenario

    task = load_task(scenario)
    return task, load_cell_scenario(task.name)


def check_lots(scenario: str, interference: str | None = None) -> None:
    from tamp.errors import InputError
    from tamp.lots.task import load_events
    from tamp.sim.lots.simulate import check_matches

    task, cell = _lots_inputs(scenario)
    check_matches(task, cell)
    if interference:  # as `tamp simulate lots --interference` today
        load_events(interference, task)
        raise InputError("not yet simulated in the Drake workcell", field="--interference")


def run_lots(
    scenario: str,
    seed: int,
    *,
    record: str | None = None,
    max_sim_time: float | None = None,
    interference: str | None = None,
) -> dict[str, Any]:
    """One LOTS workcell run of the task ``scenario`` in its packaged cell; ``seed`` seeds
    the controller's tree update (what ``tamp simulate lots --seed`` does today)."""
    from tamp.lots.task import load_events
    from tamp.sim.lots.simulate import simulate_lots
    from verification import gate

    task, cell = _lots_inputs(scenario)
    events = load_events(interference, task) if interference else None
    result = simulate_lots(
        cell, task, events, seed=seed, record=record, max_sim_time=max_sim_time, check=gate
    )
    if result.satisfied:
        status, cause = "SUCCESS", None
    else:  # the controller's SUCCESS with a plant that disagrees is a FAILURE
        status = "FAILURE" if result.status == "SUCCESS" else result.status
        cause = result.reason
    return {**result.to_json(), **_result(status, cause, result.sim_time, seed)}


def _refine_inputs(scenario: str):
    from tamp.refine.architecture import default_architecture, load_architecture
    from tamp.refine.loader import load_program

    program = load_program(scenario)
    arch = (
        load_architecture(program.architecture) if program.architecture else default_architecture()
    )
    return program, arch


def check_refine(scenario: str) -> None:
    _refine_inputs(scenario)


def run_refine(
    scenario: str, seed: int, *, record: str | None = None, max_sim_time: float | None = None
) -> dict[str, Any]:
    """One run of the program as given (the refinement's "original" phase), behind its
    ordering gate; SUCCESS when every event fired in an order that keeps the property."""
    from tamp.sim.refine.runner import simulate
    from verification.gate import gate_program
    from verification.refine import check_run

    program, arch = _refine_inputs(scenario)
    gate_program(program, subject=f"program {program.name}")
    run = simulate(program, arch, record=record, max_sim_time=max_sim_time)
    if not run.finished:
        stuck = [r.event for r in run.timeline.records if r.end is None]
        status, cause = "TIMEOUT", f"never fired: {', '.join(stuck)}"
    elif not check_run(program, run.timeline.order()).holds:
        status, cause = "FAILURE", "the measured event order breaks the ordering property"
    else:
        status, cause = "SUCCESS", None
    task_time = run.task_time if run.finished else run.sim_time
    return _result(
        status, cause, task_time, seed, recording=run.recording, collisions=len(run.collisions)
    )
