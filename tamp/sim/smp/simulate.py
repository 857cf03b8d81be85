"""SMP-MRO end to end in Drake: plan (RG + A*), verify, grow and tick the tree, simulate.

`prepare` runs the planning layers on the scenario's demonstration: the RG order under the
scenario's cost (SMP-MRO §IV-B, Alg. 1), C_goal for the tree (§IV-C, Alg. 2), and the
verification gate on both — the order against the LTL encoding of the constraints and every
execution of the tree over the symbolic domain (scripted appearances included, one skill
failure allowed). A failed check raises `verification.VerificationError` (exit 1) with the
counterexample, and nothing is simulated. `simulate` then draws the seed's perturbation,
builds the diagram around the *same* tree object and runs it (optionally recording a
Meshcat animation). `SmpMroWorkcell` is the cell's `tamp.sim.core.workcell.Workcell`
(``WORKCELL``): its options, ``load`` (a scenario file or packaged case, with ``--appear`` /
``--fail``), ``perturbed``, ``build`` and ``run``. Drake is imported only inside functions,
so listing the workcells builds nothing.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tamp.errors import InputError
from tamp.sim.core.models import DETECTORS
from tamp.sim.core.workcell import Option

if TYPE_CHECKING:  # imported where used: listing the workcells (`tamp --help`) stays light
    from tamp.sim.smp.runner import SimResult
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


def prepare(
    scenario: SimScenario, *, verify: bool = True, verify_budget: int | None = None
) -> Prepared:
    """Plan, build the tree, and pass the verification gate (the hook before simulation);
    ``verify_budget``: the states the tree gate may explore before its verdict is unknown
    (refused, exit 1; default `tamp.verification.bt.DEFAULT_MAX_STATES`)."""
    from tamp.rg import plan as rg_plan

    result = rg_plan(scenario.demo, scenario.planner.cost)
    tree = make_tree(scenario, result)
    prepared = Prepared(scenario, result, tree)
    if verify:
        from tamp.verification import gate

        t0 = time.perf_counter()
        prepared.reports["order"] = gate(result)
        probe = make_tree(scenario, result)  # the gate ticks a copy, never the real tree
        prepared.reports["tree"] = gate(
            probe,
            state=scenario.demo.initial_world(),
            events=verification_events(scenario),
            budget=verify_budget,
        )
        prepared.verify_time = time.perf_counter() - t0
    return prepared


def simulate(
    scenario: SimScenario,
    *,
    seed: int = 0,
    record: str | Path | None = None,
    max_sim_time: float | None = None,
    verify: bool = True,
    verify_budget: int | None = None,
    meshcat: Any = None,
    realtime_rate: float = 0.0,
    progress: Any = None,
) -> SimResult:
    """Plan, verify, perturb by ``seed``, build and run ``scenario`` (module docstring).

    ``seed``: the run's draw of the scenario's perturbation (`tamp.sim.smp.perturb`); the
    same seed gives the same run, bit for bit on one machine (sim times, poses, actions).
    The plan and its verification use the nominal scenario (what the robot was shown).
    ``record``: write a self-contained Meshcat animation (HTML) of the run there (a local
    Meshcat server is started when ``meshcat`` is None). ``realtime_rate``: 0 runs as fast
    as possible, 1.0 paces a live Meshcat view. ``progress(t, runner)``: called between
    simulator chunks with the sim time and the `SimRunner` (robot pose, executor state), for
    live views; an exception it raises ends the run there.
    """
    from tamp.sim.core.recording import new_meshcat, save_recording, start_recording
    from tamp.sim.smp.perturb import perturb
    from tamp.sim.smp.runner import SimRunner
    from tamp.sim.smp.station import build_station

    prepared = prepare(scenario, verify=verify, verify_budget=verify_budget)
    run_scenario, applied = perturb(scenario, seed)
    if record is not None and meshcat is None:
        meshcat = new_meshcat()
    system = build_station(run_scenario, prepared.policy, meshcat=meshcat)
    runner = SimRunner(system, realtime_rate=realtime_rate)
    if record is not None:
        start_recording(system.visualizer)
    on_chunk = None if progress is None else (lambda t: progress(t, runner))
    result = runner.run(max_sim_time=max_sim_time, on_chunk=on_chunk)
    result.seed = applied.seed
    result.perturbation = applied.to_json()
    result.order = list(prepared.plan.order)
    result.verified = {k: r.holds for k, r in prepared.reports.items()}
    if record is not None:
        result.recording = save_recording(system.visualizer, meshcat, record)
    return result


class SmpMroWorkcell:
    """The SMP-MRO youBot workcell as a `tamp.sim.core.workcell.Workcell`: what ``tamp
    simulate smp-mro`` and ``tamp campaign --kind smp-mro`` run."""

    name = "smp-mro"
    title = "SMP-MRO cases 1-3 (youBot pick-and-place)"
    folder = "sim"
    key = "demonstration"
    main = Option(
        "scenario",
        "simulation scenario file or packaged name (overrides --case)",
        flag="scenario",
        metavar="SCENARIO",
        folder="sim",
    )
    options = (
        Option(
            "case",
            "packaged case, when no SCENARIO is given (default 1)",
            type=int,
            choices=(1, 2, 3),
        ),
        Option(
            "appear",
            "an object is put at PLACE (area name or x,y[,z] in the robot frame) at WHEN "
            "(tick, t=SECONDS or after:Action(args)); without WHEN when the robot reaches it. "
            "Overrides the file's entry for that object",
            action="append",
            metavar="OBJ@PLACE[@WHEN]",
        ),
        Option(
            "fail",
            "scripted skill failure: the first TIMES attempts fail, e.g. Pick(O1) or Pick(O1)x2",
            action="append",
            metavar="ACTION[(ARGS)][xTIMES]",
        ),
        Option(
            "detector",
            "what reads the mast camera's views (perception: camera): the renderer's labels as "
            "a perfect detector or the learned detector (default: the scenario's detector)",
            choices=DETECTORS,
        ),
        Option(
            "verify_budget",
            "states the tree gate may explore before its verdict is unknown (exit 1) "
            "(default 200000)",
            stage="run",
            type=int,
            metavar="N",
        ),
        Option(
            "rate",
            "target real-time rate (default: as fast as possible; 1.0 with --meshcat)",
            stage="run",
            type=float,
        ),
    )
    replay = "tamp simulate smp-mro {scenario} --seed {seed}"

    def load(
        self,
        name_or_path: str | Path | None = None,
        *,
        case: int | None = None,
        appear: Sequence[str] = (),
        fail: Sequence[str] = (),
        detector: str | None = None,
    ) -> SimScenario:
        """The scenario file (or packaged name; none: packaged case ``case``, default 1)
        with the ``--appear`` / ``--fail`` entries applied (`SimScenario.with_events`) and
        read by ``detector`` (None: the file's; `with_detector`)."""
        from tamp.sim.smp.scenario import load_scenario, with_detector
        from tamp.world.events import check_events, parse_appear, parse_fail

        scenario = load_scenario(name_or_path or f"case{case or 1}")
        if appear or fail:
            flags = [parse_appear(text, field="--appear") for text in appear or ()]
            fails = [parse_fail(text, field="--fail") for text in fail or ()]
            demo = scenario.demo
            check_events(
                flags,
                fails,
                objects=[o.id for o in scenario.objects],
                areas=demo.initial_world().areas,
                domain=demo.domain(),
            )
            scenario = scenario.with_events(flags, fails)
        if detector is not None:
            scenario = with_detector(scenario, detector)
        return scenario

    def perturbed(self, scenario: SimScenario, seed: int) -> tuple[SimScenario, Any]:
        from tamp.sim.smp.perturb import perturb

        return perturb(scenario, seed)

    def build(self, scenario: SimScenario, *, policy: Any = None, meshcat: Any = None) -> Any:
        """The Drake Diagram of ``scenario`` around ``policy`` (default: its planned tree,
        unverified); its exported ports are listed in `tamp.sim.smp.station`. The run loop
        uses `build_station`, which also returns the handles it needs."""
        from tamp.sim.smp.station import build_station

        if policy is None:
            policy = prepare(scenario, verify=False).policy
        return build_station(scenario, policy, meshcat=meshcat).diagram

    def run(
        self,
        scenario: SimScenario,
        *,
        seed: int = 0,
        record: str | Path | None = None,
        max_sim_time: float | None = None,
        verify: bool = True,
        meshcat: bool = False,
        rate: float | None = None,
        verify_budget: int | None = None,
    ) -> SimResult:
        """`simulate`; ``meshcat``: a live local Meshcat (its URL logged), ``rate``: the
        real-time rate (>= 0; default 1.0 with ``meshcat``, else as fast as possible)."""
        if rate is not None and not (math.isfinite(rate) and rate >= 0):
            raise InputError(f"must be >= 0 (0: as fast as possible), got {rate}", field="--rate")
        if verify_budget is not None and verify_budget < 1:
            raise InputError(f"must be >= 1, got {verify_budget}", field="--verify-budget")
        viewer = None
        if meshcat:
            from tamp.sim.core.recording import new_meshcat

            viewer = new_meshcat()
            logging.getLogger("tamp").info("meshcat: %s", viewer.web_url())
        return simulate(
            scenario,
            seed=seed,
            record=record,
            max_sim_time=max_sim_time,
            verify=verify,
            verify_budget=verify_budget,
            meshcat=viewer,
            realtime_rate=rate if rate is not None else (1.0 if meshcat else 0.0),
        )


WORKCELL = SmpMroWorkcell()
