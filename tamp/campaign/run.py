"""One run of a campaign: what is sent to a worker (`Job`), what comes back (`RunRecord`),
and `execute`, the function every engine calls where the run happens.

`execute` is the whole of a run: it runs the workcell's seeded run there (so a Ray worker builds
its own Drake diagram; nothing Drake-made crosses a process boundary), times it, and turns
what happened into one of four statuses: ``success``, ``failure`` (the simulation's verdict,
or a `TampError` such as a refused plan), ``timeout`` (no result within the sim-time limit,
or killed at the campaign's wall-time limit) and ``crash`` (any other exception, or the
worker's death). A failed run's recording comes back as HTML text, so that it reaches the
driver's ``--out`` even when the worker is on another machine.
"""

from __future__ import annotations

import os
import tempfile
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

STATUSES = ("success", "failure", "timeout", "crash")
_FROM_RUNNER = {"SUCCESS": "success", "FAILURE": "failure", "TIMEOUT": "timeout"}


@dataclass(frozen=True)
class Job:
    """One seeded run to do: plain data, cheap to pickle."""

    workcell: Any  # the `tamp.sim.core.workcell.Workcell` (plain data: pickled by reference)
    scenario: str  # file path (resolved on the driver)
    seed: int
    max_sim_time: float | None = None
    record: bool = True  # keep the recording when the run does not succeed
    options: tuple[tuple[str, str], ...] = ()  # the workcell's campaign options
    verify: bool = True  # pass the verification gate before the run


@dataclass
class RunRecord:
    """What one run gave. ``task_time``: sim s at the end of the run (None for a crash or
    a killed run); ``wall_time``: s the run took where it ran; ``perturbation``: its size."""

    seed: int
    status: str
    cause: str | None
    task_time: float | None
    wall_time: float
    perturbation: float = 0.0
    result: dict[str, Any] = field(default_factory=dict)  # the runner's dict, as returned
    error: str | None = None  # a crash's traceback
    recording_html: str | None = None  # a failed run's animation (written by the driver)

    @property
    def ok(self) -> bool:
        return self.status == "success"

    def summary_json(self) -> dict[str, Any]:
        """The run's line in the campaign's JSON."""
        return {
            "seed": self.seed,
            "status": self.status,
            "cause": self.cause,
            "task_time": None if self.task_time is None else round(self.task_time, 3),
            "wall_time": round(self.wall_time, 3),
            "perturbation": round(self.perturbation, 6),
        }


def perturbation_size(value: Any) -> float:
    """A runner's ``perturbation`` as one number: a number, or a mapping's ``size``."""
    if isinstance(value, Mapping):
        value = value.get("size", 0.0)
    try:
        return float(value or 0.0)
    except (TypeError, ValueError):
        return 0.0


def crashed(seed: int, cause: str, wall_time: float, error: str | None = None) -> RunRecord:
    """The record of a run that raised or whose worker died."""
    return RunRecord(seed, "crash", cause, None, wall_time, error=error)


def timed_out(seed: int, limit: float, wall_time: float) -> RunRecord:
    """The record of a run killed at the campaign's wall-time limit."""
    return RunRecord(
        seed, "timeout", f"killed after the {limit:g} s wall-time limit", None, wall_time
    )


def from_runner(seed: int, out: Mapping[str, Any], wall_time: float) -> RunRecord:
    """Normalise a run's JSON (`tamp.sim.core.workcell.RunResult.to_json`) into a record."""
    raw = str(out.get("status", "")).upper()
    if raw not in _FROM_RUNNER:
        return crashed(seed, f"runner returned status {out.get('status')!r}", wall_time)
    status = _FROM_RUNNER[raw]
    cause = out.get("cause")
    if status != "success" and not cause:
        cause = f"{raw} (no cause given)"
    task_time = out.get("task_time")
    return RunRecord(
        seed,
        status,
        None if status == "success" else str(cause),
        None if task_time is None else float(task_time),
        wall_time,
        perturbation_size(out.get("perturbation")),
        result={k: v for k, v in out.items() if k != "recording"},
    )


def execute(job: Job) -> RunRecord:
    """Run ``job`` here (a Ray task or this process) and return its record; never raises
    for a run's own fault (see the module docstring)."""
    from tamp.errors import InputError, TampError
    from tamp.sim.core.workcell import run_seeded

    os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")
    os.environ.setdefault("MPLBACKEND", "Agg")
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="tamp-run-") as tmp:
        record = str(Path(tmp) / f"seed_{job.seed}.html") if job.record else None
        try:
            out = run_seeded(
                job.workcell,
                job.scenario,
                job.seed,
                record=record,
                max_sim_time=job.max_sim_time,
                verify=job.verify,
                **dict(job.options),
            )
            rec = from_runner(job.seed, out, time.perf_counter() - t0)
        except TampError as exc:
            wall = time.perf_counter() - t0
            if isinstance(exc, InputError):  # the driver validated the file: a bug, not bad luck
                return crashed(job.seed, f"InputError: {exc}", wall, traceback.format_exc())
            return RunRecord(job.seed, "failure", f"{type(exc).__name__}: {exc}", None, wall)
        except Exception as exc:
            wall = time.perf_counter() - t0
            return crashed(job.seed, f"{type(exc).__name__}: {exc}", wall, traceback.format_exc())
        if record and not rec.ok and Path(record).is_file():
            rec.recording_html = Path(record).read_text(encoding="utf-8")
    return rec
