"""The workcell measures what the program does: events on delivered data, late data late."""

from __future__ import annotations

from dataclasses import replace

import pytest

from tamp.refine.architecture import ServiceTimes, default_architecture, load_architecture
from tamp.refine.order import precedence
from tamp.refine.steps import refine_rate
from tamp.scenarios import path
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


def test_sensors_sample_at_their_own_rates_and_commands_carry_their_load():
    """The per-sensor architecture in the Channel: by the tick at 0.99 s (the last one an
    advance to 1 s handles; the short program's fast motions run at the 10 ms step) the
    force sensor gave 100 samples (100 Hz), the IMU 199, odometry 50; Robot 2's commands
    while it drives travel as base commands, Robot 1's while it lowers its lever as plain
    ones."""
    from tamp.refine.architecture import COMMAND
    from tamp.sim.core.runner import make_simulator
    from tamp.sim.refine.scenario import load_scene
    from tamp.sim.refine.station import build_station

    arch = load_architecture(path("refine/architecture_per_sensor.yaml"))
    program = short()
    cell = build_station(program, arch, load_scene(program.scene))
    sim = make_simulator(cell.diagram)
    sim.AdvanceTo(1.0)
    root = sim.get_context()
    states = {n: c.state(c.GetMyContextFromRoot(root)) for n, c in cell.channels.items()}
    assert cell.time_step == 0.01
    assert states["R1"].samples == (100, 199, 50)  # SENSORS order: force, imu, odometry
    assert program.robot("R2").behaviors[0].section == "base"
    assert states["R2"].latest[COMMAND].message.stream == "command.base"
    assert program.robot("R1").behaviors[0].section == "arm"
    assert states["R1"].latest[COMMAND].message.stream == COMMAND


def test_a_rate_faster_than_the_tick_is_refused():
    """A command leaves on a tick: Task 4's slow motions run at the chair scene's 20 ms
    step, where a behavior commanding at 60 Hz is refused before anything runs; the short
    program's fast motions run at 10 ms (a coarse step only for slow programs)."""
    from tamp.errors import InfeasibleError
    from tamp.refine.loader import load_program
    from tamp.refine.steps import apply_rate
    from tamp.sim.refine.scenario import load_scene
    from tamp.sim.refine.station import build_station, time_step

    task4 = load_program("task4")
    scene = load_scene(task4.scene)
    assert time_step(task4, scene) == scene.time_step == 0.02
    assert time_step(short(), scene) == 0.01
    program = apply_rate(task4, "R1", {"lower_arm": 60.0})  # an arm: its speed stays
    assert time_step(program, scene) == 0.02
    with pytest.raises(InfeasibleError, match="at 60 Hz.*20 ms step sends at most 50 Hz"):
        build_station(program, default_architecture(), scene)
