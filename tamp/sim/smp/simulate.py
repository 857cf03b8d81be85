"""SMP-MRO end to end in Drake: plan (RG + A*), verify, grow and tick the tree, simulate.

`prepare` runs the planning layers on the scenario's demonstration: the RG order under the
scenario's cost (SMP-MRO §IV-B, Alg. 1), C_goal for the tree (§IV-C, Alg. 2), and the
verification gate on both — the order against the LTL encoding of the constraints and every
execution of the tree over the symbolic domain (scripted appearances included, one skill
failure allowed). A failed check raises `verification.VerificationError` (exit 1) with the
counterexample, and nothing is simulated. `simulate_smp_mro` then builds the diagram around
the *same* tree object and runs it (optionally recording a Meshcat animation).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tamp.sim.smp.scenario import SimScenario


@dataclass
class Prepared:
    """The plan, the tree the executor will tick, and the verification reports."""

    scenario: SimScenario
    plan: Any  # tamp.rg.PlanResult
    policy: Any  # tamp.bt.PaBtExecutor
    reports: dict[str, Any] = field(default_factory=dict)
    verify_time: float = 0.0


def make_tree(scenario: SimScenario, plan) -> Any:
    """The PA-BT executor for the plan's C_goal (Alg. 2 l. 1-3), with the free areas."""
    from tamp.bt import PaBtExecutor

    demo = scenario.demo
    return PaBtExecutor(plan.c_goal, demo.domain(), free_areas=list(demo.free_areas))


def verification_events(scenario: SimScenario) -> list:
    """The scenario's appearances as symbolic events, for the tree's verification."""
    from tamp.bt import Appear

    return [
        Appear(o.id, scenario.place_of(o.appear)) for o in scenario.objects if o.appear is not None
    ]


def prepare(scenario: SimScenario, *, verify: bool = True) -> Prepared:
    """Plan, build the tree, and pass the verification gate (the hook before simulation)."""
    from tamp.rg import plan as rg_plan

    result = rg_plan(scenario.demo, scenario.planner.cost)
    tree = make_tree(scenario, result)
    prepared = Prepared(scenario, result, tree)
    if verify:
        from verification import gate

        t0 = time.perf_counter()
        prepared.reports["order"] = gate(result)
        probe = make_tree(scenario, result)  # the gate ticks a copy, never the real tree
        prepared.reports["tree"] = gate(
            probe, state=scenario.demo.initial_world(), events=verification_events(scenario)
        )
        prepared.verify_time = time.perf_counter() - t0
    return prepared


def simulate_smp_mro(
    scenario: SimScenario,
    *,
    seed: int = 0,
    verify: bool = True,
    meshcat: Any = None,
    record: str | Path | None = None,
    max_sim_time: float | None = None,
    realtime_rate: float = 0.0,
):
    """Plan, verify, build and run; returns (`SimResult`, `Prepared`, `SmpStation`).

    ``seed``: the run's draw of the scenario's perturbation (`tamp.sim.smp.perturb`); the
    same seed gives the same run, bit for bit on one machine (sim times, poses, actions).
    The plan and its verification use the nominal scenario (what the robot was shown).
    ``record``: write a self-contained Meshcat animation (HTML) of the run there
    (a local Meshcat server is started when ``meshcat`` is None).
    """
    from tamp.sim.core.recording import new_meshcat, save_recording, start_recording
    from tamp.sim.smp.perturb import perturb
    from tamp.sim.smp.runner import SimRunner
    from tamp.sim.smp.station import build_station

    prepared = prepare(scenario, verify=verify)
    scenario, applied = perturb(scenario, seed)
    if record is not None and meshcat is None:
        meshcat = new_meshcat()
    system = build_station(scenario, prepared.policy, meshcat=meshcat)
    runner = SimRunner(system, realtime_rate=realtime_rate)
    if record is not None:
        start_recording(system.visualizer)
    result = runner.run(max_sim_time=max_sim_time)
    result.seed = applied.seed
    result.perturbation = applied.to_json()
    if record is not None:
        result.recording = save_recording(system.visualizer, meshcat, record)
    return result, prepared, system


def run_seeded(
    scenario: str | Path,
    seed: int,
    *,
    verify: bool = True,
    max_sim_time: float | None = None,
    record: str | Path | None = None,
) -> dict[str, Any]:
    """ONE seeded run of the scenario file (or packaged name) ``scenario``, as the JSON of
    ``tamp simulate smp-mro --scenario S --seed N --json``: ``status``, ``cause`` (None on
    success, else `tamp.sim.core.outcome.CAUSES`), ``task_time`` (sim s), ``seed``,
    ``perturbation`` (the sample applied, its ``size``), ``wall_time``, ... The entry point
    of ``tamp campaign --kind smp-mro`` (picklable arguments, builds everything inside)."""
    from tamp.sim.smp.scenario import load_scenario, scenario_path

    loaded = load_scenario(scenario_path(scenario))
    result, prepared, _ = simulate_smp_mro(
        loaded, seed=seed, verify=verify, max_sim_time=max_sim_time, record=record
    )
    return run_json(result, prepared)


def run_json(result, prepared: Prepared) -> dict[str, Any]:
    """A run's JSON (``tamp simulate smp-mro --json``): the result, the order, the checks."""
    payload = result.to_json()
    payload["order"] = list(prepared.plan.order)
    payload["verified"] = {k: r.holds for k, r in prepared.reports.items()}
    return payload
