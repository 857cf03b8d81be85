"""The workcell measures what the program does: events on delivered data, late data late."""

from __future__ import annotations

from dataclasses import replace

import pytest

from tamp.refine.architecture import ServiceTimes, default_architecture
from tamp.refine.order import precedence
from tamp.refine.steps import refine_rate
from tamp.sim.refine.simulate import simulate
from tamp.verification.refine import check_run
from tests.sim.refine.helpers import fast_architecture, short

pytestmark = pytest.mark.slow  # Drake simulations of the short Task 4 program


@pytest.fixture(scope="module")
def run():
    return simulate(short(), default_architecture())


def test_the_short_program_finishes_in_sim_time(run):
    assert run.finished
    assert 8.0 < run.task_time < 20.0
    # measured, not computed: every behavior took time and ends after it started
    for r in run.timeline.records:
        assert r.start is not None and r.end is not None and r.end >= r.start
    # the measured order respects the program's precedences and its ordering property
    order = run.timeline.order()
    prec = precedence(short())
    for i, e in enumerate(order):
        assert prec[e] <= set(order[:i])
    assert check_run(short(), order).holds
    # robots touched nothing with their chassis or lever, nor each other
    assert run.collisions == {}
    # the chair really opened: the pull on the latch turned frame_b about the hinge
    assert run.outcome.achieved, run.outcome.failed()
    assert 0.35 <= run.outcome.values["folding_chair.hinge"] < 1.2
    assert run.outcome.values["folding_chair.tilt"] < 0.05  # frame_a stayed on the floor


def test_samples_queue_in_the_channel(run):
    arch = default_architecture()
    threshold = arch.wait_threshold("II", "imu")
    for robot, wait in run.max_wait.items():
        assert 0.0 < wait <= threshold, robot  # queued a little, never delayed at 10 Hz


def test_late_samples_fire_the_event_late():
    """A saturated sensor sub-CPU (rho > 1) delays the IMU samples: the lift's event fires
    later, on stale data, while the lever kept moving."""
    arch = default_architecture()
    cat = arch.categories["II"]
    slow = replace(cat, sub_cpu=ServiceTimes(sensor=1.8e-3, command=cat.sub_cpu.command))
    late_arch = replace(arch, categories={**arch.categories, "II": slow})
    fast = simulate(short(), arch, max_sim_time=6.0)
    late = simulate(short(), late_arch, max_sim_time=6.0)
    t_fast = fast.timeline.record("R1.lower_arm").end
    t_late = late.timeline.record("R1.lower_arm").end
    assert t_fast is not None and t_late is not None
    assert t_late > t_fast + 0.05
    assert late.max_wait["R1"] > 10 * fast.max_wait["R1"]


def test_online_search_finds_the_queue_models_rate():
    """Fig. 5 in the diagram (the supervisor on the Channels' deliveries) stops where the
    offline queue model's search stops, within one step."""
    arch = fast_architecture()
    tuned = simulate(short(), arch, tune=True)
    found = tuned.found_rates()
    assert set(found) == {"R1", "R2"}
    offline = refine_rate(
        arch.search("II", 10.0, 200.0),
        lambda rate: arch.probe_wait("II", 200.0, rate),
    ).found
    for robot, rate in found.items():
        assert abs(rate - offline) <= arch.rate_step_hz, robot
    # one search per robot and trigger sensor (Fig. 5 per behavior), each ended on a delay
    assert set(tuned.searches) == {"R1.imu", "R1.odometry", "R2.odometry", "R2.force"}
    for key, search in tuned.searches.items():
        assert abs(search.found - offline) <= arch.rate_step_hz, key
        assert search.probes[-1][1] > search.threshold, key  # the last probe was delayed


@pytest.mark.slow
def test_categories_are_ordered():
    """The rate found online: Category I >= II >= III (one architecture, never per task)."""
    arch = fast_architecture()
    found = {}
    for cat in ("I", "II", "III"):
        tuned = simulate(short().with_category(cat), arch, tune=True)
        found[cat] = min(tuned.found_rates().values())
    assert found["I"] >= found["II"] >= found["III"]
    assert found["I"] > found["III"]


def test_record_writes_a_meshcat_animation(tmp_path):
    out = tmp_path / "rec" / "run.html"
    run = simulate(short(), default_architecture(), max_sim_time=0.5, record=out)
    assert run.recording == str(out)
    text = out.read_text()
    assert "<html" in text.lower() and len(text) > 100_000
