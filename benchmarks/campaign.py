"""Campaign targets and throughput: success rates over many seeds, runs per
minute with 1 and 2 Ray workers, and what Ray adds per run compared with one process.

Sections (``--only``):

- ``smp``: SMP-MRO Case 3 over 50 seeds on Ray (target: success >= 95 %, every failure
  with its cause). ``--smp-scenario`` picks the scenario: the perturbed Case 3 with friction
  grasps and camera perception (``case3_camera.yaml``, the default).
- ``lots``: the LOTS tower with the person's interference (``tower_interference``) in the
  perturbed cell ``tower_perturbed`` over 20 seeds (target >= 90 %); ``--lots-scenario``,
  ``--lots-cell`` and ``--lots-interference`` change them.
- ``perception``: the same campaigns read by another perception, each beside the one it
  changes: the learned detector (SMP-MRO ``detector: learned``, the mast camera's weights;
  LOTS ``camera.detector: learned``) and the seeded noisy detector
  (``perturbation.sensor.detector: low`` and ``high``, `tamp.sim.core.detection_noise`) over
  the label oracle or (SMP-MRO) over the learned detector; ``--smp-readings`` and
  ``--lots-readings`` pick the rows. ``--perception-cells`` picks ``smp`` and/or ``lots``
  (default ``smp``: a LOTS tower campaign costs about 280 CPU s per run); each variant is
  the packaged file with that one field changed, written into the output folder.
- ``overhead``: Ray's own cost per run, without a simulation's noise: runs that only sleep
  ``--sleep`` s, in this process and on a local Ray with 1 and 2 workers (scheduling, the
  worker's start-up, pickling the job and the record both ways).
- ``throughput``: the same seeds of ``--throughput-scenario`` (Case 1 by default) in this
  process (``--workers 0``), on a local Ray with 1 worker and with 2: runs per minute, the
  scaling 1 -> 2 workers, and Ray's overhead per run = (Ray 1-worker wall - in-process
  wall) / runs, beside Ray's start-up (``init_time``, not in the wall).

Every campaign is one ``tamp campaign --json`` subprocess (a fresh process each, so every
engine pays its own imports). On a shared machine wall times depend on the load (printed).

    python benchmarks/campaign.py [--runs N] [--only smp lots overhead throughput] [--out DIR]

Prints a table and one JSON line.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

TARGETS = {"smp": 0.95, "lots": 0.90}
ROOT = Path(__file__).resolve().parents[1]
SLEEP = float(os.environ.get("TAMP_BENCH_SLEEP", "0.5"))


def accept(scenario: str) -> None:
    """The sleeping kind's check: any file will do."""


def sleeper(scenario: str, seed: int, *, record=None, max_sim_time=None) -> dict:
    """A run that only sleeps `SLEEP` s: what is left is the engine's own cost."""
    time.sleep(SLEEP)
    return {
        "status": "SUCCESS",
        "cause": None,
        "task_time": SLEEP,
        "seed": seed,
        "perturbation": 0.0,
    }


def overhead(runs: int) -> dict:
    """Wall time of ``runs`` sleeping runs per engine; Ray's overhead per run against the
    in-process engine, and its start-up."""
    from tamp.campaign import CampaignSpec, LocalEngine, RayEngine, run_campaign
    from tamp.campaign.kinds import Kind

    kind = Kind(
        "bench-sleep",
        "sim",
        "bench_sleep",
        "benchmarks.campaign:sleeper",
        "benchmarks.campaign:accept",
        "-",
    )
    spec = CampaignSpec(kind, Path(__file__), runs)
    out = {"runs": runs, "sleep_s": SLEEP}
    for name, engine in (
        ("local", LocalEngine()),
        ("ray1", RayEngine(workers=1)),
        ("ray2", RayEngine(workers=2)),
    ):
        load = os.getloadavg()[0]
        result = run_campaign(spec, engine, out=None, progress=False)
        assert result.successes == runs, result.to_json()["causes"]
        out[name] = {
            "wall_time": round(result.wall_time, 3),
            "init_time": round(result.init_time, 3),
            "load_avg": round(load, 2),
        }
    ideal = runs * SLEEP
    for name, workers in (("local", 1), ("ray1", 1), ("ray2", 2)):
        out[name]["overhead_per_run_s"] = round(
            (out[name]["wall_time"] - ideal / workers) / runs * workers, 4
        )
    out["ray_overhead_per_run_s"] = round(
        (out["ray1"]["wall_time"] - out["local"]["wall_time"]) / runs, 4
    )
    return out


