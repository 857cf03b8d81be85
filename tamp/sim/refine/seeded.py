"""Seeded runs of a refinement program (``tamp refine --seed N``, ``tamp campaign --kind
refine``): the program file's ``perturbation`` section (`tamp.perturbation`) drawn
for one seed and applied to the program.

The refinement workcell simulates the ``robot`` field only: each robot's start pose
``(x, y, yaw)`` is moved by its own draw (`PerturbationSample.robot_offset`, keyed by the
robot's name). The scene's objects are fixed by the scene (`tamp.sim.refine.scene`); a
section asking for more is refused naming the field. A start moved onto the object shows as
a collision or an unfinished run, which is what a perturbation is for.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from tamp.refine.program import Program
from tamp.perturbation import NONE, Applied, Perturbation, check_seed, read_perturbation

#: the ``perturbation`` fields this workcell simulates
PERTURBED = ("robot",)


def program_perturbation(program: Program) -> Perturbation:
    """The ``perturbation`` section of ``program``'s file (`NONE` without a file or one)."""
    if program.file is None:
        return NONE
    p = read_perturbation(program.file, kind="refinement program")
    p.require(PERTURBED, "refinement")
    return p


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
    from tamp.sim.refine.runner import simulate
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
