"""How `tamp plan` scales with the size of a demonstration (issue "scale without cliffs").

Instances come from `tests.demo.generate` (the same generator the tests use):

* ``multi`` — n steps over n/3 objects in a row, each object moved three times up its own
  column (independent goal chains: a wide RG, an exact search over many interleavings);
* ``one`` — n steps of a single object (one chain: a path-shaped RG of n+1 states);
* ``wide`` — n objects in a row, each moved once (n interleavable goals, many equal-cost
  orders: where a plateau of equal f used to make the search wander for minutes).

Each instance runs in its own process (so peak memory is its own): parse (load and derive
C), plan (A* + RG statistics), gate (the order check and, when small enough, the whole
RG), each timed, plus the process's peak resident memory. A demonstration above the
loader's limits is refused (exit 2) and the row says so.

    python benchmarks/demo_scale.py       # 300 multi, 1000 multi, 1000 wide, 5000/20000/50000 one
    python benchmarks/demo_scale.py --cases 300:multi 20000:one

Prints a table and one JSON line (``{"benchmark": "demo_scale", "rows": [...]}``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DEFAULT = ["300:multi", "1000:multi", "1000:wide", "5000:one", "20000:one", "50000:one"]


def measure(path: str) -> dict:
    """Run parse, plan and gate on one file in this process; peak memory from rusage."""
    import resource

    from tamp import fileio
    from tamp.demo import load_demonstration
    from tamp.errors import TampError
    from tamp.rg import plan
    from tamp.verification.gate import gate_order

    c_scanner = fileio._LOADER is not fileio._StrictLoader
    row: dict = {"yaml_loader": "libyaml" if c_scanner else "pure-python"}
    t0 = time.perf_counter()
    try:
        demo = load_demonstration(path)
    except TampError as exc:
        row.update(refused=str(exc), exit=exc.exit_code, parse_s=time.perf_counter() - t0)
        return row
    t1 = time.perf_counter()
    result = plan(demo)
    stats = result.rg
    t2 = time.perf_counter()
    report = gate_order(result)
    t3 = time.perf_counter()
    row.update(
        steps=len(demo.goals),
        objects=len(demo.objects),
        parse_s=t1 - t0,
        plan_s=t2 - t1,
        gate_s=t3 - t2,
        cost=result.cost,
        expanded=result.expanded,
        rg_states=stats.states,
        gate_notes=report.notes,
        peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    )
    return row


def run_case(spec: str, workdir: Path) -> dict:
    n_text, kind = spec.split(":")
    n = int(n_text)
    path = workdir / f"demo_{n}_{kind}.yaml"
    from tests.demo.generate import write_demo

    write_demo(path, n, kind)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path.cwd()), *sys.path]))
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, __file__, "--measure", str(path)],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        return {"case": spec, "error": proc.stderr.strip().splitlines()[-1:], "wall_s": wall}
    row = json.loads(proc.stdout)
    return {"case": spec, **row, "wall_s": wall}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=DEFAULT, metavar="N:KIND")
    ap.add_argument("--measure", metavar="FILE", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.measure:
        print(json.dumps(measure(args.measure)))
        return 0
    rows = []
    header = f"{'case':>12} {'steps':>6} {'objs':>5} {'parse s':>8} {'plan s':>7} {'gate s':>7}"
    header += f" {'wall s':>7} {'peak MB':>8}  note"
    print(header)
    print("-" * len(header))
    with tempfile.TemporaryDirectory() as tmp:
        for spec in args.cases:
            r = run_case(spec, Path(tmp))
            rows.append(r)
            if "refused" in r or "error" in r:
                note = r.get("refused") or r.get("error")
                print(
                    f"{spec:>12} {'':>6} {'':>5} {r.get('parse_s', 0):8.2f} {'':>7} {'':>7}"
                    f" {r['wall_s']:7.2f} {'':>8}  refused: {note}"
                )
                continue
            note = "; ".join(r["gate_notes"])
            print(
                f"{spec:>12} {r['steps']:6d} {r['objects']:5d} {r['parse_s']:8.2f} "
                f"{r['plan_s']:7.2f} {r['gate_s']:7.2f} {r['wall_s']:7.2f} {r['peak_mb']:8.0f}"
                f"  {note}"
            )
    if rows and "yaml_loader" in rows[0]:
        print(f"YAML: {rows[0]['yaml_loader']} scanner")
    print(json.dumps({"benchmark": "demo_scale", "rows": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
