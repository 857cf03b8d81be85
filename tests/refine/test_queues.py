"""The FIFO network: hand-computed cases, incremental = batch, and the knee at rho = 1."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tamp.refine.architecture import COMMAND, default_architecture
from tamp.refine.queues import Hop, Network, deliver, max_wait, periodic, periodic_waits

NET = Network({"s": (Hop("A", 1.0), Hop("B", 2.0)), "c": (Hop("B", 3.0),)})


def test_lindley_by_hand():
    out = deliver(NET, [("s", 0.0, "x"), ("c", 0.5, "y"), ("s", 0.5, "z")])
    got = {(d.message.stream, d.message.created): (d.time, d.wait) for d in out}
    # c@0.5 reaches B first: B 0.5-3.5. s@0: A 0-1, B (arrives 1) 3.5-5.5, wait 2.5.
    # s@0.5: A 1-2 (wait 0.5), B (arrives 2) 5.5-7.5, wait 0.5 + 3.5.
    assert got[("c", 0.5)] == (3.5, 0.0)
    assert got[("s", 0.0)] == (5.5, 2.5)
    assert got[("s", 0.5)] == (7.5, 4.0)
    assert [d.message.value for d in out] == ["y", "x", "z"]
    assert out[2].latency == pytest.approx(7.0)


def test_idle_network_has_no_wait():
    out = deliver(NET, [("s", 10.0 * k, None) for k in range(5)])
    assert [d.wait for d in out] == [0.0] * 5
    assert [d.time for d in out] == [3.0 + 10.0 * k for k in range(5)]


def test_rejects_bad_routes_and_past_messages():
    with pytest.raises(ValueError):
        Network({"s": ()})
    with pytest.raises(ValueError):
        Network({"s": (Hop("A", -1.0),)})
    state, _ = NET.advance(NET.initial(), 5.0)
    with pytest.raises(ValueError, match="before the queue time"):
        NET.inject(state, [("s", 1.0, None)])
    with pytest.raises(KeyError):
        NET.inject(state, [("x", 6.0, None)])


@given(
    times=st.lists(st.floats(0, 20, allow_nan=False), min_size=1, max_size=40),
    streams=st.lists(st.sampled_from(["s", "c"]), min_size=40, max_size=40),
    cuts=st.lists(st.floats(0, 40, allow_nan=False), max_size=6),
)
def test_incremental_advance_equals_batch(times, streams, cuts):
    items = sorted(((streams[i], t, i) for i, t in enumerate(times)), key=lambda x: x[1])
    batch = [(d.message.value, d.time, d.wait) for d in deliver(NET, items)]
    state = NET.initial()
    got = []
    todo = list(items)
    for cut in sorted(cuts) + [math.inf]:
        now = [x for x in todo if x[1] <= cut]
        todo = [x for x in todo if x[1] > cut]
        state, _ = NET.inject(state, now)
        state, out = NET.advance(state, cut)
        got += [(d.message.value, d.time, d.wait) for d in out]
    assert got == batch


def test_periodic_streams():
    assert [t for _, t, _ in periodic("s", 4.0, 1.0, 2.0)] == [1.0, 1.25, 1.5, 1.75]
    assert periodic("s", 4.0, 1.0, 1.0) == []


ARCH = default_architecture()


@given(
    category=st.sampled_from(["I", "II", "III"]),
    p1=st.integers(1, 60),
    dp=st.integers(1, 30),
    sensor_rate=st.sampled_from([100.0, 150.0, 200.0]),
)
def test_wait_grows_with_the_command_rate(category, p1, dp, sensor_rate):
    """Monotone up to phase effects: never shorter by more than the longest service on the
    sensor's route, and clearly longer once the busiest server is past rho = 1."""
    net = ARCH.network(category)
    p2 = p1 + dp
    w1, w2 = (
        max_wait(
            periodic_waits(
                net,
                ARCH.rates(
                    sensor_rate,
                    p,
                ),
                1.0,
            ),
            ["force"],
        )
        for p in (p1, p2)
    )
    slack = max(h.service for r in net.routes.values() for h in r)
    assert w2 >= w1 - slack
    rho1 = max(net.utilisation(ARCH.rates(sensor_rate, p1)).values())
    rho2 = max(net.utilisation(ARCH.rates(sensor_rate, p2)).values())
    if rho1 < 0.95 and rho2 > 1.05:
        assert w2 > w1 + 0.02


def test_saturated_backlog_grows_linearly():
    net = ARCH.network("II")
    rates = ARCH.rates(200.0, 30.0)
    rho = max(net.utilisation(rates).values())
    assert rho > 1.05
    waits = periodic_waits(net, rates, 4.0)["imu"]
    first, last = waits[len(waits) // 4], waits[-1]
    # the backlog grows by (rho - 1) seconds of work per second, within a few messages
    assert last - first == pytest.approx((rho - 1) * 3.0, rel=0.15)
    assert COMMAND in rates
