"""The contract every Drake workcell keeps, the result every run returns, and the registry.

A workcell (the youBot cell of SMP-MRO, the LOTS arm cell, the two-robot refinement cell) is
a `Workcell`: it loads its scenario files (`load`), draws a seeded perturbation of a scenario
(`perturbed`), builds its Drake diagram (`build`) and runs it (`run`) to a `RunResult`.
Everything that handles "any workcell" — ``tamp simulate <cell>``, campaign kinds, the one
seeded run `run_seeded` — is derived from the registry (`workcells`), so a new cell is one
subpackage that exports ``WORKCELL`` plus one line in `CELL_PACKAGES`.

No Drake import here: the registry, the option declarations and the scenario loaders run
without building anything (``tamp --help``, a campaign's driver, validation of files).
"""

from __future__ import annotations

import importlib
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from tamp.errors import InputError

#: The run's verdicts: the simulation's own judgement, read on the plant.
STATUSES = ("SUCCESS", "FAILURE", "TIMEOUT")
#: Schema version of a run's JSON document.
RUN_SCHEMA = 1


@dataclass(kw_only=True)
class RunResult:
    """What one simulated run did, said the same way by every workcell.

    ``status`` is the one verdict (SUCCESS | FAILURE | TIMEOUT); ``ok`` and ``exit_code`` are
    derived from it so they cannot disagree. ``cause`` is None on success, else one of
    `tamp.sim.core.outcome.CAUSES`; ``reason`` the human sentence. ``task_time`` is the sim
    time at which the task ended (None when it never did), ``sim_time`` how far the simulation
    ran, ``wall_time``/``cpu_time`` what it cost here. ``seed`` and ``perturbation`` (the
    `tamp.perturbation.Applied` record's JSON) say which draw ran; ``verified`` maps each
    verification gate that ran before the simulation to its verdict. A cell's result extends
    this class with its own fields and `details_json` / `details_lines`.
    """

    workcell: str = ""
    scenario: str = ""
    status: str = "FAILURE"
    reason: str = ""
    cause: str | None = None
    task_time: float | None = None
    sim_time: float = 0.0
    wall_time: float = 0.0
    cpu_time: float = 0.0
    seed: int | None = None
    perturbation: dict[str, Any] | None = None
    recording: str | None = None
    verified: dict[str, bool] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """The task is done: the status is SUCCESS."""
        return self.status == "SUCCESS"

    @property
    def exit_code(self) -> int:
        """0 when ``ok``, else 1 (what ``tamp simulate`` exits with)."""
        return 0 if self.ok else 1

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf

    @property
    def cpu_realtime_factor(self) -> float:
        """Simulated seconds per CPU second of this process (fair under load)."""
        return self.sim_time / self.cpu_time if self.cpu_time > 0 else math.inf

    def to_json(self) -> dict[str, Any]:
        """The run's JSON document: the common keys first, then the cell's own."""
        out: dict[str, Any] = {
            "schema": RUN_SCHEMA,
            "workcell": self.workcell,
            "scenario": self.scenario,
            "status": self.status,
            "ok": self.ok,
            "cause": self.cause,
            "reason": self.reason,
            "task_time": _round(self.task_time),
            "sim_time": _round(self.sim_time),
            "wall_time": _round(self.wall_time),
            "cpu_time": _round(self.cpu_time),
            "realtime_factor": _round(self.realtime_factor, 2),
            "seed": self.seed,
            "perturbation": self.perturbation,
            "recording": self.recording,
            "verified": dict(self.verified),
        }
        for key, value in self.details_json().items():
            if key in out:
                raise KeyError(f"{type(self).__name__}.details_json() redefines {key!r}")
            out[key] = value
        return out

    def details_json(self) -> dict[str, Any]:
        """The cell's own keys of the JSON document (none here)."""
        return {}

    def details_lines(self) -> list[str]:
        """The cell's own lines of the text report, before the status line (none here)."""
        return []

    def report_lines(self) -> list[str]:
        """The text report ``tamp simulate`` prints: the cell's lines, then the verdict."""
        lines = list(self.details_lines())
        if self.cause is not None:
            lines.append(f"cause: {self.cause}")
        rtf = self.realtime_factor
        cpu = f" (CPU {self.cpu_time:.2f} s)" if self.cpu_time > 0 else ""
        lines.append(
            f"{self.status}: {self.reason}; sim {self.sim_time:.2f} s, wall "
            f"{self.wall_time:.2f} s{cpu}, real-time factor {rtf:.2f}x"
        )
        if self.recording:
            lines.append(f"recording: {self.recording}")
        return lines


