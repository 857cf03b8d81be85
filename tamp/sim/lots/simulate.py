"""``tamp simulate lots``: a LOTS task run by the LOTS controller inside the Drake workcell.

    build_lots_diagram: the workcell station (`build_station`) as a subsystem, and
      LotsControllerSystem:  cell.observation, cell.skill_status ─► controller
                             controller.skill_command ─► cell.skill_command

A run's input is a `LotsScenario`: the LTL task (Zhou et al., IEEE T-ASE 2023, §III), the
workcell scenario it runs in (`tamp.sim.lots.scenario`) and, optionally, a person's
interference script, validated together when loaded (`LotsWorkcell.load`: the cell starts
from the task's objects, the person brings in only classes the cell has). `simulate_lots`
draws the seed's perturbation, builds the controller (its initial table passes the
verification gate before anything moves), simulates in chunks until the controller stops or
the time limit, and measures the result on the plant: counts per class in W^A, W^B and the
waste basket from the objects' poses. The run is a SUCCESS only when the controller
completed its round, the plant's W^B is a W^B state that ends a round of the task
(`Lots.is_goal`), and the run's word — the robot's deliveries and the W^B states its camera
saw, in order — is accepted by the task automaton (`tamp.verification.lots.judge_word`): the
same verdict as ``tamp lots``, which applies it to its symbolic ground truth. A cell that
declares a stack (Fig. 10's tower, `tamp.sim.lots.stack`) is also judged by the stack's
height on the plant (``stack`` in the result): counts alone would pass a tower laid side by
side.
`LotsWorkcell` (``WORKCELL``) is the cell's `tamp.sim.core.workcell.Workcell`.
Drake is imported only inside functions, so listing the workcells builds nothing.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tamp.errors import InputError
from tamp.grasp.networks import DEFAULT_NETWORK, NETWORKS
from tamp.lots.task import Event, Task
from tamp.perturbation import Applied
from tamp.sim.core.workcell import Option, RunResult
from tamp.sim.lots.scenario import (
    BASKET_HALF,
    DEFAULT_WEIGHTS,
    DETECTORS,
    CellScenario,
    perturbed,
)

if TYPE_CHECKING:
    from pydrake.systems.framework import Diagram

    from tamp.lots.controller import ActionRecord, LotsController
    from tamp.sim.core.executor import ActionLog
    from tamp.sim.lots.controller_system import LotsControllerSystem
    from tamp.sim.lots.person import PersonAction
    from tamp.sim.lots.safety import SafetyStop
    from tamp.sim.lots.stack import StackCheck
    from tamp.sim.lots.station import LotsStation

#: how far the simulator runs between checks of the controller's result (sim s)
CHUNK = 0.5
#: after the controller's result, how long the person may take to finish its trip (sim s)
PERSON_GRACE = 15.0


@dataclass(frozen=True)
class LotsScenario:
    """What one LOTS run takes: the task, the workcell scenario (its grasp network
    chosen) and the person's interference events (empty: no person in the cell)."""

    task: Task
    cell: CellScenario
    interference: tuple[Event, ...] = ()

    @property
    def name(self) -> str:
        return self.task.name


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
    period: float | None = None,
    person: Sequence[Event] | None = None,
) -> LotsDiagram:
    """The cell diagram of ``scenario`` driven by ``controller`` (observation and skill status
    in, skill command out: nothing else reaches the controller). ``person``: interference
    events a scripted person carries out in the cell (`tamp.sim.lots.person`). ``period``:
    the controller's tick (default `tamp.sim.lots.controller_system.PERIOD`)."""
    from pydrake.systems.framework import DiagramBuilder

    from tamp.sim.lots.controller_system import PERIOD, LotsControllerSystem
    from tamp.sim.lots.station import build_station

    cell = build_station(scenario, meshcat=meshcat, person=person)
    builder = DiagramBuilder()
    sub = builder.AddSystem(cell.diagram)
    ctrl = builder.AddSystem(LotsControllerSystem(controller, period=period or PERIOD))
    builder.Connect(sub.GetOutputPort("observation"), ctrl.observation_port)
    builder.Connect(sub.GetOutputPort("skill_status"), ctrl.skill_status_port)
    builder.Connect(ctrl.command_port, sub.GetInputPort("skill_command"))
    diagram = builder.Build()
    diagram.set_name(f"lots_{scenario.name}")
    return LotsDiagram(diagram, cell, ctrl)


