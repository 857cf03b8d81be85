"""Identity is perception's own in the LOTS workcell: nothing that decides (controller, skills,
grasping, descent, safety) reads a label image or a body index, and the seeded noisy detector
is a ``perturbation.sensor`` field wired into the cell's perception from the run's seed."""

from __future__ import annotations

import re
from pathlib import Path

import tamp.sim.lots as lots
from tamp.sim.core.perception import DetectorNoise
from tamp.sim.lots.scenario import load_cell_scenario, perturbed
from tamp.sim.lots.station import detector_noise
from tests.sim.lots.helpers import write_scenario

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