def _round(value: float | None, digits: int = 3) -> float | None:
    if value is None or not math.isfinite(value):
        return None
    return round(float(value), digits)


@dataclass(frozen=True)
class Option:
    """A workcell's own command-line option and run argument (``--interference FILE``).

    ``dest`` is the keyword the cell's `Workcell.load` (``stage="load"``) or `Workcell.run`
    (``stage="run"``) takes; ``flag`` its command-line spelling (default ``--dest`` with
    dashes; a spelling without dashes is a positional argument). ``campaign``: campaigns pass
    the option on too (as a string: a file, or a packaged name resolved in ``folder``). The
    CLI builds its parser from these declarations only (`add_to`).
    """

    dest: str
    help: str
    stage: str = "load"  # load | run
    flag: str | None = None
    metavar: str | None = None
    type: Callable[[str], Any] | None = None
    choices: tuple[str, ...] | None = None
    default: Any = None
    action: str | None = None  # None (a value) | append | store_true
    required: bool = False
    campaign: bool = False
    folder: str | None = None  # packaged folder a name resolves in (`tamp.scenarios.resolve`)

    @property
    def spelling(self) -> str:
        return self.flag or "--" + self.dest.replace("_", "-")

    def add_to(self, parser: Any) -> None:
        """Add this option to an argparse parser."""
        kwargs: dict[str, Any] = {"dest": self.dest, "help": self.help}
        if self.action == "store_true":
            kwargs.update(action="store_true")
        else:
            if self.action == "append":
                kwargs.update(action="append", default=list(self.default or []))
            else:
                kwargs.update(default=self.default)
            for key in ("metavar", "type", "choices"):
                if getattr(self, key) is not None:
                    kwargs[key] = getattr(self, key)
            if self.required:
                kwargs["required"] = True
        if not self.spelling.startswith("-"):  # a positional argument
            del kwargs["dest"]
            kwargs.pop("required", None)
            if self.default is not None or not self.required:
                kwargs["nargs"] = "?"
            parser.add_argument(self.dest, **kwargs)
            return
        parser.add_argument(self.spelling, **kwargs)


@runtime_checkable
class Workcell(Protocol):
    """One Drake workcell (module docstring).

    Attributes: ``name`` (``tamp simulate NAME``, ``--kind NAME``), ``title`` (one line of
    help), ``folder`` (its packaged scenario folder, `tamp.scenarios.resolve`), ``key`` (a
    top-level YAML key that only its scenario files have: how a campaign tells the cell of a
    user file), ``main`` (the positional argument naming the scenario: ``SCENARIO``, ``TASK``,
    ``PROGRAM``), ``options`` (its other options), ``replay`` (the command that reruns one
    seed, with ``{scenario}`` and ``{seed}``).
    """

    name: str
    title: str
    folder: str
    key: str
    main: Option
    options: tuple[Option, ...]
    replay: str

    def load(self, name_or_path: str | Path, **options: Any) -> Any:
        """The validated scenario (`InputError` naming file and field, nothing half-done)."""
        ...

    def perturbed(self, scenario: Any, seed: int) -> tuple[Any, Any]:
        """``scenario`` as run ``seed`` draws it, and the `tamp.perturbation.Applied` record."""
        ...

    def build(self, scenario: Any, **options: Any) -> Any:
        """The cell's Drake diagram (its station) with named exported ports."""
        ...

    def run(
        self,
        scenario: Any,
        *,
        seed: int = 0,
        record: str | Path | None = None,
        max_sim_time: float | None = None,
        verify: bool = True,
        **options: Any,
    ) -> RunResult:
        """Verify, perturb by ``seed``, build, simulate and judge on the plant. A cell with
        a live view also takes ``meshcat: bool`` (``tamp simulate CELL --meshcat``)."""
        ...


