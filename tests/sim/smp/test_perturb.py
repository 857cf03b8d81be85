"""Seeded runs of SMP-MRO scenarios: the perturbation applied to a scenario (no simulation)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from tamp.errors import InputError
from tamp.perturbation import Perturbation, PoseSpread
from tamp.sim.smp.perturb import perturb
from tamp.sim.smp.robot import ROBOT
from tamp.sim.smp.scenario import RunConditions, load_scenario
from tamp.world.events import AtTime

from .helpers import packaged


def scenario(name="case3_perturbed.yaml"):
    return load_scenario(packaged(name))


def test_packaged_perturbed_cases_load():
    s = scenario()
    assert s.name == "case3_perturbed"
    assert (s.grasp, s.perception) == ("friction", "truth")
    assert s.perturbation.fields() == {"objects", "robot", "friction", "skills"}
    c = scenario("case3_camera.yaml")
    assert (c.grasp, c.perception) == ("friction", "camera")
    assert c.perturbation.depth_noise == 0.002 and c.perturbation.pose_noise == 0.003
    plain = scenario("case3.yaml")
    assert (plain.grasp, plain.perception, plain.perturbation.fields()) == ("weld", "truth", set())


def test_perturb_moves_objects_and_robot_and_mutates_nothing():
    s = scenario()
    before = dataclasses.replace(s)
    out, applied = perturb(s, 5)
    assert s == before  # the loaded scenario is untouched
    assert out.demo is s.demo  # the plan stays nominal: the robot was shown these poses
    for o in s.objects:
        if o.appear is not None:
            assert out.object(o.id) == o  # appears later: not moved
            continue
        dx, dy, dyaw = applied.objects[o.id]
        moved = out.object(o.id)
        assert moved.xy == pytest.approx((o.xy[0] + dx, o.xy[1] + dy))
        assert moved.yaw == pytest.approx(o.yaw + dyaw)
        assert math.hypot(dx, dy) > 0
    rx, ry, ryaw = s.robot_start
    assert out.robot_start == pytest.approx(
        (rx + applied.robot[0], ry + applied.robot[1], ryaw + applied.robot[2])
    )
    assert applied.size == max(math.hypot(dx, dy) for dx, dy, _ in applied.objects.values())
    c = out.conditions
    assert c.seed == 5 and 0.5 <= c.friction <= 0.9
    assert dict(c.chance_failures)["Pick"] == s.perturbation.sample(5).skill_failures("Pick")
    assert {k for k, *_ in c.nominal} == {"O0", "O1"}  # the camera's prior


def test_same_seed_same_scenario_different_seed_different():
    s = scenario()
    assert perturb(s, 11) == perturb(s, 11)
    assert perturb(s, 11)[1].to_json() == perturb(s, 11)[1].to_json()
    assert perturb(s, 11)[0].objects != perturb(s, 12)[0].objects


def test_no_perturbation_changes_nothing_but_the_seed():
    s = scenario("case3.yaml")
    out, applied = perturb(s, 3)
    assert out.objects == s.objects and out.robot_start == s.robot_start
    assert out.conditions == RunConditions(seed=3, nominal=out.conditions.nominal)
    assert applied.size == 0.0 and applied.to_json()["friction"] is None


def test_large_offsets_are_redrawn_until_the_start_is_valid():
    s = dataclasses.replace(
        scenario(), perturbation=Perturbation(objects=PoseSpread("uniform", 0.5, 0.0))
    )
    for seed in range(30):
        out, applied = perturb(s, seed)
        placed = [o for o in out.objects if o.appear is None]
        for i, a in enumerate(placed):
            assert out.in_workspace(*a.xy, margin=a.kind.radius)
            rx, ry, _ = out.robot_start
            assert math.dist(a.xy, (rx, ry)) >= ROBOT.footprint_radius + a.kind.radius
            for b in placed[i + 1 :]:
                assert math.dist(a.xy, b.xy) >= a.kind.radius + b.kind.radius
        for note in applied.notes:
            assert "nominal kept" in note


def test_timed_appearances_are_jittered_never_before_zero():
    s = scenario("case3.yaml")
    s = s.with_events()
    oa = s.object("Oa")
    timed = dataclasses.replace(oa, appear=dataclasses.replace(oa.appear, when=AtTime(20.0)))
    s = dataclasses.replace(
        s,
        objects=tuple(timed if o.id == "Oa" else o for o in s.objects),
        perturbation=Perturbation(timing_jitter=2.0),
    )
    out, applied = perturb(s, 4)
    shift = s.perturbation.sample(4).jitter("Oa")
    assert out.object("Oa").appear.when == AtTime(20.0 + shift)
    assert applied.timing == {"Oa": pytest.approx(shift)}
    # an appearance after a skill depends on the robot: not jittered
    out3, applied3 = perturb(
        dataclasses.replace(scenario("case3.yaml"), perturbation=s.perturbation), 4
    )
    assert out3.object("Oa").appear == scenario("case3.yaml").object("Oa").appear
    assert applied3.timing == {}


def _write(tmp_path, extra: str):
    text = (
        packaged("case3.yaml")
        .read_text()
        .replace(
            "demonstration: ../case3.yaml",
            f"demonstration: {packaged('case3.yaml').parent.parent / 'case3.yaml'}",
        )
    )
    f = tmp_path / "s.yaml"
    f.write_text(text + extra)
    return f


@pytest.mark.parametrize(
    ("extra", "field", "words"),
    [
        ("grasp: glue\n", "grasp", "one of"),
        ("perception: lidar\n", "perception", "one of"),
        ("perturbation: {skills: {Place: 0.1}}\n", "perturbation.skills.Place", "Pick"),
        ("perturbation: {objects: {xy: 0.9}}\n", "perturbation.objects.xy", "<= 0.5"),
        ("perturbation: {colour: 1}\n", "perturbation.colour", "unknown key"),
        (
            "perturbation: {sensor: {detector: low}}\n",
            "perturbation.sensor.detector",
            "perception: camera",
        ),
    ],
)
def test_bad_grasp_perception_and_perturbation_fields_exit_2(tmp_path, extra, field, words):
    with pytest.raises(InputError) as e:
        load_scenario(_write(tmp_path, extra))
    assert e.value.field == field and words in str(e.value)
    assert e.value.file.endswith("s.yaml")


def test_the_noisy_detector_is_a_camera_cell_perturbation(tmp_path):
    """With ``perception: camera`` the seeded noisy detector is drawn per run (exact
    without a seed) and reaches the cell's perception."""
    from tamp.sim.core.perception import DetectorNoise
    from tamp.sim.smp.simulate import prepare
    from tamp.sim.smp.station import build_station

    s = load_scenario(
        _write(tmp_path, "perception: camera\nperturbation: {sensor: {detector: high}}\n")
    )
    assert s.perturbation.detector == "high" and s.conditions.detector is None
    run, applied = perturb(s, 3)
    assert run.conditions.detector == "high" and applied.to_json()["detector"] == "high"
    system = build_station(run, prepare(run).policy)
    perception = system.diagram.GetSubsystemByName("perception")
    assert perception.noise == DetectorNoise("high", 3)