@dataclass(kw_only=True)
class LotsSimResult(RunResult):
    """A finished workcell run: the common verdict (`RunResult`: ``status`` is SUCCESS only
    when ``satisfied``), the task, what the controller said (``controller_status``), the
    skill log (sim times), robot and person actions, and what the plant shows at the end."""

    workcell: str = "lots"
    task: str = ""
    formula: str = ""
    satisfied: bool = False
    #: the run's word (robot deliveries, observed W^B states) and the automaton's verdict
    word: dict[str, Any] = field(default_factory=dict)
    word_accepted: bool = False
    word_verdict: dict[str, Any] = field(default_factory=dict)
    final_w_b: dict[str, int] = field(default_factory=dict)  # the plan in use (after replans)
    controller_status: str = "TIMEOUT"  # the controller's result (TIMEOUT: none in time)
    actions: list[ActionLog] = field(default_factory=list)
    robot_actions: list[ActionRecord] = field(default_factory=list)
    replans: int = 0
    frames_rendered: int = 0
    grasps: dict[str, int] = field(default_factory=dict)
    final_counts: dict[str, dict[str, int]] = field(default_factory=dict)
    #: the declared stack judged on the plant (`tamp.sim.lots.stack.StackCheck.to_json`;
    #: empty when the cell declares none)
    stack: dict[str, Any] = field(default_factory=dict)
    elsewhere: list[str] = field(default_factory=list)  # objects in no workspace nor basket
    network: str = DEFAULT_NETWORK
    safety_stops: list[SafetyStop] = field(default_factory=list)
    person_actions: list[PersonAction] = field(default_factory=list)
    never_happened: list[Event] = field(default_factory=list)  # scripted, run ended first
    perturbed: bool = False  # the scenario has a perturbation section

    def details_json(self) -> dict[str, Any]:
        return {
            "task": self.task,
            "grasp": self.network,
            "satisfied": self.satisfied,
            "word": self.word,
            "word_accepted": self.word_accepted,
            "word_verdict": self.word_verdict,
            "final_w_b": self.final_w_b,
            "controller_status": self.controller_status,
            "actions": [a.to_json() for a in self.actions],
            "robot_actions": [a.to_json() for a in self.robot_actions],
            "replans": self.replans,
            "safety_stops": [stop.to_json() for stop in self.safety_stops],
            "frames_rendered": self.frames_rendered,
            "grasps": dict(self.grasps),
            "final_counts": self.final_counts,
            "stack": self.stack,
            "elsewhere": self.elsewhere,
            "person_actions": [a.to_json() for a in self.person_actions],
            "never_happened": [e.never_happened() for e in self.never_happened],
        }

    def details_lines(self) -> list[str]:
        lines = [
            f"task {self.task}: {self.formula}  (workcell {self.scenario}, grasp {self.network})",
            f"{'skill':<22} {'start':>8} {'end':>8}  status",
        ]
        for a in self.actions:
            end = "-" if a.end is None else f"{a.end:8.2f}"
            lines.append(f"{a.action:<22} {a.start:8.2f} {end:>8}  {a.outcome}  {a.detail}")
        lines += [f"  {a.index:2d}. {a.text()}" for a in self.robot_actions]
        for p in self.person_actions:
            end = "-" if p.end is None else f"{p.end:.2f}"
            what = f"{p.uid or '-'} {p.src}→{p.dst}"
            detail = f" ({p.detail})" if p.detail else ""
            lines.append(
                f"  person: {p.event.describe()} {p.event.when()}: {what} {p.start:.2f}–{end} s, "
                f"{p.outcome}{detail}"
            )
        lines += [e.never_happened() for e in self.never_happened]
        c = self.final_counts
        lines.append(f"final (plant): W^A {c['A']}  W^B {c['B']}  waste {c['waste']}")
        if self.stack:
            levels = " on ".join(reversed(self.stack["levels"])) or "nothing"
            lines.append(
                f"stack (plant): {self.stack['height']} of {self.stack['required']} high: {levels}"
            )
        if self.word:
            letters = " ".join("{" + ",".join(x) + "}" for x in self.word.get("trace", []))
            verdict = "accepted" if self.word_accepted else "rejected"
            lines.append(f"run's word: {letters or '(empty)'}  — {verdict} by the task automaton")
        if self.elsewhere:
            lines.append(f"elsewhere: {', '.join(self.elsewhere)}")
        for stop in self.safety_stops:
            lines.append(
                f"safety stop at {stop.time:.2f} s: {stop.cause} ({stop.detail}), "
                f"held {stop.duration:.2f} s"
            )
        g = self.grasps
        lines.append(
            f"replans {self.replans}, grasps {g['successes']}/{g['attempts']}, "
            f"frames {self.frames_rendered}, safety stops {len(self.safety_stops)}"
        )
        if self.perturbed and self.perturbation is not None:
            lines.append(f"seed {self.seed}: perturbation size {self.perturbation['size']:.3f} m")
        return lines


