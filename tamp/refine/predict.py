"""Refining from a measured log, without simulating (Fig. 1(b), Fig. 5 Step 1).

The paper's input is a state machine plus what one execution measured: when each
behavior started and its event fired, and the rates (Figueroa Heredia et al. 2018 §3,
Fig. 3: "store execution time in the state machine", Fig. 6(a)). `predicting` turns such a
`Log` into a `tamp.refine.measure.Measure`, so `tamp.refine.refinement.refine` runs the
same steps on it and the phases it returns are *predictions*:

- a behavior lasts what the log measured, divided by how much faster its motion became
  (the speed ratio of the program measured against the logged one: Step 2 and Step 3
  change speeds and rates, never the amounts);
- it starts when the events it must follow have fired (`tamp.refine.order`), so
  parallelizing and relaxing waits move starts exactly as the program says; an event
  triggered by another robot's fires when that one does;
- the goal and collisions are not predicted (every phase is accepted; the simulation
  confirms);
- the rates of Fig. 5 are the log's (``rates``, ``ROBOT.BEHAVIOR`` or ``ROBOT.SENSOR`` ->
  Hz; `Predicting.rate_searches`) or, if the log has none, the architecture's queue
  model's (`tamp.refine.architecture.behavior_searches`).

Log file (JSON or CSV; ``tamp refine --json`` writes the JSON form: its first phase is
the run of the program as given)::

    {"program": "task4",
     "timeline": [{"event": "R1.lower_arm", "start": 0.0, "end": 53.1}, ...],
     "rates": {"R1.lower_arm": 23, ...},            # optional (or "R1.imu": 23)
     "touches": {"R1": [63.2, "folding_chair.latch_plate"], ...}}   # optional

    event,start,end          # CSV: one row per behavior, seconds
    R1.lower_arm,0.0,53.1
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

from tamp.errors import InputError
from tamp.refine.architecture import Architecture, behavior_searches
from tamp.refine.measure import Run
from tamp.refine.order import direct_predecessors
from tamp.refine.program import Program, event_id
from tamp.refine.steps import RateSearch
from tamp.refine.timeline import BehaviorRecord, Timeline


@dataclass(frozen=True)
class Log:
    """One measured execution of ``program``: event id -> (start, end), found rates per
    ``ROBOT.SENSOR`` (may be empty), first gripper/object touch per robot."""

    spans: dict[str, tuple[float, float]]
    rates: dict[str, float] = field(default_factory=dict)
    touches: dict[str, tuple[float, str]] = field(default_factory=dict)
    file: str | None = None


def _number(value, file: str, where: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise InputError(f"expected a number, got {value!r}", file=file, field=where) from None
    if out != out or out < 0:
        raise InputError(f"expected a time >= 0, got {value!r}", file=file, field=where)
    return out


def load_log(path: str | Path, program: Program) -> Log:
    """Read a log (module docstring) for ``program``: every behavior of the program needs
    one row, with end >= start (`InputError` naming the file and field)."""
    file = str(path)
    try:
        text = Path(path).read_text()
    except OSError as e:
        raise InputError(f"cannot read the log: {e.strerror}", file=file) from None
    spans: dict[str, tuple[float, float]] = {}
    rates: dict[str, float] = {}
    touches: dict[str, tuple[float, str]] = {}
    if file.endswith(".csv"):
        rows = list(csv.DictReader(text.splitlines()))
        if not rows or not {"event", "start", "end"} <= set(rows[0]):
            raise InputError("expected the columns event,start,end", file=file, field="header")
        items = [(f"row {i + 2}", r) for i, r in enumerate(rows)]
    else:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise InputError(f"not JSON: {e.msg} (line {e.lineno})", file=file) from None
        if not isinstance(data, dict):
            raise InputError("expected a JSON object", file=file)
        if "phases" in data:  # a `tamp refine --json` document: its original run
            timeline = data["phases"][0]["timeline"]
            rates = {k: float(v) for k, v in (data.get("rates_found") or {}).items()}
            touches = {
                b["robot"]: (float(b["touch"][0]), str(b["touch"][1]))
                for b in data.get("manipulation_starts") or []
                if b.get("touch")
            }
            where = "phases[0].timeline"
        else:
            timeline = data.get("timeline")
            rates = {k: float(v) for k, v in (data.get("rates") or {}).items()}
            touches = {k: (float(v[0]), str(v[1])) for k, v in (data.get("touches") or {}).items()}
            where = "timeline"
        if not isinstance(timeline, list):
            raise InputError("expected a list of behaviors", file=file, field=where)
        items = [(f"{where}[{i}]", r) for i, r in enumerate(timeline)]
    for where, row in items:
        if not isinstance(row, dict) or "event" not in row:
            raise InputError("expected event, start and end", file=file, field=where)
        start = _number(row.get("start"), file, f"{where}.start")
        end = _number(row.get("end"), file, f"{where}.end")
        if end < start:
            raise InputError(f"ends ({end:g}) before it starts ({start:g})", file=file, field=where)
        spans[str(row["event"])] = (start, end)
    missing = [e for e in program.events() if e not in spans]
    if missing:
        raise InputError(
            f"no row for {', '.join(missing)} (program {program.name})", file=file, field=where
        )
    return Log(spans, rates, touches, file)


def _speed_ratio(program: Program, logged: Program, eid: str) -> float:
    """How much faster behavior ``eid`` moves in ``program`` than in the ``logged`` one."""
    return program.behavior(eid).motion.speed / logged.behavior(eid).motion.speed


def predicted_timeline(program: Program, logged: Program, log: Log) -> Timeline:
    """When each behavior of ``program`` would start and end, from the ``log`` of the
    ``logged`` program (module docstring)."""
    preds = direct_predecessors(program)
    end: dict[str, float] = {}
    start: dict[str, float] = {}
    pending = list(program.events())
    while pending:
        progressed = False
        for eid in list(pending):
            if not preds[eid] <= set(end):
                continue
            pending.remove(eid)
            progressed = True
            b = program.behavior(eid)
            gate = [e for e in preds[eid] if e != b.event.after]
            s = max((end[e] for e in gate), default=0.0)
            logged_start, logged_end = log.spans[eid]
            t = s + (logged_end - logged_start) / _speed_ratio(program, logged, eid)
            if b.event.after is not None:
                t = max(t, end[b.event.after])
            start[eid], end[eid] = s, t
        assert progressed, "check_can_finish refuses cycles before this"
    records = tuple(
        BehaviorRecord(r.name, b.name, b.section, start[e], end[e], r.gating(i))
        for r in program.robots
        for i, b in enumerate(r.behaviors)
        for e in [event_id(r.name, b.name)]
    )
    return Timeline(records)


@dataclass
class Predicting:
    """A `tamp.refine.measure.Measure` that predicts from a `Log` of ``logged``."""

    logged: Program
    log: Log

    def __call__(
        self,
        program: Program,
        architecture: Architecture,
        *,
        tune: bool = False,
        max_sim_time: float | None = None,
        record: str | Path | None = None,
    ) -> Run:
        timeline = predicted_timeline(program, self.logged, self.log)
        run = Run(program, timeline, touches=dict(self.log.touches))
        if tune:
            run.searches = dict(self.rate_searches(program, architecture))
        return run

    def rate_searches(
        self, program: Program, architecture: Architecture
    ) -> dict[str, RateSearch | None]:
        """Fig. 5's result: the log's rates (keyed as the log keys them: ``ROBOT.BEHAVIOR``
        or ``ROBOT.SENSOR``) or, when it has none, the queue model's search per behavior
        (`tamp.refine.architecture.behavior_searches`)."""
        if not self.log.rates:
            return dict(behavior_searches(program, architecture))
        out: dict[str, RateSearch | None] = {}
        for key, rate in self.log.rates.items():
            robot = key.partition(".")[0]
            current = program.rate(program.robot(robot).behaviors[0])
            step = architecture.rate_step_hz
            out[key] = RateSearch(current, step, 0.0, max(rate, current), found=rate)
        return out


def predicting(program: Program, log: Log) -> Predicting:
    """The measuring function that predicts every phase from ``log`` of ``program``."""
    return Predicting(program, log)