def campaign(scenario: str, runs: int, workers: int, out: Path, *extra: str) -> dict:
    """One ``tamp campaign`` in a fresh process; its JSON summary plus the load average."""
    cmd = [sys.executable, "-m", "tamp.commands.main", "campaign", scenario, "--runs", str(runs)]
    cmd += ["--workers", str(workers), "--out", str(out), "--json", *extra]
    load = os.getloadavg()[0]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)} exited {proc.returncode}:\n{proc.stderr[-2000:]}")
    doc = json.loads(proc.stdout)
    doc["load_avg"] = round((load + os.getloadavg()[0]) / 2, 2)
    return doc


def variant(name: str, folder: str, out: Path, tag: str, **sections) -> Path:
    """The packaged scenario ``name`` (in ``folder``) with the given fields changed
    (``sections``: section -> {field: value}, merged one level down, or a top-level field ->
    its value), written to
    ``out/<stem>_<tag>.yaml``; a relative ``demonstration`` is made absolute."""
    import yaml

    from tamp.scenarios import resolve

    src = resolve(name, folder)
    data = yaml.safe_load(src.read_text())
    if isinstance(data.get("demonstration"), str) and data["demonstration"].startswith("."):
        data["demonstration"] = str((src.parent / data["demonstration"]).resolve())
    for section, fields in sections.items():
        if not isinstance(fields, dict):
            data[section] = fields
            continue
        node = data.setdefault(section, {})
        for key, value in fields.items():
            if isinstance(value, dict):
                node.setdefault(key, {}).update(value)
            else:
                node[key] = value
    data["name"] = f"{data['name']}_{tag}"
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{src.stem}_{tag}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


#: the LOTS tower's perception rows: the learned detector, the noisy one over the oracle
LOTS_READINGS = ["learned", "oracle, low", "oracle, high"]


def perception(
    cells: list[str],
    runs: dict[str, int],
    workers: int,
    out: Path,
    lots,
    readings: list[str],
    lots_readings: list[str] = LOTS_READINGS,
) -> list:
    """The ``perception`` section (module docstring): one row per cell and reading (SMP-MRO:
    those of ``readings``; LOTS: those of ``lots_readings``)."""
    rows = []
    noisy = {lvl: {"perturbation": {"sensor": {"detector": lvl}}} for lvl in ("low", "high")}
    if "smp" in cells:
        learned = {"detector": "learned"}
        smp = {
            "learned": learned,
            "oracle, low": noisy["low"],
            "oracle, high": noisy["high"],
            "learned, low": {**learned, **noisy["low"]},
            "learned, high": {**learned, **noisy["high"]},
        }
        for reading in readings:
            tag = "detector_" + reading.replace(", ", "_")
            path = variant("case3_camera", "sim", out / "perception", tag, **smp[reading])
            doc = campaign(str(path), runs["smp"], workers, out / f"perception_smp_{tag}")
            rows.append({**row("perception", doc), "cell": "smp", "reading": reading})
    if "lots" in cells:
        scenario, cell, interference = lots
        lots_changes = {"learned": {"camera": {"detector": "learned"}}, **noisy}
        for tag in (r.removeprefix("oracle, ") for r in lots_readings):
            change = lots_changes[tag]
            path = variant(cell, "lots_sim", out / "perception", tag, **change)
            extra = ("--cell", str(path))
            if interference != "none":
                extra += ("--interference", interference)
            doc = campaign(scenario, runs["lots"], workers, out / f"perception_lots_{tag}", *extra)
            reading = tag if tag == "learned" else f"oracle, {tag}"
            rows.append({**row("perception", doc), "cell": "lots", "reading": reading})
    return rows


