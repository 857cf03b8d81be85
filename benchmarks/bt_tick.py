"""Tick cost per node: our flat recursive executor vs py_trees 2.6 on the same grown tree.

Tree shape (what Alg. 3 grows for one condition, one "action unit"):

    SequenceWithMemory
      ReactiveFallback(cond_i, PriorityFallback(ReactiveSequence(pre_a_i, pre_b_i, Act_i)))   × N

Scenario "full": every cond_i fails, every pre_* holds, every action succeeds at its first
poll, so one tick visits all 7·N + 1 nodes (checked by counting on both sides).
Scenario "steady": the root is a ReactiveSequence, units 1..N-1 are achieved (their guard
holds: 2 nodes each) and the last unit's action is RUNNING: 2·(N-1) + 8 nodes per tick, the
usual state of a grown tree between growth steps. Conditions read a constant (the same
trivial callable on both sides), so the figures are the executors' own overhead. In
py_trees: Sequence(memory=True), Selector(memory=False) for the reactive fallback,
Selector(memory=True) for the priority fallback, Sequence(memory=False) for the reactive
sequence, and Behaviours for conditions and actions; ticked with ``root.tick_once()``.

Prints a table and one JSON line: µs per ticked node for N = 100 and 1000, and the ratio.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from dataclasses import dataclass

from tamp.bt.executor import PaBtExecutor
from tamp.bt.nodes import (
    ActionNode,
    Condition,
    PriorityFallback,
    ReactiveFallback,
    ReactiveSequence,
    Sequence,
)
from tamp.world.actions import Action, ActionTemplate
from tamp.world.interface import Status
from tamp.world.predicates import Predicate


@dataclass(frozen=True)
class Const(Predicate):
    """A condition whose value is fixed (same cost on both sides)."""

    label: str
    value: bool
    name = "Const"

    def holds(self, state) -> bool:
        return self.value


class InstantWorld:
    """Every skill succeeds at its first poll."""

    def __init__(self) -> None:
        self._n = 0

    def observe(self):
        return None

    def start(self, action) -> int:
        self._n += 1
        return self._n

    def poll(self, handle: int) -> Status:
        return Status.SUCCESS

    def cancel(self, handle: int) -> None:
        pass


def build_ours(n: int, steady: bool = False) -> PaBtExecutor:
    """N action units as the PA-BT grows them.

    ``steady=False``: nothing achieved yet, every node is ticked (a memory Sequence root);
    ``steady=True``: N-1 achieved units re-checked reactively while the last one's action
    runs (a ReactiveSequence root).
    """
    ex = PaBtExecutor([Const("goal", True)], record_attempts=False, max_repeats=10**9)
    units = []
    for i in range(n):
        act = Action(ActionTemplate(f"Act{i}", (), (), ()), (), (), ())
        rs = ReactiveSequence(
            [Condition(Const(f"a{i}", True)), Condition(Const(f"b{i}", True)), ActionNode(act)]
        )
        done = steady and i < n - 1
        units.append(
            ReactiveFallback([Condition(Const(f"c{i}", done)), PriorityFallback([rs], [1.0])])
        )
    ex.root = ReactiveSequence(units) if steady else Sequence(units, memory=True)
    return ex


def build_py_trees(n: int, steady: bool = False):
    """The same tree shape in py_trees 2.6 (memoryless Sequence/Selector = reactive nodes)."""
    import py_trees
    from py_trees.common import Status as PS

    class Cond(py_trees.behaviour.Behaviour):
        def __init__(self, name: str, value: bool) -> None:
            super().__init__(name)
            self.pred = Const(name, value)

        def update(self):
            return PS.SUCCESS if self.pred.holds(None) else PS.FAILURE

    class Act(py_trees.behaviour.Behaviour):
        def update(self):
            return PS.RUNNING if steady else PS.SUCCESS

    units = []
    for i in range(n):
        rs = py_trees.composites.Sequence(
            f"rs{i}",
            memory=False,
            children=[Cond(f"a{i}", True), Cond(f"b{i}", True), Act(f"Act{i}")],
        )
        pf = py_trees.composites.Selector(f"pf{i}", memory=True, children=[rs])
        units.append(
            py_trees.composites.Selector(
                f"rf{i}", memory=False, children=[Cond(f"c{i}", steady and i < n - 1), pf]
            )
        )
    return py_trees.composites.Sequence("root", memory=not steady, children=units)


class RunningWorld(InstantWorld):
    def poll(self, handle: int) -> Status:
        return Status.RUNNING


def _ours_runner(ex: PaBtExecutor, world):
    def run(ticks: int) -> None:
        for _ in range(ticks):
            ex.result = None
            ex.tick(world)

    return run


def _py_trees_runner(root):
    def run(ticks: int) -> None:
        for _ in range(ticks):
            root.tick_once()

    return run


def measure(scenario: str, n: int, node_ticks: int, repeats: int) -> dict:
    """Both executors, interleaved ``repeats`` times (the machine may be shared); best of."""
    from py_trees.common import Status as PS

    if scenario == "full":
        ex, world, root = build_ours(n), InstantWorld(), build_py_trees(n)
    else:
        ex, world, root = build_ours(n, True), RunningWorld(), build_py_trees(n, True)
    ex.tick(world)
    root.tick_once()
    v_ours = sum(1 for node in ex.root.walk() if node.tick_id == ex.tick_id)
    v_peer = sum(1 for node in root.iterate() if node.status != PS.INVALID)
    expected = 7 * n + 1 if scenario == "full" else 2 * (n - 1) + 7 + 1
    assert v_ours == v_peer == expected, (v_ours, v_peer, expected)
    ticks = max(3, node_ticks // expected)
    ours_run, peer_run = _ours_runner(ex, world), _py_trees_runner(root)
    best_ours = best_peer = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        ours_run(ticks)
        t1 = time.perf_counter()
        peer_run(ticks)
        t2 = time.perf_counter()
        best_ours = min(best_ours, (t1 - t0) / ticks)
        best_peer = min(best_peer, (t2 - t1) / ticks)
    return {
        "scenario": scenario,
        "units": n,
        "nodes_per_tick": expected,
        "ours_us_per_node": best_ours / expected * 1e6,
        "py_trees_us_per_node": best_peer / expected * 1e6,
        "speedup": best_peer / best_ours,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[100, 1000])
    p.add_argument("--node-ticks", type=int, default=200_000, help="nodes ticked per batch")
    p.add_argument("--repeats", type=int, default=7, help="interleaved batches (best is kept)")
    args = p.parse_args(argv)
    rows = [
        measure(scenario, n, args.node_ticks, args.repeats)
        for scenario in ("full", "steady")
        for n in args.sizes
    ]
    print(
        f"{'scenario':>8} {'units':>6} {'nodes/tick':>10} {'ours µs/node':>13} "
        f"{'py_trees µs/node':>17} {'speedup':>8}"
    )
    for r in rows:
        print(
            f"{r['scenario']:>8} {r['units']:>6} {r['nodes_per_tick']:>10} "
            f"{r['ours_us_per_node']:>13.3f} {r['py_trees_us_per_node']:>17.3f} "
            f"{r['speedup']:>7.1f}x"
        )
    print(
        json.dumps(
            {
                "benchmark": "bt_tick",
                "python": platform.python_version(),
                "rows": [
                    {k: round(v, 4) if isinstance(v, float) else v for k, v in r.items()}
                    for r in rows
                ],
            }
        )
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
