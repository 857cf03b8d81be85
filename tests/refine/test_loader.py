"""Program files: the packaged tasks load, write back equal, and every bad field is named."""

from __future__ import annotations

import copy

import pytest

from tamp.errors import EXIT_BAD_INPUT, InputError
from tamp.refine.loader import dump_program, load_program
from tamp.refine.program import Motion, Trigger

from .helpers import reload, task, task_dict, write


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_packaged_tasks_load_and_round_trip(n, tmp_path):
    p = task(n)
    assert [r.name for r in p.robots] == ["R1", "R2"]
    assert p.communication.category == "II"
    assert p.communication.sensor_rate_hz == 200.0
    assert p.communication.command_rate_hz == 10.0
    assert reload(p, tmp_path) == p
    assert dump_program(p).startswith("version: 1\n")


def test_task4_is_the_papers_setting():
    p = task(4)
    c = p.communication
    assert (c.category, c.sensor_rate_hz, c.command_rate_hz, c.base_speed) == (
        "II",
        200.0,
        10.0,
        1.05e-2,
    )
    r1, r2 = p.robots
    first = [i for i, b in enumerate(r1.behaviors) if b.manipulates][0]
    assert r1.behaviors[first].name == "pull_out" and first == 2  # two behaviors before it
    assert [i for i, b in enumerate(r2.behaviors) if b.manipulates][0] == 1  # one before
    approach = r1.behavior("approach")
    assert approach.motion == Motion("distance", 0.7, 1.05e-2)  # base speed by default
    assert approach.event == Trigger(sensor="odometry", op="reaches", value=0.69)
    assert r1.behavior("pull_out").waits_for == ("R2.grip",)


def _edit(path, value, data=None):
    """A copy of Task 4 with ``value`` at the dotted/indexed ``path`` (None deletes)."""
    data = copy.deepcopy(data or task_dict(4))
    keys = path.split("/")
    node = data
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node[k]
    last = keys[-1]
    if isinstance(node, list):
        node[int(last)] = value
    elif value is None:
        del node[last]
    else:
        node[last] = value
    return data


B = "robots/0/behaviors"


@pytest.mark.parametrize(
    "path,value,field,words",
    [
        ("version", 2, "version", "unsupported version"),
        ("colour", "red", "colour", "unknown key"),
        ("scene", "kitchen", "scene", "no packaged scene 'kitchen'"),
        ("communication/category", "IV", "communication.category", "expected one of"),
        ("communication/command_rate_hz", -1, "communication.command_rate_hz", "must be >"),
        ("communication/base_speed", None, "communication.base_speed", "missing field"),
        ("ordering", "G(R1.fly -> R2.grip)", "ordering", "unknown event 'R1.fly'"),
        (f"{B}/0/section", "leg", "robots[0].behaviors[0].section", "expected one of"),
        (
            f"{B}/0/motion",
            {"distance": 0.1},
            "robots[0].behaviors[0].motion.distance",
            "the arm moves by angle",
        ),
        (f"{B}/0/motion", {"angle": 0.0, "speed": 1}, "behaviors[0].motion.angle", "must move"),
        (f"{B}/0/motion", {"angle": 0.3}, "behaviors[0].motion.speed", "missing field"),
        (f"{B}/0/event", {"sensor": "sonar", "above": 1}, "event.sensor", "expected one of"),
        (f"{B}/0/event", {"sensor": "force"}, "behaviors[0].event", "exactly one of"),
        (f"{B}/0/event", {"sensor": "force", "reaches": 1}, "event.reaches", "odometry ends"),
        (f"{B}/0/event", {"sensor": "odometry", "reaches": 0.1}, "event.sensor", "the base"),
        (f"{B}/0/event", {"after": "R1.approach"}, "event.after", "other robot"),
        (f"{B}/0/event", {"after": "R2.fly"}, "event.after", "unknown event"),
        (f"{B}/2/waits_for", ["R2.nothing"], "behaviors[2].waits_for[0]", "unknown event"),
        (f"{B}/2/waits_for", ["R1.pull_out"], "behaviors[2].waits_for[0]", "its own event"),
        (f"{B}/1/name", "lower_arm", "behaviors[1].name", "duplicate behavior"),
        (f"{B}/1/name", "1st", "behaviors[1].name", "identifiers"),
        (f"{B}/2/parallel_with", "lower_arm", "behaviors[2].parallel_with", "previous"),
        (f"{B}/0/parallel_with", "x", "behaviors[0].parallel_with", "previous behavior (none)"),
        (f"{B}/2/parallel_with", "approach", "behaviors[2].parallel_with", "one motion"),
        (f"{B}/1/rate_hz", 0, "behaviors[1].rate_hz", "must be >"),
        ("robots/0/model", "youbot", "robots[0].model", "expected one of"),
        ("robots/0/start", [0, 0], "robots[0].start", "list of 3"),
        ("robots/1/name", "R1", "robots", "duplicate robot names"),
        ("robots/0/behaviors", [], "robots[0].behaviors", "at least one"),
    ],
)
def test_bad_fields_are_named(tmp_path, path, value, field, words):
    f = write(tmp_path, _edit(path, value))
    with pytest.raises(InputError) as exc:
        load_program(f)
    assert exc.value.exit_code == EXIT_BAD_INPUT
    assert exc.value.file == str(f)
    assert field in (exc.value.field or ""), exc.value
    assert words in str(exc.value)


