"""Identity is perception's own in the LOTS workcell: nothing that decides (controller, skills,
grasping, descent, safety) reads a label image or a body index; with ``camera.detector:
learned`` no label image reaches perception either (the diagram's connections); the seeded
noisy detector is a ``perturbation.sensor`` field wired into the cell's perception from the
run's seed."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import tamp.sim.lots as lots
from tamp.errors import InputError
from tamp.sim.core.perception import CONFIRM_VIEWS, DetectorNoise
from tamp.sim.lots.scenario import load_cell_scenario, perturbed
from tamp.sim.lots.station import build_station, detector_noise
from tests.sim.lots.helpers import BASE, write_scenario
from tests.sim.lots.test_declared_classes import widget_scenario

#: label images, render labels and body indices: the simulator's identities, not perception's
SIM_IDS = re.compile(r"label_image|label_port|ImageLabel|RenderLabel|BodyIndex|\.index\(\)")
#: the modules of the cell that may use them, and why
ALLOWED = {
    # the builder maps each object body's render label to its class for Perception's label
    # input: the detector's stand-in, until the learned detector is on the decision path
    "station.py",
    "plant.py",  # builds the world: gives the person's hand its render label
    "person.py",  # the scripted person (the world, not the robot) pushes bodies by index
}


def test_nothing_that_decides_reads_a_label_image_or_a_body_index():
    folder = Path(lots.__file__).parent
    users = {p.name for p in folder.glob("*.py") if SIM_IDS.search(p.read_text())}
    assert users <= ALLOWED, sorted(users - ALLOWED)
    assert "station.py" in users  # the one place the label input is wired (the test is live)
    for name in ("skills.py", "controller_system.py", "grasping.py", "safety.py"):
        assert name not in users


def test_the_noisy_detector_comes_from_the_scenario_and_the_runs_seed(tmp_path):
    objects = [{"class": "hammer", "workspace": "A", "xy": [0.0, 0.0], "yaw": 0}]
    path = write_scenario(tmp_path, objects, perturbation={"sensor": {"detector": "high"}})
    scenario = load_cell_scenario(path)
    assert detector_noise(scenario) is None  # not a seeded run: the detector is exact
    run, applied = perturbed(scenario, 7)
    assert detector_noise(run) == DetectorNoise("high", 7)
    assert applied.detector == "high" and applied.to_json()["detector"] == "high"
    plain, _ = perturbed(load_cell_scenario(write_scenario(tmp_path, objects)), 7)
    assert detector_noise(plain) is None


@pytest.mark.slow
def test_with_the_learned_detector_no_label_image_reaches_perception(tmp_path):
    objects = [{"class": "hammer", "workspace": "A", "xy": [0.0, 0.0], "yaw": 0}]
    camera = {**BASE["camera"], "detector": "learned"}
    station = build_station(load_cell_scenario(write_scenario(tmp_path, objects, camera=camera)))
    perception = station.perception
    assert perception.label_port is None
    inputs = {perception.get_input_port(i).get_name() for i in range(perception.num_input_ports())}
    assert inputs == {"color_image", "depth_image", "view_request"}
    label = station.camera.label_image_output_port().get_index()
    assert not [
        k for k, v in station.diagram.connection_map().items() if v == (station.camera, label)
    ]
    # the label oracle (the default) wires the label image to perception, and only there
    plain = build_station(load_cell_scenario(write_scenario(tmp_path, objects)))
    label = plain.camera.label_image_output_port().get_index()
    users = [k for k, v in plain.diagram.connection_map().items() if v == (plain.camera, label)]
    assert users == [(plain.perception, plain.perception.label_port.get_index())]


def test_a_task_counting_a_class_the_learned_detector_does_not_know_is_refused(tmp_path):
    import yaml

    from tamp.lots.task import load_task
    from tamp.sim.lots.simulate import check_detector_classes

    path = widget_scenario(tmp_path)
    text = path.read_text().replace("fov_y_deg: 42.5", "fov_y_deg: 42.5\n  detector: learned")
    path.write_text(text)
    scenario = load_cell_scenario(path)
    assert scenario.camera.detector == "learned"

    def task(cls: str):
        doc = {
            "version": 1,
            "name": cls,
            "formula": "GF p",
            "propositions": {"p": {"class": cls}},
            "initial": {"A": {"widget": 2, "body": 1}, "B": {}},
        }
        (tmp_path / "task.yaml").write_text(yaml.safe_dump(doc))
        return load_task(tmp_path / "task.yaml")

    check_detector_classes(task("body"), scenario)  # the widgets may lie there: unknown
    with pytest.raises(InputError, match=r"camera\.detector: .*not trained on \['widget'\]"):
        check_detector_classes(task("widget"), scenario)
    oracle = load_cell_scenario(widget_scenario(tmp_path))
    check_detector_classes(task("widget"), oracle)  # the oracle knows every class


@pytest.mark.slow
def test_the_learned_detector_counts_the_packaged_scenes_looks(tmp_path):
    """A look from the look pose with the learned detector counts what the label oracle
    counts (model building's W^A: saw, 2 scissors, hammer; the tower's W^A: bottom, 2
    bodies, peak), from colour and depth alone, and renders colour instead of labels."""
    import yaml

    from tamp.scenarios import resolve
    from tamp.sim.lots.driver import CellDriver
    from tamp.world.interface import Status

    for name, want in (
        ("model_building", "hammer=1,saw=1,scissors=2"),
        ("tower", "body=2,bottom=1,peak=1"),
    ):
        data = yaml.safe_load(resolve(name, "lots_sim").read_text())
        data["camera"]["detector"] = "learned"
        path = tmp_path / f"{name}.yaml"
        path.write_text(yaml.safe_dump(data))
        station = build_station(load_cell_scenario(path))
        d = CellDriver(station)
        look = d.run("LookAt(A)")
        assert look.status is Status.SUCCESS and look.detail == want, name
        assert d.run("LookAt(B)").detail == ""
        p = station.perception
        # two looks of `CONFIRM_VIEWS` views, each rendering colour + depth
        assert p.state(p.GetMyContextFromRoot(d.context)).render_kinds == 2 * CONFIRM_VIEWS * 2


@pytest.mark.slow
def test_the_learned_detector_sees_into_example1s_tray_and_not_its_walls(tmp_path):
    """W^B of Example 1 holds a tray (walls 3 cm high, floor 1 cm up): the cell tells
    perception the floor's height and where the walls stand (`Region.fixtures`), so the
    empty tray counts nothing and what lies in it counts by class."""
    import yaml
    from pydrake.math import RigidTransform, RotationMatrix

    from tamp.scenarios import resolve
    from tamp.sim.lots.driver import CellDriver

    data = yaml.safe_load(resolve("example1", "lots_sim").read_text())
    data["camera"]["detector"] = "learned"
    path = tmp_path / "example1.yaml"
    path.write_text(yaml.safe_dump(data))
    station = build_station(load_cell_scenario(path))
    d = CellDriver(station)
    assert d.run("LookAt(B)").detail == ""  # the walls are no screwdrivers
    pc = d.plant_context()
    for uid, (x, y) in (("hammer_0", (0.47, -0.27)), ("screw_0", (0.56, -0.18))):
        X = RigidTransform(RotationMatrix.MakeZRotation(0.3), [x, y, 0.012])
        station.plant.SetFreeBodyPose(pc, station.cell.bodies[uid], X)
    d.advance(0.5)
    assert d.run("LookAt(B)").detail == "hammer=1,screw=1"
    assert d.run("LookAt(A)").detail == "screw=1,screwdriver=1"
