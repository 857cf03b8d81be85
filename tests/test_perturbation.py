"""The one perturbation concept: strict parsing, seeded samples, the size measure."""

from __future__ import annotations

import numpy as np
import pytest

from tamp.errors import InputError
from tamp.fileio import Fields
from tamp.perturbation import (
    DETECTOR_LEVELS,
    MAX_ATTEMPTS,
    NONE,
    NORMAL_CLIP,
    Applied,
    Perturbation,
    PoseSpread,
    check_seed,
    parse_perturbation,
)
from tamp.sim.core.outcome import CAUSES, run_cause

FULL = {
    "objects": {"distribution": "normal", "xy": 0.03, "yaw": 0.3},
    "robot": {"distribution": "uniform", "xy": 0.05, "yaw": 0.05},
    "friction": [0.5, 0.9],
    "sensor": {"depth_noise": 0.002, "pose_noise": 0.004},
    "timing": {"jitter": 0.5},
    "skills": {"Pick": 0.1, "Place": 0.05},
}


def parse(section, file="scn.yaml") -> Perturbation:
    return parse_perturbation(Fields({"perturbation": section}, file))


def test_a_full_section_parses_into_its_fields():
    p = parse(FULL)
    assert p.objects == PoseSpread("normal", 0.03, 0.3)
    assert p.robot == PoseSpread("uniform", 0.05, 0.05)
    assert p.friction == (0.5, 0.9)
    assert (p.depth_noise, p.pose_noise, p.timing_jitter) == (0.002, 0.004, 0.5)
    assert dict(p.skill_failure) == {"Pick": 0.1, "Place": 0.05}
    assert p.fields() == {"objects", "robot", "friction", "sensor", "timing", "skills"}
    assert p.source == "scn.yaml"


def test_no_section_is_no_perturbation():
    assert parse_perturbation(Fields({}, "f.yaml")) is NONE
    assert NONE.fields() == set()
    s = NONE.sample(7)
    assert s.robot == (0.0, 0.0, 0.0) and s.friction is None
    assert s.object_offset("O1") == (0.0, 0.0, 0.0)
    assert s.jitter("Oa") == 0.0 and s.skill_failures("Pick") == ()


@pytest.mark.parametrize(
    ("section", "field", "words"),
    [
        ({"object": {}}, "perturbation.object", "unknown key"),
        ({"objects": {"xy": -0.1}}, "perturbation.objects.xy", ">= 0"),
        ({"objects": {"xy": 2.0}}, "perturbation.objects.xy", "<= 0.5"),
        ({"objects": {"xy": float("nan")}}, "perturbation.objects.xy", "finite"),
        ({"objects": {"distribution": "cauchy"}}, "perturbation.objects.distribution", "one of"),
        ({"robot": {"yaw": 4.0}}, "perturbation.robot.yaw", "<="),
        ({"friction": [0.9, 0.5]}, "perturbation.friction", "low <= high"),
        ({"friction": [0.0, 0.5]}, "perturbation.friction[0]", "within"),
        ({"friction": 0.5}, "perturbation.friction", "list of 2"),
        ({"sensor": {"depth_noise": 1.0}}, "perturbation.sensor.depth_noise", "<="),
        ({"sensor": {"noise": 1.0}}, "perturbation.sensor.noise", "unknown key"),
        ({"sensor": {"detector": "huge"}}, "perturbation.sensor.detector", "one of"),
        ({"timing": {"jitter": -1}}, "perturbation.timing.jitter", ">= 0"),
        ({"skills": {"Pick": 1.0}}, "perturbation.skills.Pick", "below 1"),
        ({"skills": {"Pick": "often"}}, "perturbation.skills.Pick", "number"),
        ({"skills": {"Pick(O1)": 0.1}}, "perturbation.skills.Pick(O1)", "action name"),
        ([1, 2], "perturbation", "mapping"),
    ],
)
def test_bad_sections_name_file_and_field(section, field, words):
    with pytest.raises(InputError) as e:
        parse(section)
    assert e.value.file == "scn.yaml"
    assert e.value.field == field
    assert words in str(e.value)


def test_the_noisy_detector_is_a_sensor_perturbation_of_its_own():
    from tamp.sim.core.detection_noise import LEVELS

    assert set(DETECTOR_LEVELS) == set(LEVELS)  # the names the file may give are the levels
    p = parse({"sensor": {"detector": "high"}})
    assert p.detector == "high" and p.fields() == {"sensor"} and p.depth_noise == 0.0
    assert p.to_json()["sensor"]["detector"] == "high"
    assert parse(FULL).detector is None and NONE.detector is None


