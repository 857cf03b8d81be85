"""A campaign: N seeded runs of one scenario on an engine, their files, and the summary.

`run_campaign` validates the scenario on the driver (bad input stops everything before a
run starts), runs seeds ``seed .. seed + runs - 1`` on the engine, writes each run's JSON
(``OUT/runs/seed_N.json``) and each unsuccessful run's recording
(``OUT/recordings/seed_N.html``) as the run finishes, then the summary
(``OUT/summary.json``) and the plots. The progress bar (stderr, tqdm) counts the runs done
and the successes so far.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tamp.campaign.kinds import Workcell
from tamp.campaign.run import STATUSES, Job, RunRecord
from tamp.campaign.stats import Distribution, group_causes, success_by_size, wilson_interval
from tamp.errors import InputError

MAX_SEED = 2**63 - 1  # the simulations' seed range (`numpy` seed sequences)


@dataclass(frozen=True)
class CampaignSpec:
    """What to run: ``runs`` seeds from ``seed`` of ``scenario`` (a file of workcell
    ``kind``); ``options``: the workcell's campaign options as (dest, value) strings."""

    kind: Workcell
    scenario: Path
    runs: int
    seed: int = 0
    time_limit: float = 600.0  # wall s per run
    max_sim_time: float | None = None
    record: bool = True
    options: tuple[tuple[str, str], ...] = ()
    verify: bool = True  # False: every run skips the verification gate (--no-verify)

    def __post_init__(self) -> None:
        from tamp.sim.core.workcell import campaign_options

        allowed = {o.dest: o for o in campaign_options(self.kind)}
        for name, _ in self.options:
            if name not in allowed:
                raise InputError(
                    f"not an option of kind {self.kind.name}", field="--" + name.replace("_", "-")
                )
        if self.runs < 1:
            raise InputError(f"must be at least 1, got {self.runs}", field="--runs")
        if self.seed < 0 or self.seed + self.runs - 1 > MAX_SEED:
            raise InputError(
                f"seeds {self.seed}..{self.seed + self.runs - 1} must lie within [0, 2^63 - 1]",
                field="--seed",
            )
        if not (math.isfinite(self.time_limit) and self.time_limit > 0):
            raise InputError(
                f"must be a positive number of seconds, got {self.time_limit}",
                field="--time-limit",
            )
        if self.max_sim_time is not None and not (
            math.isfinite(self.max_sim_time) and self.max_sim_time > 0
        ):
            raise InputError(
                f"must be a positive number of seconds, got {self.max_sim_time}",
                field="--max-sim-time",
            )

    @property
    def seeds(self) -> range:
        return range(self.seed, self.seed + self.runs)

    def jobs(self) -> list[Job]:
        return [
            Job(
                self.kind,
                str(self.scenario),
                s,
                self.max_sim_time,
                self.record,
                self.options,
                self.verify,
            )
            for s in self.seeds
        ]

    def replay(self, seed: int) -> str:
        """The command that reruns one seed of this campaign."""
        spelling = {o.dest: o.spelling for o in self.kind.options}
        extra = "".join(f" {spelling[name]} {value}" for name, value in self.options)
        if not self.verify:
            extra += " --no-verify"
        return self.kind.replay.format(scenario=self.scenario, seed=seed) + extra


@dataclass
class CampaignResult:
    """Every run's record (in seed order), where they ran, and what it cost."""

    spec: CampaignSpec
    engine: str
    address: str | None
    workers: int
    records: list[RunRecord]
    wall_time: float
    init_time: float = 0.0
    out: Path | None = None
    plots: list[str] = field(default_factory=list)

    @property
    def successes(self) -> int:
        return sum(r.ok for r in self.records)

    @property
    def success_rate(self) -> float:
        return self.successes / len(self.records) if self.records else 0.0

    def task_times(self) -> list[float]:
        """Task times of the successful runs (what the distribution describes)."""
        return [r.task_time for r in self.records if r.ok and r.task_time is not None]

    def worst(self) -> RunRecord | None:
        """The run to look at first: the lowest unsuccessful seed, else the slowest success."""
        bad = [r for r in self.records if not r.ok]
        if bad:
            return bad[0]
        ok = [r for r in self.records if r.task_time is not None]
        return max(ok, key=lambda r: r.task_time) if ok else None

    def to_json(self) -> dict[str, Any]:
        n = len(self.records)
        lo, hi = wilson_interval(self.successes, n)
        runs = [(r.seed, r.status, r.cause) for r in self.records]
        sizes = [(r.perturbation, r.ok) for r in self.records]
        return {
            "kind": self.spec.kind.name,
            "scenario": str(self.spec.scenario),
            "engine": self.engine,
            "address": self.address,
            "workers": self.workers,
            "seeds": [self.spec.seed, self.spec.seed + self.spec.runs - 1],
            "n_runs": n,
            "successes": self.successes,
            "success_rate": round(self.success_rate, 4),
            "wilson_95": [round(lo, 4), round(hi, 4)],
            "statuses": {s: sum(r.status == s for r in self.records) for s in STATUSES},
            "task_time": Distribution.of(self.task_times()).to_json(),
            "causes": [c.to_json() for c in group_causes(runs)],
            "by_perturbation": [b.to_json() for b in success_by_size(sizes)],
            "runs": [r.summary_json() for r in self.records],
            "options": dict(self.spec.options),
            "verified": self.spec.verify,
            "time_limit": self.spec.time_limit,
            "wall_time": round(self.wall_time, 3),
            "init_time": round(self.init_time, 3),
            "runs_per_minute": round(60.0 * n / self.wall_time, 2) if self.wall_time > 0 else None,
            "out": None if self.out is None else str(self.out),
            "plots": list(self.plots),
        }