def test_three_robots_and_missing_file(tmp_path):
    data = task_dict(4)
    data["robots"].append(copy.deepcopy(data["robots"][1]) | {"name": "R3"})
    with pytest.raises(InputError, match="expected two robots"):
        load_program(write(tmp_path, data))
    with pytest.raises(InputError, match="not found"):
        load_program(tmp_path / "nope.yaml")


def test_parallel_group_shares_rate(tmp_path):
    data = _edit(f"{B}/1/parallel_with", "lower_arm")
    data["robots"][0]["behaviors"][1]["rate_hz"] = 20
    with pytest.raises(InputError, match="share one rate") as exc:
        load_program(write(tmp_path, data))
    assert exc.value.field.endswith("behaviors[1].rate_hz")
    data["robots"][0]["behaviors"][0]["rate_hz"] = 20
    p = load_program(write(tmp_path, data))
    assert p.robot("R1").groups() == [(0, 1), (2,), (3,)]
    assert p.robot("R1").gating(0) is False and p.robot("R1").gating(1) is True


def test_the_perturbation_section_is_read_once_into_the_program(tmp_path):
    """The loader parses ``perturbation:`` (`tamp.perturbation`) into the program: seeded
    runs draw from ``Program.perturbation`` and never read the file again."""
    from tamp.perturbation import NONE, PoseSpread

    assert task(4).perturbation == NONE
    f = write(tmp_path, _edit("perturbation", {"robot": {"xy": 0.02, "yaw": 0.05}}))
    p = load_program(f)
    assert p.perturbation.robot == PoseSpread("normal", 0.02, 0.05)
    assert p.perturbation.source == str(f)
    f.unlink()  # nothing reads it any more
    assert p.perturbation.sample(3).robot_offset("R1") != (0.0, 0.0, 0.0)
    assert p == task(4)  # the section is no part of the program's equality
    f = write(tmp_path, _edit("perturbation", {"robot": {"xy": -1}}))
    with pytest.raises(InputError) as exc:
        load_program(f)
    assert exc.value.field == "perturbation.robot.xy"


def test_a_scene_is_a_packaged_name_or_a_file_beside_the_program(tmp_path):
    assert task(4).scene == "open_chair"
    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "mine.yaml").write_text("version: 1\n")  # read by the workcell
    p = load_program(write(tmp_path, _edit("scene", "scenes/mine.yaml")))
    assert p.scene == str(tmp_path / "scenes" / "mine.yaml")
    assert reload(p, tmp_path).scene == p.scene