#: Registered workcells: name -> the package exporting ``WORKCELL`` (imported on first use,
#: so nothing Drake-made is built to list them).
CELL_PACKAGES: dict[str, str] = {
    "smp-mro": "tamp.sim.smp",
    "lots": "tamp.sim.lots",
    "refine": "tamp.sim.refine",
}
_EXTRA: dict[str, Workcell] = {}


def register(cell: Workcell) -> None:
    """Add (or replace) a workcell object, e.g. a user's own cell or a test's stand-in."""
    if not isinstance(cell, Workcell):
        raise TypeError(f"{cell!r} does not implement the Workcell protocol")
    _EXTRA[cell.name] = cell


def unregister(name: str) -> None:
    """Remove a workcell added by `register`."""
    _EXTRA.pop(name, None)


def names() -> tuple[str, ...]:
    """Names of the packaged workcells, then those added by `register`."""
    return tuple(CELL_PACKAGES) + tuple(n for n in _EXTRA if n not in CELL_PACKAGES)


def get(name: str) -> Workcell:
    """The workcell ``name`` (`InputError` naming the known ones otherwise)."""
    if name in _EXTRA:
        return _EXTRA[name]
    if name not in CELL_PACKAGES:
        raise InputError(f"unknown workcell {name!r} (known: {', '.join(names())})")
    return importlib.import_module(CELL_PACKAGES[name]).WORKCELL


def workcells() -> dict[str, Workcell]:
    """Every registered workcell by name."""
    return {n: get(n) for n in names()}


def run_seeded(
    cell: str | Workcell,
    scenario: str | Path,
    seed: int,
    /,
    *,
    record: str | Path | None = None,
    max_sim_time: float | None = None,
    verify: bool = True,
    **options: Any,
) -> dict[str, Any]:
    """ONE seeded run of any workcell, as the JSON of ``tamp simulate CELL ... --seed N
    --json``: load the scenario (with the cell's load-stage ``options``), run it, return
    `RunResult.to_json`. Arguments are plain data, so a campaign sends them to a Ray worker
    and the diagram is built there. The entry point of every campaign kind. The first three
    are positional only: a cell's own option may be called ``cell`` (the LOTS ``--cell``)."""
    wc = get(cell) if isinstance(cell, str) else cell
    load_opts, run_opts = split_options(wc, options)
    _quiet_drake()
    loaded = wc.load(scenario, **load_opts)
    result = wc.run(
        loaded, seed=seed, record=record, max_sim_time=max_sim_time, verify=verify, **run_opts
    )
    return result.to_json()


def _quiet_drake() -> None:
    """Drake's logger at WARNING (pydrake sets it up on import; a run would print one
    Meshcat URL each)."""
    import pydrake  # noqa: F401

    logging.getLogger("drake").setLevel(logging.WARNING)


def split_options(cell: Workcell, options: dict[str, Any]) -> tuple[dict, dict]:
    """``options`` split into the cell's load-stage and run-stage keywords; an option the
    cell does not declare is an `InputError` naming it."""
    declared = {o.dest: o for o in cell.options}
    load, run = {}, {}
    for key, value in options.items():
        if key not in declared:
            known = ", ".join(o.spelling for o in cell.options) or "none"
            raise InputError(
                f"the {cell.name} workcell has no option {key!r} (its options: {known})",
                field="--" + key.replace("_", "-"),
            )
        (run if declared[key].stage == "run" else load)[key] = value
    return load, run


def campaign_options(cell: Workcell) -> Sequence[Option]:
    """The options a campaign of ``cell`` passes on to each run."""
    return tuple(o for o in cell.options if o.campaign)