def check_scenario(spec: CampaignSpec) -> None:
    """Load and validate the scenario here, before any run (`InputError`: exit 2)."""
    spec.kind.load(str(spec.scenario), **_load_options(spec))


def _load_options(spec: CampaignSpec) -> dict[str, str]:
    """The spec's options that the workcell's loader takes (its load-stage options)."""
    stage = {o.dest: o.stage for o in spec.kind.options}
    return {k: v for k, v in spec.options if stage.get(k) == "load"}


def run_campaign(
    spec: CampaignSpec,
    engine,
    *,
    out: Path | None = None,
    progress: bool = True,
    plots: bool = True,
) -> CampaignResult:
    """Run the campaign on ``engine`` (`tamp.campaign.engines`), entered here; with ``out``,
    write the files (the plots too unless ``plots`` is False)."""
    from tqdm import tqdm

    check_scenario(spec)
    records: list[RunRecord] = []

    def done(rec: RunRecord) -> None:
        records.append(rec)
        if out is not None:
            _write_run(out, spec, rec)
        rec.recording_html = None  # written (or not wanted): do not keep megabytes around
        bar.update(1)
        bar.set_postfix_str(f"{sum(r.ok for r in records)}/{len(records)} ok")

    with engine:  # a local Ray starts here, or the cluster is reached (or refused)
        if out is not None:
            _clear_runs(out)
        bar = tqdm(total=spec.runs, desc="campaign", unit="run", disable=None if progress else True)
        t0 = time.perf_counter()
        try:
            engine.run(spec.jobs(), spec.time_limit, done)
        finally:
            bar.close()
        wall = time.perf_counter() - t0
    result = CampaignResult(
        spec,
        engine.name,
        engine.address,
        engine.workers,
        sorted(records, key=lambda r: r.seed),
        wall,
        init_time=getattr(engine, "init_time", 0.0),
        out=out,
    )
    if out is not None:
        result.plots = _plots(result, out) if plots else []
        (out / "summary.json").write_text(json.dumps(result.to_json(), indent=2) + "\n")
    return result


def _clear_runs(out: Path) -> None:
    for sub, pattern in (("runs", "seed_*.json"), ("recordings", "seed_*.html")):
        folder = out / sub
        folder.mkdir(parents=True, exist_ok=True)
        for old in folder.glob(pattern):
            old.unlink()


def _write_run(out: Path, spec: CampaignSpec, rec: RunRecord) -> None:
    recording = None
    if rec.recording_html is not None:
        path = out / "recordings" / f"seed_{rec.seed}.html"
        path.write_text(rec.recording_html, encoding="utf-8")
        recording = str(path)
    doc = {
        **rec.summary_json(),
        "kind": spec.kind.name,
        "scenario": str(spec.scenario),
        "replay": spec.replay(rec.seed),
        "recording": recording,
        "error": rec.error,
        "result": rec.result,
    }
    path = out / "runs" / f"seed_{rec.seed}.json"
    path.write_text(json.dumps(doc, indent=2, default=str) + "\n")


def _plots(result: CampaignResult, out: Path) -> list[str]:
    from tamp.campaign.plots import success_by_perturbation, task_time_histogram

    name = f"{result.spec.kind.name} {result.spec.scenario.stem}"
    n, k = len(result.records), result.successes
    title = f"{name}: {k}/{n} runs succeeded"
    sizes = [(r.perturbation, r.ok) for r in result.records]
    return task_time_histogram(result.task_times(), out, title) + success_by_perturbation(
        success_by_size(sizes), out, title
    )
