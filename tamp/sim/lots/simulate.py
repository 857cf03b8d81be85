"""``tamp simulate lots``: a LOTS task run by the LOTS controller inside the Drake workcell.

    build_lots_diagram: the workcell station (`build_station`) as a subsystem, and
      LotsControllerSystem:  cell.observation, cell.skill_status ─► controller
                             controller.skill_command ─► cell.skill_command

`simulate_lots` checks that the task and the cell scenario start from the same objects,
builds the controller (its initial table passes the verification gate before anything
moves), simulates in chunks until the controller stops or the time limit, and measures the
result on the plant: counts per class in W^A, W^B and the waste basket from the objects'
poses. The task counts as satisfied only when the controller completed its round and the
plant's W^B is a W^B state that ends a round of the task (`Lots.is_goal`: the same verdict
as ``tamp lots``, which applies it to its symbolic ground truth).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from pydrake.systems.framework import Diagram, DiagramBuilder

from tamp.errors import InputError
from tamp.lots.controller import ActionRecord, LotsController
from tamp.lots.task import Event, Task
from tamp.sim.core.executor import ActionLog
from tamp.sim.core.recording import new_meshcat, save_recording, start_recording
from tamp.sim.core.runner import make_simulator, run_in_chunks
from tamp.sim.lots.controller_system import PERIOD, LotsControllerSystem
from tamp.sim.lots.person import (
    REACTION,
    RESTING_Z,
    STAGING,
    PersonAction,
    on_shelf,
    reaction_time,
    slot_key,
)
from tamp.sim.lots.safety import SafetyStop
from tamp.sim.lots.scenario import (
    BASKET_HALF,
    DEFAULT_WEIGHTS,
    NETWORKS,
    CellScenario,
    perturbed,
)
from tamp.sim.lots.station import LotsStation, build_station
from tamp.world.interface import Status

#: how far the simulator runs between checks of the controller's result (sim s)
CHUNK = 0.5
#: after the controller's result, how long the person may take to finish its trip (sim s)
PERSON_GRACE = 15.0


@dataclass
class LotsDiagram:
    """The workcell with the LOTS controller wired in."""

    diagram: Diagram
    cell: LotsStation
    controller: LotsControllerSystem


def build_lots_diagram(
    scenario: CellScenario,
    controller: LotsController,
    *,
    meshcat: Any = None,
    period=PERIOD,
    person: Sequence[Event] | None = None,
) -> LotsDiagram:
    """The cell diagram of ``scenario`` driven by ``controller`` (observation and skill status
    in, skill command out: nothing else reaches the controller). ``person``: interference
    events a scripted person carries out in the cell (`tamp.sim.lots.person`)."""
    cell = build_station(scenario, meshcat=meshcat, person=person)
    builder = DiagramBuilder()
    sub = builder.AddSystem(cell.diagram)
    ctrl = builder.AddSystem(LotsControllerSystem(controller, period=period))
    builder.Connect(sub.GetOutputPort("observation"), ctrl.observation_port)
    builder.Connect(sub.GetOutputPort("skill_status"), ctrl.skill_status_port)
    builder.Connect(ctrl.command_port, sub.GetInputPort("skill_command"))
    diagram = builder.Build()
    diagram.set_name(f"lots_{scenario.name}")
    return LotsDiagram(diagram, cell, ctrl)


@dataclass
class LotsSimResult:
    """A finished workcell run: verdict, skill log (sim times), robot actions, measurements."""

    task: str
    scenario: str
    status: str  # SUCCESS | FAILURE | TIMEOUT (the controller's result, or no result in time)
    reason: str
    satisfied: bool
    actions: list[ActionLog]
    robot_actions: list[ActionRecord]
    replans: int
    frames_rendered: int
    grasps: dict[str, int]
    sim_time: float
    wall_time: float
    final_counts: dict[str, dict[str, int]]
    elsewhere: list[str] = field(default_factory=list)  # objects in no workspace nor basket
    network: str = "hrgnet"
    recording: str | None = None
    safety_stops: list[SafetyStop] = field(default_factory=list)
    seed: int = 0
    perturbation: dict | None = None  # `tamp.perturbation.Applied.to_json()`

    @property
    def cause(self) -> str | None:
        """Why the run failed, one of `tamp.sim.core.outcome.CAUSES` (None when satisfied)."""
        return lots_cause(self)

    person_actions: list[PersonAction] = field(default_factory=list)
    never_happened: list[Event] = field(default_factory=list)  # scripted, run ended first

    @property
    def rtf(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else float("inf")

    @property
    def exit_code(self) -> int:
        return 0 if self.satisfied else 1

    def to_json(self) -> dict[str, Any]:
        return {
            "task": self.task,
            "scenario": self.scenario,
            "grasp": self.network,
            "status": self.status,
            "reason": self.reason,
            "satisfied": self.satisfied,
            "actions": [a.to_json() for a in self.actions],
            "robot_actions": [a.to_json() for a in self.robot_actions],
            "replans": self.replans,
            "safety_stops": [stop.to_json() for stop in self.safety_stops],
            "frames_rendered": self.frames_rendered,
            "grasps": dict(self.grasps),
            "sim_time": round(self.sim_time, 3),
            "wall_time": round(self.wall_time, 3),
            "rtf": round(self.rtf, 3),
            "final_counts": self.final_counts,
            "elsewhere": self.elsewhere,
            "person_actions": [a.to_json() for a in self.person_actions],
            "never_happened": [e.never_happened() for e in self.never_happened],
            "recording": self.recording,
            "cause": self.cause,
            "task_time": round(self.sim_time, 3),
            "seed": self.seed,
            "perturbation": self.perturbation,
        }


def scenario_counts(scenario: CellScenario) -> dict[str, dict[str, int]]:
    """Counts per class in W^A and W^B at the start of ``scenario``."""
    out: dict[str, dict[str, int]] = {side: {} for side in scenario.workspaces}
    for o in scenario.objects:
        out[o.workspace][o.cls] = out[o.workspace].get(o.cls, 0) + 1
    return out


def check_matches(task: Task, scenario: CellScenario) -> None:
    """The task's initial counts must be the scene's (`InputError` naming the scenario)."""
    have = scenario_counts(scenario)
    for side, want in (("A", task.initial_a), ("B", task.initial_b)):
        want = {k: v for k, v in want.items() if v}
        if have.get(side, {}) != want:
            raise InputError(
                f"W^{side} holds {have.get(side, {})} but task {task.name!r} "
                f"({task.file}) starts from {want}",
                file=scenario.source,
                field="objects",
            )


def with_network(scenario: CellScenario, network: str | None) -> CellScenario:
    """``scenario`` with grasp network ``network`` (None: the scenario's own)."""
    if network is None or network == scenario.grasp.network:
        return scenario
    if network not in NETWORKS:
        raise InputError(f"unknown network {network!r} (known: {list(NETWORKS)})", field="--grasp")
    if network not in DEFAULT_WEIGHTS:
        raise InputError(
            f"no shipped weights for {network!r} yet (shipped: {sorted(DEFAULT_WEIGHTS)})",
            field="--grasp",
        )
    grasp = dataclasses.replace(scenario.grasp, network=network, weights=None)
    return dataclasses.replace(scenario, grasp=grasp)


def plant_counts(cell: LotsStation, plant_context) -> tuple[dict[str, dict[str, int]], list[str]]:
    """Counts per class in W^A, W^B and the waste basket from the objects' plant poses, and
    the objects lying in none of them (held, on the floor, elsewhere on the table)."""
    plant, scenario = cell.plant, cell.scenario
    counts: dict[str, dict[str, int]] = {"A": {}, "B": {}, "waste": {}}
    if cell.cell.staged:
        counts[STAGING] = {}
    elsewhere = []
    bx, by = scenario.waste_basket
    for uid, body in sorted(cell.cell.bodies.items()):
        p = plant.EvalBodyPoseInWorld(plant_context, body).translation()
        x, y, z = (float(v) for v in p)
        where = None
        for side, w in scenario.workspaces.items():
            if z < RESTING_Z and w.contains(x, y):
                where = side
        if abs(x - bx) <= BASKET_HALF and abs(y - by) <= BASKET_HALF and z < RESTING_Z:
            where = "waste"
        if cell.cell.staged and on_shelf(x, y, z):
            where = STAGING
        if where is None:
            elsewhere.append(uid)
            continue
        cls = cell.cell.classes[uid]
        counts[where][cls] = counts[where].get(cls, 0) + 1
    return counts, elsewhere


def simulate_lots(
    scenario: CellScenario,
    task: Task,
    interference: Any = None,
    *,
    grasp: str | None = None,
    seed: int = 0,
    record: str | None = None,
    meshcat: Any = None,
    max_sim_time: float | None = None,
    check=None,
) -> LotsSimResult:
    """Run ``task`` in the workcell of ``scenario`` (see the module docstring).

    ``check``: the verification gate (`verification.gate`), called on every table before it
    is used; what it raises propagates. ``interference``: the events of an interference file
    (`tamp.lots.task.load_events`), carried out by a scripted person's hand; the run then
    also waits (at most `PERSON_GRACE` s) for the person to finish what it started.
    """
    scenario, applied = perturbed(scenario, seed)  # the run's draw of its perturbation
    scenario = with_network(scenario, grasp)
    check_matches(task, scenario)
    events = list(interference) if interference else None
    if events:
        check_person_classes(events, scenario)
        for n, phase in sorted({(e.after, e.phase) for e in events}):  # the drawn reactions
            if scenario.perturbation.timing_jitter > 0:
                shift = reaction_time(scenario.sample, n, phase) - REACTION
                applied.timing[slot_key(n, phase)] = shift
    controller = LotsController(task, seed=seed, check=check)  # the gate runs here
    if record and meshcat is None:
        meshcat = new_meshcat()
    built = build_lots_diagram(scenario, controller, meshcat=meshcat, person=events)
    if record:
        start_recording(built.cell.visualizer)
    simulator = make_simulator(built.diagram)
    context = simulator.get_mutable_context()
    ctrl = built.controller
    ctrl_context = ctrl.GetMyContextFromRoot(context)

    person = built.cell.person
    person_context = None if person is None else person.GetMyContextFromRoot(context)

    def finished(t: float) -> bool:
        s = ctrl.state(ctrl_context)
        if s.result is None:
            return False
        if person is None or s.finished_at is None or t > s.finished_at + PERSON_GRACE:
            return True
        return person.state(person_context).idle  # let the person put down what it holds

    limit = max_sim_time if max_sim_time is not None else scenario.max_sim_time
    t0 = time.perf_counter()
    run = run_in_chunks(simulator, chunk=CHUNK, limit=limit, between=finished)
    wall = time.perf_counter() - t0
    cell = built.cell
    s = ctrl.state(ctrl_context)
    counts, elsewhere = plant_counts(cell, cell.plant.GetMyContextFromRoot(context))
    c = s.controller
    status = s.result.value if s.result is not None else "TIMEOUT"
    reason = s.reason if s.result is not None else f"no result within {limit:g} s of sim time"
    truth = c.lots.vector(counts["B"])
    satisfied = s.result is Status.SUCCESS and c.lots.is_goal(truth)
    if s.result is Status.SUCCESS and not satisfied:
        reason = (
            f"the controller completed its round, but the plant's W^B holds "
            f"{c.lots.format(truth)}, which ends no round of the task "
            f"(planned: {c.lots.format(c.lots.final)})"
        )
    skills = cell.skills.state(cell.skills.GetMyContextFromRoot(context))
    perception = cell.perception.state(cell.perception.GetMyContextFromRoot(context))
    recording = save_recording(cell.visualizer, meshcat, record) if record else None
    frames, stops = perception.frames, []
    if cell.safety is not None:  # the monitor's own renders count too (none without a hand)
        safety = cell.safety.state(cell.safety.GetMyContextFromRoot(context))
        frames, stops = frames + safety.frames, safety.all_stops(context.get_time())
    ps = None if person is None else person.state(person_context)
    return LotsSimResult(
        task=task.name,
        scenario=scenario.name,
        status=status,
        reason=reason,
        satisfied=satisfied,
        actions=list(s.log),
        robot_actions=list(c.actions),
        replans=c.replans,
        frames_rendered=frames,
        grasps={"attempts": skills.grasp_attempts, "successes": skills.grasp_successes},
        sim_time=run.sim_time,
        wall_time=wall,
        final_counts=counts,
        elsewhere=elsewhere,
        network=scenario.grasp.network,
        recording=recording,
        safety_stops=stops,
        seed=applied.seed,
        perturbation=applied.to_json(),
        person_actions=[] if ps is None else list(ps.actions),
        never_happened=[] if ps is None else ps.script.unfired(),
    )


def lots_cause(result: LotsSimResult) -> str | None:
    """The run's cause (`tamp.sim.core.outcome.run_cause`): the cause the last failed skill
    reported (`SkillStatus.cause`), ``placement_off`` when the controller finished but the
    plant's W^B ends no round."""
    from tamp.sim.core.outcome import run_cause

    if result.satisfied:
        return None
    causes = [a.cause or "task_failed" for a in result.actions if a.status == "FAILURE"]
    status = "FAILURE" if result.status == "SUCCESS" else result.status
    return run_cause(status, causes, plant_disagrees=result.status == "SUCCESS")


def run_seeded(
    task: str,
    seed: int,
    *,
    scenario: str | None = None,
    interference: str | None = None,
    grasp: str | None = None,
    max_sim_time: float | None = None,
    record: str | None = None,
) -> dict[str, Any]:
    """ONE seeded run of LOTS task ``task`` (file or packaged name) in the workcell
    ``scenario`` (default: the packaged one named like the task), with the person's
    ``interference`` file (events, as ``--interference``) if given, as the JSON of
    ``tamp simulate lots --task T --seed N --json``: ``status``, ``cause``, ``task_time``
    (sim s), ``seed``, ``perturbation``, ``satisfied``, ... The entry point of
    ``tamp campaign --kind lots``; ``seed`` drives the perturbation draw and the
    controller's tree update."""
    from tamp.lots.task import load_events, load_task
    from tamp.sim.lots.scenario import load_cell_scenario
    from verification import gate

    loaded = load_task(task)
    cell = load_cell_scenario(scenario or loaded.name)
    events = load_events(interference, loaded) if interference else None
    result = simulate_lots(
        cell,
        loaded,
        events,
        grasp=grasp,
        seed=seed,
        record=record,
        max_sim_time=max_sim_time,
        check=gate,
    )
    return result.to_json()


def check_person_classes(events: Sequence[Event], scenario: CellScenario) -> None:
    """Every class the person brings in must be a class of the workcell scenario, packaged
    or its own (`InputError` naming the interference file's ``events[i].class``)."""
    names = scenario.class_names
    for e in events:
        if e.kind == "add" and e.cls not in names:
            file, _, where = e.where.partition(": ")
            raise InputError(
                f"the workcell has no {e.cls!r} objects for the person to bring in "
                f"(classes: {', '.join(sorted(names))})",
                file=file or None,
                field=f"{where}.class" if where else "class",
            )