def row(section: str, doc: dict) -> dict:
    """The figures of one campaign that the table and the JSON line report."""
    per_run = [r["wall_time"] for r in doc["runs"]]
    return {
        "section": section,
        "scenario": Path(doc["scenario"]).name,
        "engine": doc["engine"],
        "workers": doc["workers"],
        "runs": doc["n_runs"],
        "successes": doc["successes"],
        "success_rate": doc["success_rate"],
        "wilson_95": doc["wilson_95"],
        "target": TARGETS.get(section),
        "causes": doc["causes"],
        "task_time": doc["task_time"],
        "wall_time": doc["wall_time"],
        "init_time": doc["init_time"],
        "runs_per_minute": doc["runs_per_minute"],
        "mean_run_wall": round(sum(per_run) / len(per_run), 3) if per_run else None,
        "load_avg": doc["load_avg"],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, help="runs of every section (smaller than the targets')")
    ap.add_argument("--smp-runs", type=int, default=50)
    ap.add_argument("--lots-runs", type=int, default=20)
    ap.add_argument("--throughput-runs", type=int, default=8)
    ap.add_argument("--smp-scenario", default="case3_camera.yaml")
    ap.add_argument("--lots-scenario", default="tower.yaml")
    ap.add_argument(
        "--lots-interference",
        default="tower_interference",
        help="the person's script (default tower_interference; 'none' for no person)",
    )
    ap.add_argument(
        "--lots-cell",
        default="tower_perturbed",
        help="the workcell the tower runs in (default tower_perturbed: poses, friction, "
        "depth noise, reaction jitter, chance grasp failures)",
    )
    ap.add_argument("--throughput-scenario", default="case1.yaml")
    ap.add_argument("--workers", type=int, default=2, help="Ray workers of smp and lots")
    ap.add_argument("--overhead-runs", type=int, default=20)
    ap.add_argument(
        "--only", nargs="+", choices=("smp", "lots", "perception", "overhead", "throughput")
    )
    ap.add_argument("--perception-cells", nargs="+", choices=("smp", "lots"), default=["smp"])
    smp_readings = ("learned", "oracle, low", "oracle, high", "learned, low", "learned, high")
    ap.add_argument(
        "--smp-readings",
        nargs="+",
        choices=smp_readings,
        default=list(smp_readings),
        help="the SMP-MRO perception rows: the learned detector (`detector: learned`) and the "
        "seeded noisy detector's levels over the oracle or the learned detector (default: all)",
    )
    ap.add_argument(
        "--lots-readings",
        nargs="+",
        choices=LOTS_READINGS,
        default=list(LOTS_READINGS),
        help="the LOTS tower's perception rows: the learned detector (`camera.detector: "
        "learned`) and the seeded noisy detector's levels over the oracle (default: all)",
    )
    ap.add_argument("--out", default="build/bench_campaign", help="campaign folders")
    args = ap.parse_args()
    os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")
    # `benchmarks.campaign` (the sleeping runner) importable here and in Ray's workers
    sys.path.insert(0, str(ROOT))
    os.environ["PYTHONPATH"] = os.pathsep.join(
        p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p
    )
    only = set(args.only or ("smp", "lots", "perception", "overhead", "throughput"))
    out = Path(args.out)
    rows = []
    if "smp" in only:
        n = args.runs or args.smp_runs
        rows.append(row("smp", campaign(args.smp_scenario, n, args.workers, out / "smp")))
    if "lots" in only:
        n = args.runs or args.lots_runs
        extra: tuple[str, ...] = ("--cell", args.lots_cell)
        if args.lots_interference != "none":
            extra += ("--interference", args.lots_interference)
        doc = campaign(args.lots_scenario, n, args.workers, out / "lots", *extra)
        rows.append(row("lots", doc))
    if "perception" in only:
        runs = {"smp": args.runs or args.smp_runs, "lots": args.runs or args.lots_runs}
        lots = (args.lots_scenario, args.lots_cell, args.lots_interference)
        rows += perception(
            args.perception_cells,
            runs,
            args.workers,
            out,
            lots,
            args.smp_readings,
            args.lots_readings,
        )
    engine_cost = overhead(args.runs or args.overhead_runs) if "overhead" in only else None
    scaling = None
    if "throughput" in only:
        n = args.runs or args.throughput_runs
        sc = args.throughput_scenario
        by_workers = {}
        for workers in (0, 1, 2):
            doc = campaign(sc, n, workers, out / f"throughput_{workers}", "--no-record")
            by_workers[workers] = row("throughput", doc)
            rows.append(by_workers[workers])
        local, ray1, ray2 = by_workers[0], by_workers[1], by_workers[2]
        scaling = {
            "runs": n,
            "ray_overhead_per_run_s": round((ray1["wall_time"] - local["wall_time"]) / n, 3),
            "ray_init_s": ray1["init_time"],
            "scaling_1_to_2_workers": round(ray2["runs_per_minute"] / ray1["runs_per_minute"], 2),
            "in_process_runs_per_minute": local["runs_per_minute"],
        }

    print(
        f"{'section':<10} {'scenario':<12} {'engine':<6} {'wk':>2} {'ok/runs':>8} {'rate':>6} "
        f"{'wilson 95 %':>13} {'target':>6} {'wall s':>7} {'runs/min':>8} {'load':>5}"
    )
    for r in rows:
        lo, hi = r["wilson_95"]
        if "reading" in r:
            print(f"{'':<10} {r['cell']} read by: {r['reading']}")
        target = "-" if r["target"] is None else f"{r['target']:.0%}"
        print(
            f"{r['section']:<10} {r['scenario']:<12} {r['engine']:<6} {r['workers']:>2} "
            f"{r['successes']:>3}/{r['runs']:<4} {r['success_rate']:>6.1%} "
            f"{lo:>6.1%}-{hi:<6.1%} {target:>6} {r['wall_time']:>7.1f} "
            f"{r['runs_per_minute']:>8.2f} {r['load_avg']:>5.1f}"
        )
        for c in r["causes"]:
            print(f"{'':<10} {c['status']} x{c['count']} seeds {c['seeds']}: {c['cause']}")
    if scaling:
        print(
            f"simulations: Ray 1 worker - in-process {scaling['ray_overhead_per_run_s']:+.2f} s "
            f"per run (Ray start-up {scaling['ray_init_s']:.1f} s not included); "
            f"1 -> 2 workers: {scaling['scaling_1_to_2_workers']:.2f}x runs/min"
        )
    if engine_cost:
        e = engine_cost
        print(
            f"engine cost ({e['runs']} runs sleeping {e['sleep_s']:g} s): in-process "
            f"{e['local']['wall_time']:.2f} s, Ray 1 worker {e['ray1']['wall_time']:.2f} s, "
            f"2 workers {e['ray2']['wall_time']:.2f} s; Ray overhead per run "
            f"{e['ray_overhead_per_run_s'] * 1000:.0f} ms; Ray start-up "
            f"{e['ray1']['init_time']:.1f} s"
        )
    print(
        json.dumps(
            {
                "benchmark": "campaign",
                "machine": f"{platform.machine()} {os.cpu_count()} cpus",
                "targets": TARGETS,
                "rows": rows,
                "throughput": scaling,
                "engine_cost": engine_cost,
            }
        )
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
