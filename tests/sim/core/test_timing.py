"""Where a run's time goes (`tamp.sim.core.timing`): stopwatches and the breakdown."""

from __future__ import annotations

import time

import pytest

from tamp.sim.core.timing import Stopwatch, breakdown


def test_stopwatch_accumulates_wall_and_cpu():
    sw = Stopwatch()
    for _ in range(2):
        with sw:
            t = time.process_time()
            while time.process_time() - t < 0.02:  # busy: CPU time advances too
                pass
    assert sw.calls == 2
    assert sw.cpu >= 0.04 and sw.wall >= sw.cpu * 0.5
    sw.reset()
    assert (sw.wall, sw.cpu, sw.calls) == (0.0, 0.0, 0)


def test_breakdown_gives_the_rest_to_physics_and_shares_sum_to_one():
    parts = {"render": Stopwatch(1.0, 0.5, 3), "network": Stopwatch(2.0, 1.5, 4)}
    out = breakdown(10.0, 4.0, parts)
    assert out["physics"]["wall"] == 7.0 and out["physics"]["cpu"] == 2.0
    assert out["render"]["wall_share"] == 0.1 and out["network"]["cpu_share"] == 0.375
    assert sum(r["cpu_share"] for r in out.values()) == pytest.approx(1.0)
