"""Verification speed: a 1,000-step trace, an RG of 2^12 states, a BT of the Case 3 size.

Each row is measured side by side with a peer in the same run:
- trace: our check (automaton of f, conjunct by conjunct, shortest-bad-prefix walk) vs the
  direct Spot route (translate !f, ``parse_word``, ``intersects``; what the tests use as
  oracle); for LTLf, vs a direct recursive evaluator of the formula on the trace;
- RG: our Kripke check (one small negated automaton per conjunct) vs Spot on the whole
  negated formula (one translation of ``!(F g0 & … & F g11)``, then ``intersecting_run``);
- BT: our exploration of every execution (skill failures up to k) vs one plain symbolic
  execution of the same executor (`tamp.bt.SymbolicWorld`), i.e. the cost per execution.

Prints a table and one JSON line. ``--quick`` skips the slow whole-formula RG peer.
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

import spot  # noqa: E402

from tamp.bt import Appear, SymbolicWorld  # noqa: E402
from tamp.demo import load_demonstration, make_demonstration  # noqa: E402
from tamp.rg import build_rg  # noqa: E402
from tamp.scenarios import path  # noqa: E402
from tamp.world import Point  # noqa: E402
from verification import ltl  # noqa: E402
from verification.bt import check_tree, executor_for  # noqa: E402
from verification.kripke import to_kripke  # noqa: E402
from verification.rg import constraint_formula, rg_system  # noqa: E402
from verification.traces import check_trace  # noqa: E402
from verification.words import Word  # noqa: E402


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


def spot_lasso_holds(f: spot.formula, word: Word) -> bool:
    neg = spot.translate(spot.formula.Not(f), "Buchi", "SBAcc", "small", "high")
    aps = sorted(a.ap_name() for a in spot.atomic_prop_collect(f))

    def lit(x):
        return " & ".join(a if a in x else f"!{a}" for a in aps)

    text = (
        "; ".join(lit(x) for x in word.prefix)
        + "; cycle{"
        + "; ".join(lit(x) for x in word.cycle)
        + "}"
    )
    w = spot.parse_word(text, neg.get_dict())
    return not neg.intersects(w.as_automaton())


def direct_ltlf(f: spot.formula, trace) -> bool:
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
    phi = spot.formula("GF p1 & GF p2 & GF p3 & GF p4 & G(p1 -> !p2)")
    letters = [frozenset({f"p{1 + i % 4}"}) for i in range(n)]
    word = Word.lasso(letters[:-4], letters[-4:])
    ltl._buchi.cache_clear()
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
    tower = spot.formula("F(p1 & F(p2 & F p3)) & G !bad")
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
    from verification.rg import check_graph

    t_ours, v = timed(lambda: check_graph(demo, rg), repeat=3)
    peer_ms = None
    if not quick:

        def whole():
            bd = spot.make_bdd_dict()
            k = to_kripke(rg_system(rg), ltl.ap_names(f), bd)
            neg = spot.translate(spot.formula.Not(f), "Buchi", "SBAcc", "small", "high", dict=bd)
            return k.intersecting_run(neg) is None

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the slow whole-formula RG peer")
    args = ap.parse_args()
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
    print(json.dumps({"benchmark": "verify", "rows": rows}, default=str))


if __name__ == "__main__":
    main()