def lots_verdict(
    controller_status: str, satisfied: bool, actions: Sequence[ActionLog]
) -> tuple[str, str | None]:
    """The run's status and cause (`tamp.sim.core.outcome.run_cause`): SUCCESS when the task
    is satisfied on the plant; ``placement_off`` (a FAILURE) when the controller completed
    its round but the plant's W^B ends none; else the controller's status with the cause the
    last failed skill reported (`SkillStatus.cause`)."""
    from tamp.sim.core.outcome import run_cause

    if satisfied:
        return "SUCCESS", None
    status = "FAILURE" if controller_status == "SUCCESS" else controller_status
    causes = [a.cause or "task_failed" for a in actions if a.status == "FAILURE"]
    return status, run_cause(status, causes, plant_disagrees=controller_status == "SUCCESS")


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


def check_detector_classes(task: Task, scenario: CellScenario) -> None:
    """With the learned detector (``camera.detector: learned``) every class the task counts
    must be one it was trained on: it would report any other as ``unknown`` or as a class
    it knows, and the task could never be observed done (`InputError` naming the field)."""
    if scenario.camera.detector != "learned":
        return
    from tamp.sim.lots.station import shipped_detector

    missing = sorted(set(task.classes) - set(shipped_detector().classes))
    if missing:
        raise InputError(
            f"the learned detector was not trained on {missing}, which task {task.name!r} "
            "counts: use oracle",
            file=scenario.source or None,
            field="camera.detector",
        )


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
    from tamp.sim.lots.person import RESTING_Z, STAGING, on_shelf

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


def plant_stack(cell: LotsStation, plant_context, required: int | None = None) -> StackCheck:
    """The cell's declared stack judged on the plant (`tamp.sim.lots.stack.judge_stack`): how
    many levels stand on each other in W^B, from the objects' poses; ``required``: how many
    the task needs (None: all)."""
    from tamp.sim.lots.stack import STACK_SIDE, judge_stack

    plant, scenario = cell.plant, cell.scenario
    w = scenario.workspaces[STACK_SIDE]
    objects = {
        uid: (
            cell.cell.classes[uid],
            plant.EvalBodyPoseInWorld(plant_context, body).GetAsMatrix4(),
        )
        for uid, body in cell.cell.bodies.items()
    }
    footprints = {c: scenario.object_class(c).footprint for c in set(cell.cell.classes.values())}
    return judge_stack(scenario.stack, objects, footprints, w.contains, w.floor, required=required)


