"""Verification speed: a 1,000-step trace, an RG of 2^12 states, a BT of the Case 3 size,
and both plan gates on generated demonstrations of 10 / 30 / 72 / 300 goals.

Each row of the first table is measured side by side with a peer in the same run:
- trace: our check (automaton of f, conjunct by conjunct, shortest-bad-prefix walk) vs the
  direct Spot route (translate !f, ``parse_word``, ``intersects``; what the tests use as
  oracle); for LTLf, vs a direct recursive evaluator of the formula on the trace;
- RG: our Kripke check (one small negated automaton per conjunct) vs Spot on the whole
  negated formula (one translation of ``!(F g0 & … & F g11)``, then ``intersecting_run``);
- BT: our exploration of every execution (skill failures up to k) vs one plain symbolic
  execution of the same executor (`tamp.bt.SymbolicWorld`), i.e. the cost per execution.

The scale table (``--scale``): demonstrations of four objects, each moved up its own column
(`tests.demo.generate`, ``multi`` with 4 objects: 72 goals = four chains of 18 steps). Per
size: the tree gate (`tamp.verification.gate.gate_tree`: every execution of the grown tree, at
most one skill failure; states explored, wall and CPU seconds), the same exploration without
the reduction where it runs in reasonable time (``--explicit-up-to``), and the order gate
(`tamp.verification.gate.gate_order`).

Prints the tables and one JSON line; ``--out FILE`` also writes the JSON there
(``benchmarks/results/verify.json`` is the committed run). ``--quick`` skips the slow
whole-formula RG peer; ``--scale-only`` runs only the scale table.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tamp import ltl  # noqa: E402
from tamp.bt import Appear, SymbolicWorld  # noqa: E402
from tamp.demo import load_demonstration, make_demonstration  # noqa: E402
from tamp.ltl.automata import accepts_lasso  # noqa: E402
from tamp.ltl.kripke import intersecting_lasso  # noqa: E402
from tamp.rg import build_rg  # noqa: E402
from tamp.scenarios import path  # noqa: E402
from tamp.verification.bt import check_tree, executor_for  # noqa: E402
from tamp.verification.kripke import to_kripke  # noqa: E402
from tamp.verification.rg import constraint_formula, rg_system  # noqa: E402
from tamp.verification.traces import check_trace  # noqa: E402
from tamp.verification.words import Word  # noqa: E402
from tamp.world import Point  # noqa: E402

#: the sizes of the scale table (goals; four objects)
SCALE_GOALS = (10, 30, 72, 300)


def timed(fn, repeat: int = 5) -> tuple[float, object]:
    """Median wall time (s) over ``repeat`` calls after one warm-up; and the last result."""
    out = fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def cold(fn) -> tuple[float, object]:
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def spot_lasso_holds(f: ltl.Formula, word: Word) -> bool:
    """The direct route: the automaton of !f (Spot's 'high' level), product with the word."""
    neg = ltl.translate(ltl.negate(f), ltl.Options(level="high", pref="small"))
    return not accepts_lasso(neg, word.prefix, word.cycle)[0]


def direct_ltlf(f: ltl.Formula, trace) -> bool:
    """A direct dynamic-programming LTLf evaluator (backwards over positions)."""
    n = len(trace)
    memo: dict = {}

    def ev(g):
        key = str(g)
        if key in memo:
            return memo[key]
        k = g.kindstr()
        c = list(g)
        if k == "ap":
            vals = [g.ap_name() in x for x in trace]
        elif k == "tt":
            vals = [True] * n
        elif k == "Not":
            vals = [not v for v in ev(c[0])]
        elif k == "And":
            cs = [ev(x) for x in c]
            vals = [all(v) for v in zip(*cs, strict=True)]
        elif k == "F":
            a, vals, acc = ev(c[0]), [False] * n, False
            for i in range(n - 1, -1, -1):
                acc = acc or a[i]
                vals[i] = acc
        elif k == "G":
            a, vals, acc = ev(c[0]), [False] * n, True
            for i in range(n - 1, -1, -1):
                acc = acc and a[i]
                vals[i] = acc
        else:
            raise ValueError(k)
        memo[key] = vals
        return vals

    return n > 0 and ev(f)[0]


def bench_trace(n: int = 1000) -> list[dict]:
    rows = []
    phi = ltl.parse("GF p1 & GF p2 & GF p3 & GF p4 & G(p1 -> !p2)")
    letters = [frozenset({f"p{1 + i % 4}"}) for i in range(n)]
    word = Word.lasso(letters[:-4], letters[-4:])
    ltl.clear_cache()
    t_cold, _ = cold(lambda: check_trace(phi, word))
    t_ours, v = timed(lambda: check_trace(phi, word))
    t_peer, peer = timed(lambda: spot_lasso_holds(phi, word))
    assert v.holds == peer
    rows.append(
        dict(
            case=f"lasso trace, {n} steps",
            formula=str(phi),
            holds=v.holds,
            states=v.states_explored,
            ours_ms=t_ours * 1e3,
            ours_cold_ms=t_cold * 1e3,
            peer="Spot !f product",
            peer_ms=t_peer * 1e3,
        )
    )
    bad = Word.lasso(
        letters[: n // 2] + [frozenset({"p1", "p2"})] + letters[n // 2 :], [frozenset()]
    )
    t_bad, vb = timed(lambda: check_trace(phi, bad))
    t_peer_bad, pb = timed(lambda: spot_lasso_holds(phi, bad))
    assert vb.holds == pb is False
    rows.append(
        dict(
            case=f"lasso trace, {n + 1} steps, violated (with explanation)",
            formula=str(phi),
            holds=False,
            states=vb.states_explored,
            ours_ms=t_bad * 1e3,
            ours_cold_ms=None,
            peer="Spot !f product (verdict only)",
            peer_ms=t_peer_bad * 1e3,
            bad_prefix=vb.counterexample.position,
        )
    )
    tower = ltl.parse("F(p1 & F(p2 & F p3)) & G !bad")
    fin = [frozenset()] * (n - 3) + [frozenset({"p1"}), frozenset({"p2"}), frozenset({"p3"})]
    t_fin, vf = timed(lambda: check_trace(tower, Word.finite(fin), finite=True))
    t_dir, dv = timed(lambda: direct_ltlf(tower, fin))
    assert vf.holds == dv
    rows.append(
        dict(
            case=f"finite trace (LTLf), {n} steps",
            formula=str(tower),
            holds=vf.holds,
            states=vf.states_explored,
            ours_ms=t_fin * 1e3,
            ours_cold_ms=None,
            peer="direct LTLf evaluator",
            peer_ms=t_dir * 1e3,
        )
    )
    return rows


def bench_rg(n: int = 12, quick: bool = False) -> list[dict]:
    objects = {f"O{i}": Point(float(i), 0.0) for i in range(n)}
    steps = [(f"O{i}", Point(float(i), 3.0)) for i in range(n)]
    demo = make_demonstration(objects, steps, 0.15, source=f"<{n} independent goals>")
    rg = build_rg(demo)
    f = constraint_formula(demo.goal_ids, demo.constraints)
    from tamp.verification.rg import check_graph

    t_ours, v = timed(lambda: check_graph(demo, rg), repeat=3)
    peer_ms = None
    if not quick:

        def whole():  # 'high' on the whole negation takes 12-45 s: lift the time limit
            neg = ltl.translate(
                ltl.negate(f), ltl.Options(level="high"), limits=ltl.Limits(seconds=600)
            )
            return intersecting_lasso(to_kripke(rg_system(rg), ltl.ap_names(f), neg), neg) is None

        t_peer, ok = cold(whole)
        assert ok == v.holds
        peer_ms = t_peer * 1e3
    return [
        dict(
            case=f"RG, {n} goals, all paths",
            formula=f"{len(ltl.conjuncts(f))} conjuncts",
            holds=v.holds,
            states=rg.number_of_nodes(),
            ours_ms=t_ours * 1e3,
            ours_cold_ms=None,
            peer="Spot whole !f (1 translation)",
            peer_ms=peer_ms,
        )
    ]


def bench_bt() -> list[dict]:
    demo = load_demonstration(path("case3.yaml"))
    events = [Appear("Oa", demo.goal("G1").area.pos)]
    exe = executor_for(demo)

    def one_run():
        w = SymbolicWorld(demo.initial_world(), skill_ticks=1, events=events)
        e = executor_for(demo)
        return e.run(w, step=w.step)

    t_peer, _ = timed(one_run, repeat=5)
    rows = []
    for k in (0, 1, 2):
        t, r = timed(
            lambda k=k: check_tree(exe, demo.initial_world(), events=events, max_failures=k),
            repeat=1,
        )
        rows.append(
            dict(
                case=f"BT Case 3 (+O_a), ≤{k} skill failure(s), 3 properties",
                formula="G!placed_in_occupied, G(holding_count<=1), F goal",
                holds=r.holds,
                states=r.states_explored,
                ours_ms=t * 1e3,
                ours_cold_ms=None,
                peer="1 symbolic execution",
                peer_ms=t_peer * 1e3,
            )
        )
    return rows


def _clocked(fn) -> tuple[float, float, object]:
    """Wall and CPU seconds of one call, and its result."""
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - w, time.process_time() - c, out


def bench_scale(sizes=SCALE_GOALS, explicit_up_to: int = 10) -> list[dict]:
    """Both plan gates on four chains of goals of each size (module docstring)."""
    import tempfile

    from tests.demo.generate import write_demo

    with tempfile.TemporaryDirectory() as tmp:
        return [
            scale_row(
                load_demonstration(write_demo(Path(tmp) / f"d{n}.yaml", n, "multi", 4)),
                explicit=n <= explicit_up_to,
            )
            for n in sizes
        ]


def scale_row(demo, *, explicit: bool) -> dict:
    """One size: the tree gate, the explicit exploration (when ``explicit``), the order gate."""
    from tamp.rg import plan
    from tamp.verification.gate import gate_order, gate_tree

    result = plan(demo)
    order = list(result.order)
    state = demo.initial_world()
    wall, cpu, tree = _clocked(lambda: gate_tree(executor_for(demo, order), state))
    row = dict(
        goals=len(demo.goals),
        tree_status=tree.status,
        tree_states=tree.states_explored,
        tree_s=wall,
        tree_cpu_s=cpu,
        explicit_states=None,
        explicit_s=None,
    )
    if explicit:
        ew, _, full = _clocked(lambda: check_tree(executor_for(demo, order), state, reduce=False))
        assert full.status == tree.status
        row.update(explicit_states=full.states_explored, explicit_s=ew)
    ow, ocpu, checked = _clocked(lambda: gate_order(result))
    row.update(
        order_status=checked.status,
        order_states=checked.states_explored,
        order_s=ow,
        order_cpu_s=ocpu,
    )
    return row


def print_scale(rows: list[dict]) -> None:
    head = (
        f"{'goals':>5} {'tree':>6} {'states':>7} {'wall s':>7} {'cpu s':>6} "
        f"{'explicit states':>15} {'explicit s':>10} {'order':>6} {'order s':>8}"
    )
    print(head)
    print("-" * len(head))
    for r in rows:
        es = "-" if r["explicit_states"] is None else str(r["explicit_states"])
        et = "-" if r["explicit_s"] is None else f"{r['explicit_s']:.2f}"
        print(
            f"{r['goals']:>5} {r['tree_status']:>6} {r['tree_states']:>7} {r['tree_s']:>7.2f} "
            f"{r['tree_cpu_s']:>6.2f} {es:>15} {et:>10} {r['order_status']:>6} "
            f"{r['order_s']:>8.3f}"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the slow whole-formula RG peer")
    ap.add_argument("--scale-only", action="store_true", help="only the 10/30/72/300 table")
    ap.add_argument(
        "--explicit-up-to",
        type=int,
        default=30,
        metavar="GOALS",
        help="run the unreduced exploration too up to this many goals (default 30)",
    )
    ap.add_argument("--out", metavar="FILE", help="also write the JSON document to FILE")
    args = ap.parse_args()
    rows: list[dict] = []
    if not args.scale_only:
        rows = bench_trace() + bench_rg(quick=args.quick) + bench_bt()
        head = f"{'case':<52} {'holds':>5} {'states':>7} {'ours ms':>9} {'peer ms':>9}  peer"
        print(head)
        print("-" * len(head))
        for r in rows:
            peer = "-" if r["peer_ms"] is None else f"{r['peer_ms']:9.1f}"
            print(
                f"{r['case']:<52} {str(r['holds']):>5} {r['states']:>7} {r['ours_ms']:9.1f} "
                f"{peer:>9}  {r['peer']}"
            )
        print()
    scale = bench_scale(explicit_up_to=args.explicit_up_to)
    print_scale(scale)
    doc = {
        "benchmark": "verify",
        "machine": {"cpus": os.cpu_count(), "load_1min": os.getloadavg()[0]},
        "rows": rows,
        "scale": scale,
    }
    text = json.dumps(doc, default=str)
    print(text)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(doc, default=str, indent=1) + "\n")


if __name__ == "__main__":
    main()
