"""The campaign's statistics: Wilson interval (known values and scipy), distributions,
cause grouping and success by perturbation size."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binomtest

from tamp.campaign.stats import (
    Distribution,
    group_causes,
    percentile,
    success_by_size,
    wilson_interval,
)


@pytest.mark.parametrize(
    ("k", "n", "lo", "hi"),
    [
        (0, 10, 0.0, 0.2775),  # z²/(n+z²)
        (10, 10, 0.7225, 1.0),
        (8, 10, 0.4902, 0.9433),
        (5, 10, 0.2366, 0.7634),
        (1, 1, 0.2065, 1.0),
    ],
)
def test_wilson_known_values(k, n, lo, hi):
    got = wilson_interval(k, n)
    assert got == pytest.approx((lo, hi), abs=1e-4)


@pytest.mark.parametrize(("k", "n"), [(48, 50), (19, 20), (0, 3), (3, 3), (7, 31), (95, 100)])
def test_wilson_agrees_with_scipy(k, n):
    ci = binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    assert wilson_interval(k, n) == pytest.approx((ci.low, ci.high), abs=1e-9)


def test_wilson_edges():
    assert wilson_interval(0, 0) == (0.0, 1.0)
    lo, hi = wilson_interval(50, 50)
    assert hi == 1.0 and 0.92 < lo < 0.93  # 50/50 still leaves ~7 % below
    with pytest.raises(ValueError):
        wilson_interval(3, 2)
    with pytest.raises(ValueError):
        wilson_interval(-1, 2)


def test_wilson_interval_holds_the_observed_rate():
    """Also at 0 and n successes, where rounding once put 10/10 a hair above the upper
    bound and a campaign's plot failed on a negative error bar."""
    for n in range(1, 200):
        for k in range(n + 1):
            lo, hi = wilson_interval(k, n)
            assert 0.0 <= lo <= k / n <= hi <= 1.0


def test_percentile_matches_numpy():
    xs = sorted([3.0, 1.5, 9.0, 4.25, 7.0, 2.0, 8.5])
    for q in (0, 10, 50, 90, 100):
        assert percentile(xs, q) == pytest.approx(float(np.percentile(xs, q)))


def test_distribution():
    d = Distribution.of([40.0, 10.0, 20.0, 30.0])
    assert (d.n, d.mean, d.median, d.min, d.max) == (4, 25.0, 25.0, 10.0, 40.0)
    assert d.p90 == pytest.approx(37.0)
    assert Distribution.of([]).to_json() == {
        "n": 0,
        "mean": None,
        "median": None,
        "p90": None,
        "min": None,
        "max": None,
    }


def test_group_causes_most_frequent_first_with_seeds():
    runs = [
        (0, "success", None),
        (5, "failure", "dropped O1"),
        (1, "failure", "dropped O1"),
        (2, "crash", "RuntimeError: boom"),
        (7, "failure", "dropped O1"),
        (3, "timeout", "killed after the 5 s wall-time limit"),
        (4, "failure", None),
    ]
    groups = group_causes(runs)
    assert [(g.status, g.cause, g.seeds) for g in groups] == [
        ("failure", "dropped O1", (1, 5, 7)),
        ("crash", "RuntimeError: boom", (2,)),
        ("timeout", "killed after the 5 s wall-time limit", (3,)),
        ("failure", "(no cause given)", (4,)),
    ]
    assert groups[0].to_json()["count"] == 3


def test_success_by_size_bins():
    runs = [(0.0, True), (0.1, True), (0.2, False), (0.9, False), (1.0, False), (0.5, True)]
    bins = success_by_size(runs, bins=5)
    assert [(round(b.lo, 2), b.n, b.successes) for b in bins] == [
        (0.0, 2, 2),
        (0.2, 1, 0),
        (0.4, 1, 1),
        (0.8, 2, 0),
    ]
    assert sum(b.n for b in bins) == len(runs)
    one = success_by_size([(0.0, True), (0.0, False)])
    assert len(one) == 1 and one[0].rate == 0.5
    assert success_by_size([]) == []