def perturbed_run(scenario: LotsScenario, seed: int) -> tuple[LotsScenario, Applied]:
    """``scenario`` as run ``seed`` draws it: the cell's objects, friction, depth noise and
    chance grasp failures (`tamp.sim.lots.scenario.perturbed`), and the person's reaction
    time of each scripted slot (`tamp.sim.lots.person.reaction_time`), all in one record."""
    cell, applied = perturbed(scenario.cell, seed)
    if scenario.interference and cell.perturbation.timing_jitter > 0:
        from tamp.sim.lots.person import REACTION, reaction_time, slot_key

        for n, phase in sorted({(e.after, e.phase) for e in scenario.interference}):
            shift = reaction_time(cell.sample, n, phase) - REACTION
            applied.timing[slot_key(n, phase)] = shift
    return dataclasses.replace(scenario, cell=cell), applied


class TableGate:
    """The verification gate on every table the LOTS controller builds (`tamp.verification.gate`:
    the initial one before anything moves, each replanned one before it is used); what it
    raises propagates. ``holds``: every table checked so far was proved."""

    def __init__(self) -> None:
        self.reports: list[Any] = []

    def __call__(self, controller: LotsController) -> None:
        from tamp.verification import gate

        self.reports.append(gate(controller))

    @property
    def verified(self) -> dict[str, bool]:
        return {"table": all(r.holds for r in self.reports)} if self.reports else {}


def draw_cell_views(cell, context) -> int:
    """Draw every view the wrist camera took in the run (its point cloud, frustum and the
    grasp candidates drawn from it: `tamp.sim.core.recording.draw_views`) into the cell's
    recording; returns how many."""
    from tamp.sim.core.recording import draw_views

    if cell.view_log is None or cell.visualizer is None:
        return 0
    kept = {id(crop): cands for crop, _, cands in cell.planner.history}
    return draw_views(
        cell.meshcat,
        cell.visualizer,
        cell.view_log.records(cell.view_log.GetMyContextFromRoot(context)),
        intrinsics=cell.view_log.intrinsics,
        size=cell.view_log.size,
        end=context.get_time(),
        grasps=lambda v: kept.get(id(v.target), []) if v.target is not None else [],
    )