def test_a_workcell_refuses_what_it_does_not_simulate():
    with pytest.raises(InputError) as e:
        parse(FULL).require(("objects", "robot", "friction", "sensor", "skills"), "LOTS")
    assert e.value.field == "perturbation.timing"
    assert "not simulated by the LOTS workcell" in str(e.value)
    parse({"objects": {"xy": 0.01}}).require(("objects",), "LOTS")  # no error


def test_the_same_seed_gives_the_same_sample_bit_for_bit():
    p = parse(FULL)
    a, b = p.sample(42), p.sample(42)
    assert a == b
    assert a.object_offset("O1") == b.object_offset("O1")
    assert a.object_offset("O1", 3) == b.object_offset("O1", 3)
    assert a.robot_offset("R1") == b.robot_offset("R1")
    assert a.jitter("Oa") == b.jitter("Oa")
    assert a.skill_failures("Pick") == b.skill_failures("Pick")
    assert np.array_equal(
        a.noise("depth", 5).standard_normal(8), b.noise("depth", 5).standard_normal(8)
    )


def test_different_seeds_and_keys_give_different_draws():
    p = parse(FULL)
    a, b = p.sample(1), p.sample(2)
    assert a.robot != b.robot and a.friction != b.friction
    assert a.object_offset("O1") != b.object_offset("O1")
    assert a.object_offset("O1") != a.object_offset("O2")  # one stream per object
    assert a.object_offset("O1", 0) != a.object_offset("O1", 1)  # a redraw differs


def test_draws_do_not_depend_on_other_fields_or_objects():
    """Keyed streams: adding a field or an object leaves the other draws as they were."""
    only = parse({"objects": FULL["objects"]}).sample(9)
    full = parse(FULL).sample(9)
    assert only.object_offset("O1") == full.object_offset("O1")


def test_draws_stay_within_their_bounds():
    p = parse(FULL)
    for seed in range(300):
        s = p.sample(seed)
        dx, dy, dyaw = s.object_offset("O1")
        assert max(abs(dx), abs(dy)) <= NORMAL_CLIP * 0.03 + 1e-12
        assert abs(dyaw) <= NORMAL_CLIP * 0.3 + 1e-12
        rx, ry, ryaw = s.robot
        assert max(abs(rx), abs(ry)) <= 0.05 and abs(ryaw) <= 0.05
        assert 0.5 <= s.friction <= 0.9
        assert abs(s.jitter("Oa")) <= 3 * 0.5 + 1e-12
        assert len(s.skill_failures("Pick")) == MAX_ATTEMPTS


def test_draws_follow_their_distributions():
    p = parse({"objects": {"xy": 0.02}, "skills": {"Pick": 0.25}, "friction": [0.4, 0.8]})
    xs = np.array([p.sample(s).object_offset("O")[0] for s in range(2000)])
    assert abs(xs.mean()) < 0.002 and xs.std() == pytest.approx(0.02, rel=0.08)
    fails = np.array([p.sample(s).skill_failures("Pick")[0] for s in range(2000)])
    assert fails.mean() == pytest.approx(0.25, abs=0.03)
    mus = np.array([p.sample(s).friction for s in range(2000)])
    assert mus.min() >= 0.4 and mus.max() <= 0.8 and mus.mean() == pytest.approx(0.6, abs=0.01)


def test_size_is_the_largest_object_displacement():
    a = Applied(seed=3, objects={"O1": (0.03, 0.04, 0.5), "O2": (0.01, 0.0, 0.0)})
    a.robot = (0.1, 0.0, 0.0)
    assert a.size == pytest.approx(0.05)
    j = a.to_json()
    assert j["seed"] == 3 and j["size"] == pytest.approx(0.05)
    assert j["robot_displacement"] == pytest.approx(0.1)
    assert j["objects"]["O1"] == [0.03, 0.04, 0.5]
    assert Applied(seed=0).size == 0.0


@pytest.mark.parametrize("bad", [-1, 2**63, 1.5, "3", True, None])
def test_seeds_are_non_negative_integers(bad):
    with pytest.raises(InputError) as e:
        check_seed(bad)
    assert e.value.field == "--seed"


def test_run_causes():
    assert run_cause("SUCCESS", ["grasp_slipped"], False) is None
    assert run_cause("TIMEOUT", ["grasp_slipped"], False) == "timeout"
    assert run_cause("FAILURE", [], True) == "placement_off"
    assert run_cause("FAILURE", ["grasp_missed", "unreachable"], False) == "unreachable"
    assert run_cause("FAILURE", [], False) == "task_failed"
    assert {"timeout", "grasp_slipped", "object_not_found", "placement_off"} <= set(CAUSES)
    assert all(isinstance(v, str) and v for v in CAUSES.values())
