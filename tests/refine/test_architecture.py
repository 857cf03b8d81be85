"""The calibrated architecture: routes per category, the thresholds, the rate each finds."""

from __future__ import annotations

import copy

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.errors import InputError
from tamp.refine.architecture import COMMAND, default_architecture, load_architecture
from tamp.refine.steps import refine_rate
from tamp.scenarios import path

ARCH = default_architecture()


def servers(category, stream):
    return [h.server for h in ARCH.network(category).routes[stream]]


def test_routes_follow_table_1():
    assert servers("I", "force") == ["C2.force", "C1"]
    assert servers("I", "imu") == ["C2.imu", "C1"]
    assert servers("I", COMMAND) == ["C1", "C2.A"]
    assert servers("II", "force") == ["C2.S", "CC", "C1"]
    assert servers("II", COMMAND) == ["C1", "CC", "C2.A"]
    assert servers("III", "odometry") == ["C2", "CC", "C1"]
    assert servers("III", COMMAND) == ["C1", "CC", "C2"]


def test_threshold_is_unloaded_worst_wait_plus_margin():
    m = ARCH.categories["II"]
    # C2.S: two other sensors; CC: a command and two sensors; C1: a command and two sensors
    expected = (
        2 * m.sub_cpu.sensor
        + m.channel.command
        + 2 * m.channel.sensor
        + m.main_cpu.command
        + 2 * m.main_cpu.sensor
        + ARCH.wait_margin
    )
    assert ARCH.wait_threshold("II", "force") == pytest.approx(expected)
    # below the knee the measured waits stay under it, at every rate from 1 Hz
    for p in range(1, 23):
        assert ARCH.probe_wait("II", 200.0, p) <= ARCH.wait_threshold("II", "force")


@pytest.mark.slow  # heavy for the quick loop; make test runs it
def test_task4_setting_finds_23_hz_and_categories_are_ordered():
    found = {
        c: refine_rate(ARCH.search(c, 10.0, 200.0), lambda p, c=c: ARCH.probe_wait(c, 200.0, p))
        for c in ("I", "II", "III")
    }
    assert found["II"].found == 23.0  # the paper's Task 4 rate
    assert found["I"].found > found["II"].found > found["III"].found > 10.0
    # the first rejected probe is past the knee of the busiest server
    rate, wait = found["II"].probes[-1]
    assert rate == 24.0 and wait > found["II"].threshold
    net = ARCH.network("II")
    assert max(net.utilisation(ARCH.rates(200.0, 24.0)).values()) > 1.0
    assert max(net.utilisation(ARCH.rates(200.0, 23.0)).values()) < 1.0


@pytest.mark.slow  # heavy for the quick loop; make test runs it
@settings(max_examples=5)
@given(sensor_rate=st.sampled_from([120.0, 160.0, 200.0]), start=st.integers(5, 15))
def test_categories_ordered_and_found_rate_below_the_knee(sensor_rate, start):
    """I >= II >= III for any setting, and the search stops at the knee: every server
    below saturation at the found rate, some server past it one step higher."""
    found = {}
    for c in ("I", "II", "III"):
        s = refine_rate(
            ARCH.search(c, float(start), sensor_rate),
            lambda p, c=c: ARCH.probe_wait(c, sensor_rate, p),
        )
        found[c] = s.found
        net = ARCH.network(c)
        assert max(net.utilisation(ARCH.rates(sensor_rate, s.found)).values()) <= 1.0 + 1e-9
        assert max(net.utilisation(ARCH.rates(sensor_rate, s.found + 1)).values()) > 1.0
    assert found["I"] >= found["II"] >= found["III"] >= start


def _arch_dict():
    return yaml.safe_load(path("refine/architecture.yaml").read_text())


@pytest.mark.parametrize(
    "edit,field",
    [
        (lambda d: d["categories"].pop("III"), "categories.III"),
        (lambda d: d["categories"]["I"].update(channel={"sensor": 0, "command": 0}), "I.channel"),
        (lambda d: d["categories"]["II"]["channel"].update(sensor=-1), "II.channel.sensor"),
        (lambda d: d["categories"]["II"]["main_cpu"].pop("command"), "main_cpu.command"),
        (lambda d: d.update(probe_window=0), "probe_window"),
        (lambda d: d.update(extra=1), "extra"),
    ],
)
def test_bad_architecture_files(tmp_path, edit, field):
    d = copy.deepcopy(_arch_dict())
    edit(d)
    f = tmp_path / "arch.yaml"
    f.write_text(yaml.safe_dump(d))
    with pytest.raises(InputError) as exc:
        load_architecture(f)
    assert field in exc.value.field