def simulate_lots(
    scenario: LotsScenario,
    *,
    seed: int = 0,
    record: str | Path | None = None,
    meshcat: Any = None,
    max_sim_time: float | None = None,
    verify: bool = True,
) -> LotsSimResult:
    """Run ``scenario`` (see the module docstring); ``seed`` draws the perturbation and the
    controller's tree update. ``verify``: pass every table through the verification gate
    (`TableGate`; False: no gate). With interference events, a scripted person's hand
    carries them out, and the run also waits (at most `PERSON_GRACE` s) for the person to
    finish what it started."""
    from tamp.lots.controller import LotsController
    from tamp.lots.run import run_word_json
    from tamp.sim.core.recording import new_meshcat, save_recording, start_recording
    from tamp.sim.core.runner import make_simulator, run_in_chunks
    from tamp.sim.lots.stack import required_height
    from tamp.verification.lots import judge_verdict
    from tamp.world.interface import Status

    run, applied = perturbed_run(scenario, seed)  # the run's draw of its perturbation
    cell_scenario, task = run.cell, run.task
    gate = TableGate() if verify else None
    controller = LotsController(task, seed=seed, check=gate)  # the gate runs here
    if record and meshcat is None:
        meshcat = new_meshcat()
    events = list(run.interference) or None
    built = build_lots_diagram(cell_scenario, controller, meshcat=meshcat, person=events)
    if record:
        start_recording(built.cell.visualizer)
        built.cell.planner.record = True  # each view's candidates, for the recording
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

    limit = max_sim_time if max_sim_time is not None else cell_scenario.max_sim_time
    t0, c0 = time.perf_counter(), time.process_time()
    chunks = run_in_chunks(simulator, chunk=CHUNK, limit=limit, between=finished)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    cell = built.cell
    s = ctrl.state(ctrl_context)
    plant_context = cell.plant.GetMyContextFromRoot(context)
    counts, elsewhere = plant_counts(cell, plant_context)
    # a declared stack (Fig. 10's tower) is judged by its height on the plant, not by counts
    c = s.controller
    stack = None
    if cell_scenario.stack:  # as high as the task's planned W^B needs (the base alone: one)
        needed = required_height(cell_scenario.stack, c.lots.named(c.plan.end[1]))
        stack = plant_stack(cell, plant_context, needed)
    stacked = stack is None or stack.complete
    controller_status = s.result.value if s.result is not None else "TIMEOUT"
    why = s.reason if s.result is not None else f"no result within {limit:g} s of sim time"
    truth = c.lots.vector(counts["B"])
    word_ok, word_verdict = judge_verdict(c)  # what happened, read by the task automaton
    satisfied = s.result is Status.SUCCESS and c.lots.is_goal(truth) and word_ok and stacked
    if s.result is Status.SUCCESS and not c.lots.is_goal(truth):
        why = (
            f"the controller completed its round, but the plant's W^B holds "
            f"{c.lots.format(truth)}, which ends no round of the task "
            f"(planned: {c.lots.format(c.plan.end[1])})"
        )
    elif s.result is Status.SUCCESS and not word_ok:
        why = (
            "the controller completed its round, but the run's word is not accepted by the "
            "task automaton (what happened does not satisfy the formula)"
        )
    elif s.result is Status.SUCCESS and not stacked:
        why = f"the controller completed its round, but on the plant the {stack.describe()}"
    log = list(s.log)
    status, cause = lots_verdict(controller_status, satisfied, log)
    if chunks.diverged is not None:  # the plant's last state is not a result
        satisfied, status, cause, why = False, "FAILURE", "sim_diverged", chunks.diverged
    skills = cell.skills.state(cell.skills.GetMyContextFromRoot(context))
    perception = cell.perception.state(cell.perception.GetMyContextFromRoot(context))
    recording = None
    if record and chunks.diverged is None:
        draw_cell_views(cell, context)
        recording = save_recording(cell.visualizer, meshcat, record)
    frames, stops = perception.frames, []
    if cell.safety is not None:  # the monitor's own renders count too (none without a hand)
        safety = cell.safety.state(cell.safety.GetMyContextFromRoot(context))
        frames, stops = frames + safety.frames, safety.all_stops(context.get_time())
    ps = None if person is None else person.state(person_context)
    return LotsSimResult(
        scenario=cell_scenario.name,
        status=status,
        reason="task satisfied" if satisfied else f"task NOT satisfied: {why}",
        cause=cause,
        task_time=None if s.result is None else chunks.sim_time,
        sim_time=chunks.sim_time,
        wall_time=wall,
        cpu_time=cpu,
        seed=applied.seed,
        perturbation=applied.to_json(),
        recording=recording,
        verified=gate.verified if gate is not None else {},
        task=task.name,
        formula=task.formula,
        satisfied=satisfied,
        word=run_word_json(c),
        word_accepted=word_ok,
        word_verdict=word_verdict,
        final_w_b=c.lots.named(c.plan.end[1]),
        controller_status=controller_status,
        actions=log,
        robot_actions=list(c.actions),
        replans=c.replans,
        frames_rendered=frames,
        grasps={"attempts": skills.grasp_attempts, "successes": skills.grasp_successes},
        final_counts=counts,
        stack={} if stack is None else stack.to_json(),
        elsewhere=elsewhere,
        network=cell_scenario.grasp.network,
        safety_stops=stops,
        person_actions=[] if ps is None else list(ps.actions),
        never_happened=[] if ps is None else ps.script.unfired(),
        perturbed=bool(cell_scenario.perturbation.fields()),
    )


