"""The calibrated architecture: routes per category, the thresholds, the rate each finds."""

from __future__ import annotations

import copy
from dataclasses import replace

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from tamp.errors import InputError
from tamp.refine.architecture import (
    COMMAND,
    behavior_searches,
    default_architecture,
    load_architecture,
)
from tamp.refine.steps import (
    Parallelization,
    apply_rate,
    behavior_rates,
    join,
    refine_rate,
)
from tamp.scenarios import path
from tests.refine.helpers import task

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
    below saturation at the found rate, some server past it one step higher, unless the
    search reached its limit first (the main CPU's loop, 50 Hz: Category I's knee at
    120 Hz sensors is at 74 Hz)."""
    found = {}
    for c in ("I", "II", "III"):
        s = refine_rate(
            ARCH.search(c, float(start), sensor_rate),
            lambda p, c=c: ARCH.probe_wait(c, sensor_rate, p),
        )
        found[c] = s.found
        net = ARCH.network(c)
        assert max(net.utilisation(ARCH.rates(sensor_rate, s.found)).values()) <= 1.0 + 1e-9
        if s.found == s.limit == ARCH.max_command_rate_hz:
            rate, wait = s.probes[-1]
            assert rate == s.limit and wait <= s.threshold  # stopped at the limit, no delay
            continue
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
        (lambda d: d.update(sensor_rates_hz={"imu": 0}), "sensor_rates_hz.imu"),
        (lambda d: d.update(sensor_rates_hz={"sonar": 10}), "sensor_rates_hz.sonar"),
        (lambda d: d.update(max_command_rate_hz=-5), "max_command_rate_hz"),
        (
            lambda d: d["categories"]["II"]["channel"].update(sections={"wheel": 0.01}),
            "II.channel.sections.wheel",
        ),
        (
            lambda d: d["categories"]["II"]["channel"].update(sections={"base": -0.01}),
            "II.channel.sections.base",
        ),
    ],
)
def test_bad_architecture_files(tmp_path, edit, field):
    d = copy.deepcopy(_arch_dict())
    edit(d)
    f = tmp_path / "arch.yaml"
    f.write_text(yaml.safe_dump(d))
    with pytest.raises(InputError) as exc:
        load_architecture(f)
    assert field in exc.value.field and exc.value.file == str(f)


PER_SENSOR = load_architecture(path("refine/architecture_per_sensor.yaml"))


def test_sensors_have_their_own_rates_and_commands_a_load_per_section():
    """The per-sensor file: IMU 200 Hz, force 100 Hz, odometry 50 Hz; a base command costs
    the channel 16 ms (12 ms otherwise). Unnamed sensors and sections take the defaults."""
    a = PER_SENSOR
    assert [a.sensor_rate(s, 123.0) for s in ("imu", "force", "odometry")] == [200, 100, 50]
    assert ARCH.sensor_rate("imu", 123.0) == 123.0 and ARCH.sensor_rates_hz == {}
    assert a.command_stream("II", "base") == "command.base"
    assert a.command_stream("II", ("arm", "base")) == "command.base"  # the heaviest
    assert a.command_stream("II", "arm") == COMMAND and a.command_stream("I", "base") == COMMAND
    routes = a.network("II").routes
    assert [h.service for h in routes["command.base"]] == [8.0e-3, 1.6e-2, 2.0e-3]
    assert [h.service for h in routes[COMMAND]] == [8.0e-3, 1.2e-2, 2.0e-3]
    rates = a.rates(200.0, 20.0, command="command.base")
    assert rates == {"force": 100, "imu": 200, "odometry": 50, "command.base": 20.0}
    # a heavier command ahead makes a longer unloaded wait
    assert a.wait_threshold("II", "imu", load="base") == pytest.approx(
        a.wait_threshold("II", "imu") + 4.0e-3
    )
    # P is bounded by the watched sensor's own rate and by the main CPU's loop
    assert a.search("II", 10.0, 200.0, ("odometry",)).limit == 50.0
    assert a.search("II", 10.0, 200.0, ("imu",)).limit == a.max_command_rate_hz == 50.0


def test_each_behavior_finds_its_own_rate():
    """Fig. 5 per behavior (Step 4): in Category II a behavior that drives the base loads the
    channel more, so it finds a lower rate than one that moves the arm or the gripper; a
    parallel group sends one command stream, so it takes its heaviest section's load. The
    refined program carries the rate per behavior."""
    program = task(4)
    quick = replace(PER_SENSOR, rate_step_hz=3.0, probe_window=1.5)  # the tests' probes
    found = {k: s.found for k, s in behavior_searches(program, quick).items()}
    assert set(found) == set(program.events())
    arm, base = found["R1.lower_arm"], found["R1.approach"]
    assert found["R2.grip"] == found["R1.raise_arm"] == arm
    assert found["R2.approach"] == found["R1.pull_out"] == base
    assert 10.0 < base < arm
    # each stops at the knee of its own load (the quick 1.5 s probes miss overloads of a
    # few percent), and one step higher is past it
    net = PER_SENSOR.network("II")
    for rate, stream in ((base, "command.base"), (arm, COMMAND)):
        rho = net.utilisation(PER_SENSOR.rates(200.0, rate, command=stream))
        assert max(rho.values()) < 1.05
        rho = net.utilisation(PER_SENSOR.rates(200.0, rate + 3.0, command=stream))
        assert max(rho.values()) > 1.0
    lowered = join(program, Parallelization("R1", "lower_arm", "approach"))
    grouped = {k: s.found for k, s in behavior_searches(lowered, quick).items()}
    assert grouped["R1.lower_arm"] == grouped["R1.approach"] == base
    rates = behavior_rates(program, found)
    refined = program
    for robot, rs in rates.items():
        refined = apply_rate(refined, robot, rs)
    assert refined.behavior("R1.lower_arm").rate_hz == arm
    assert refined.behavior("R1.approach").rate_hz == base
