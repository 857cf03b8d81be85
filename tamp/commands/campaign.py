"""``tamp campaign``: many seeded runs of one scenario, in parallel on Ray, summarised.

    tamp campaign SCENARIO [--kind smp-mro|lots|refine] --runs N [--seed S]
                  [--address ADDRESS] [--workers K] [--engine ray|local] [--time-limit S]
                  [--max-sim-time S] [--interference EVENTS.yaml] [--cell CELL.yaml]
                  [--out DIR] [--no-record] [--no-verify]
                  [--min-success RATE] [--json]

SCENARIO is a file or a packaged name (``case3.yaml``, ``tower.yaml``, ``task4``); the kind is
inferred from it when ``--kind`` is left out. Seeds ``S .. S+N-1`` run on a local Ray with K
CPUs (default: this machine's), or on the Ray cluster at ``--address`` / ``RAY_ADDRESS``;
``--workers 0`` (or ``--engine local``) runs them one after the other in this process. Each
run's JSON goes to ``DIR/runs/seed_N.json``, each unsuccessful run's recording to
``DIR/recordings/seed_N.html``, the summary to ``DIR/summary.json`` with the plots beside it.

Exit 0 when the campaign completed, whatever its runs did (it measures; failed, timed-out and
crashed runs are results); 1 only when ``--min-success`` is given and the success rate is
below it; 2 on bad input, or when Ray is not installed (with the install hint).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from tamp.commands.output import add_no_verify, print_json, progress, warn_unverified


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "campaign",
        help="many seeded runs of a scenario in parallel (Ray), with success statistics",
        description=__doc__.splitlines()[0],
    )
    p.add_argument("scenario", metavar="SCENARIO", help="scenario file or packaged name")
    p.add_argument("--kind", choices=kind_names(), help="the workcell (default: inferred)")
    p.add_argument("--runs", type=int, required=True, help="number of runs (seeds S..S+N-1)")
    p.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    p.add_argument("--address", help="Ray cluster to use (default: RAY_ADDRESS, else a local Ray)")
    p.add_argument(
        "--workers", type=int, help="runs at a time (default: the CPUs; 0: in this process)"
    )
    p.add_argument("--engine", choices=("ray", "local"), help="default ray (local: in-process)")
    p.add_argument(
        "--time-limit", type=float, default=600.0, help="wall s per run before it is killed"
    )
    p.add_argument(
        "--max-sim-time", type=float, metavar="S", help="override the scenario's sim-time limit (s)"
    )
    for option in campaign_flags():
        option.add_to(p)
    p.add_argument("--out", metavar="DIR", help="output folder (default build/campaign/NAME)")
    p.add_argument("--no-record", action="store_true", help="no recordings of failed runs")
    add_no_verify(p)
    p.add_argument(
        "--min-success", type=float, metavar="RATE", help="exit 1 when the success rate is below"
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)


def kind_names() -> tuple[str, ...]:
    """The registered workcells (`tamp.sim.core.workcell`)."""
    from tamp.sim.core.workcell import CELL_PACKAGES

    return tuple(CELL_PACKAGES)


def campaign_flags() -> list:
    """Every workcell's campaign options, one flag each (dest ``opt_<dest>``: a flag shared
    by two cells means the same thing in both)."""
    import dataclasses

    from tamp.sim.core.workcell import campaign_options, workcells

    seen: dict[str, object] = {}
    for cell in workcells().values():
        for o in campaign_options(cell):
            if o.spelling not in seen:
                seen[o.spelling] = dataclasses.replace(
                    o,
                    dest="opt_" + o.dest,
                    flag=o.spelling,
                    help=f"{cell.name}: {o.help}",
                    default=None,
                    required=False,
                )
    return list(seen.values())


def engine_of(args: argparse.Namespace):
    """The engine the flags ask for; contradictions are bad input (exit 2)."""
    from tamp.campaign.engines import make_engine
    from tamp.errors import InputError

    if args.workers is not None and args.workers < 0:
        raise InputError(f"must be >= 0, got {args.workers}", field="--workers")
    engine = args.engine or ("local" if args.workers == 0 else "ray")
    if engine == "local" and args.workers:
        raise InputError("the in-process engine runs one run at a time", field="--workers")
    if engine == "ray" and args.workers == 0:
        raise InputError("0 workers is the in-process engine (--engine local)", field="--workers")
    if engine == "local" and args.address:
        raise InputError("the in-process engine connects to no cluster", field="--address")
    if args.address is not None and not args.address.strip():
        raise InputError("empty address", field="--address")
    return make_engine(engine, address=args.address, workers=args.workers)


def run(args: argparse.Namespace) -> int:
    import os

    from tamp.campaign import CampaignSpec, resolve_scenario, run_campaign
    from tamp.commands.output import output_dir
    from tamp.errors import InputError
    from tamp.scenarios import resolve

    os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")
    if args.min_success is not None and not (
        math.isfinite(args.min_success) and 0 <= args.min_success <= 1
    ):
        raise InputError(f"must be in [0, 1], got {args.min_success}", field="--min-success")
    kind, path = resolve_scenario(args.scenario, args.kind)
    options: tuple[tuple[str, str], ...] = ()
    mine = {o.spelling: o for o in kind.options if o.campaign}
    for flag in campaign_flags():
        value = getattr(args, flag.dest)
        if value is None:
            continue
        if flag.spelling not in mine:
            raise InputError(f"not an option of kind {kind.name}", field=flag.spelling)
        o = mine[flag.spelling]
        options += ((o.dest, str(resolve(value, o.folder)) if o.folder else str(value)),)
    spec = CampaignSpec(
        kind,
        path,
        args.runs,
        seed=args.seed,
        time_limit=args.time_limit,
        max_sim_time=args.max_sim_time,
        record=not args.no_record,
        options=options,
        verify=not args.no_verify,
    )
    if args.no_verify:
        warn_unverified("tamp campaign", "every run's plan")
    out = output_dir(args.out or Path("build") / "campaign" / path.stem, "--out")
    engine = engine_of(args)
    progress(
        f"campaign: {spec.runs} runs of {kind.name} {path.name} (seeds {spec.seeds[0]}.."
        f"{spec.seeds[-1]}) on {engine.name}",
        quiet=args.json,
    )
    result = run_campaign(spec, engine, out=out, progress=not args.json)
    code = 0
    if args.min_success is not None and result.success_rate < args.min_success:
        code = 1
    if args.json:
        print_json(result.to_json())
        return code
    print_summary(result)
    if code:
        print(f"success rate {result.success_rate:.1%} is below --min-success {args.min_success}")
    return code


def print_summary(result) -> None:
    """The human-readable summary of a campaign."""
    doc = result.to_json()
    where = (
        "in this process"
        if doc["engine"] == "local"
        else f"on Ray at {doc['address']} ({doc['workers']} workers)"
    )
    first, last = doc["seeds"]
    print(
        f"campaign {doc['kind']} {result.spec.scenario.name}: {doc['n_runs']} runs "
        f"(seeds {first}-{last}) {where}"
    )
    lo, hi = doc["wilson_95"]
    print(
        f"success {doc['successes']}/{doc['n_runs']} = {doc['success_rate']:.1%} "
        f"(95 % Wilson interval {lo:.1%} - {hi:.1%})"
    )
    t = doc["task_time"]
    if t["n"]:
        print(
            f"task time of the {t['n']} successful runs (sim s): mean {t['mean']:.2f}, "
            f"median {t['median']:.2f}, p90 {t['p90']:.2f}, min {t['min']:.2f}, max {t['max']:.2f}"
        )
    counts = ", ".join(f"{k} {v}" for k, v in doc["statuses"].items() if v)
    print(f"statuses: {counts}")
    for c in doc["causes"]:
        seeds = ", ".join(str(s) for s in c["seeds"])
        print(f"  {c['status']:<8} x{c['count']:<3} seeds {seeds}: {c['cause']}")
    print(
        f"wall {doc['wall_time']:.1f} s ({doc['runs_per_minute']} runs/min); "
        f"runs, recordings, summary.json and plots in {doc['out']}"
    )