class LotsWorkcell:
    """The LOTS arm workcell as a `tamp.sim.core.workcell.Workcell`: what ``tamp simulate
    lots`` and ``tamp campaign --kind lots`` run. Its main input is the LTL task
    (``tamp/scenarios/lots``, told apart by its ``formula`` key)."""

    name = "lots"
    title = "LOTS task in the Drake workcell (arm with wrist camera, LOTS controller)"
    folder = "lots"
    key = "formula"
    main = Option(
        "task",
        "LTL task file or packaged task name",
        flag="task",
        metavar="TASK",
        required=True,
        folder="lots",
    )
    options = (
        Option(
            "cell",
            "workcell scenario file or packaged name (default: the packaged lots_sim scenario "
            "named like the task)",
            metavar="CELL.yaml",
            campaign=True,
            folder="lots_sim",
        ),
        Option(
            "interference",
            "human interference script: a scripted person's hand carries it out",
            metavar="EVENTS.yaml",
            campaign=True,
            folder="lots",
        ),
        Option("grasp", "grasp network (default: the scenario's)", choices=tuple(NETWORKS)),
        Option(
            "detector",
            "what reads the wrist camera's views: the renderer's labels as a perfect detector "
            "or the learned detector (default: the scenario's camera.detector)",
            choices=DETECTORS,
        ),
        Option(
            "return_action",
            "allow our extension of Zhou et al.'s action set: take an object from W^B back to "
            "W^A (same as 'actions: {return: true}' in the task file)",
            action="store_true",
        ),
    )
    replay = "tamp simulate lots {scenario} --seed {seed}"

    def load(
        self,
        name_or_path: str | Path,
        *,
        cell: str | Path | None = None,
        interference: str | Path | None = None,
        grasp: str | None = None,
        detector: str | None = None,
        return_action: bool = False,
    ) -> LotsScenario:
        """The task (file or packaged name), the workcell scenario (default: the packaged
        one named like the task) with grasp network ``grasp`` and its views read by
        ``detector`` (None: the scenario's own), and the interference events,
        checked together: the cell starts from the task's objects, its detector knows the
        task's classes, the person brings in only classes the cell has (`InputError` naming
        file and field)."""
        from tamp.lots.task import load_events, load_task
        from tamp.scenarios import resolve
        from tamp.sim.lots.scenario import load_cell_scenario

        task = load_task(name_or_path)
        if return_action:
            task = dataclasses.replace(task, returns=True)
        events = load_events(interference, task) if interference else []
        if cell is None and not resolve(task.name, "lots_sim").is_file():
            raise InputError(
                f"no packaged workcell scenario for task {task.name!r}: give one",
                field="--cell",
            )
        cell_scenario = with_network(load_cell_scenario(cell or task.name), grasp)
        if detector is not None:
            camera = dataclasses.replace(cell_scenario.camera, detector=detector)
            cell_scenario = dataclasses.replace(cell_scenario, camera=camera)
        check_matches(task, cell_scenario)
        check_detector_classes(task, cell_scenario)
        check_person_classes(events, cell_scenario)
        return LotsScenario(task, cell_scenario, tuple(events))

    def perturbed(self, scenario: LotsScenario, seed: int) -> tuple[LotsScenario, Applied]:
        return perturbed_run(scenario, seed)

    def build(self, scenario: LotsScenario, *, meshcat: Any = None) -> Diagram:
        """The Drake Diagram of ``scenario``'s workcell station, with the person's events
        (exported ports: ``skill_command`` in; ``skill_status``, ``observation``,
        ``arm_state``, ... out: `tamp.sim.lots.station`). A run wires the LOTS controller to
        those ports (`build_lots_diagram`)."""
        from tamp.sim.lots.station import build_station

        events = list(scenario.interference) or None
        return build_station(scenario.cell, meshcat=meshcat, person=events).diagram

    def run(
        self,
        scenario: LotsScenario,
        *,
        seed: int = 0,
        record: str | Path | None = None,
        max_sim_time: float | None = None,
        verify: bool = True,
        meshcat: bool = False,
    ) -> LotsSimResult:
        """`simulate_lots`; ``meshcat``: draw the run in a local Meshcat (the command
        line's live view, `tamp.sim.core.recording.new_meshcat`)."""
        viewer = None
        if meshcat:
            from tamp.sim.core.recording import new_meshcat

            viewer = new_meshcat()
        return simulate_lots(
            scenario,
            seed=seed,
            record=record,
            meshcat=viewer,
            max_sim_time=max_sim_time,
            verify=verify,
        )


WORKCELL = LotsWorkcell()
