"""Occlusion by the held object in the workcell (`tamp.sim.core.perception.recall`): a look at
W^B with a hammer in the gripper still counts the scissors the hammer hides, the place keeps
away from them, and an object taken away in plain view is gone (a short CellDriver run)."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform

from tamp.sim.lots.driver import CellDriver
from tamp.sim.lots.scenario import load_cell_scenario
from tamp.sim.lots.station import build_station
from tamp.world.interface import Status
from tests.sim.lots.helpers import write_scenario

pytestmark = pytest.mark.slow

#: a spot on W^B's near side (towards the robot) that the held hammer's head covers at the
#: look pose, for the grasp below (found by rendering; the test checks it is not detected)
HIDDEN_XY = [-0.09, 0.08]
#: a top grasp across the hammer's handle, 6 cm from the handle's end: the head hangs
#: towards the robot, the handle ends just short of the camera's axis (6.5 cm off the TCP)
GRASP = "PickAt(A, 0.54, 0.25, 0)"


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    """A hammer at the centre of W^A (head towards the robot); a saw in W^B and a scissors
    where the held hammer will hide it."""
    path = write_scenario(
        tmp_path_factory.mktemp("occlusion"),
        [
            {"class": "hammer", "workspace": "A", "xy": [0.0, 0.0], "yaw": 180},
            {"class": "saw", "workspace": "B", "xy": [0.04, -0.1], "yaw": 0},
            {"class": "scissors", "workspace": "B", "xy": HIDDEN_XY, "yaw": -90},
        ],
    )
    return build_station(load_cell_scenario(path))


def test_a_scissors_hidden_by_the_held_hammer_is_still_counted(cell, monkeypatch):
    """One look only (the second look of a held object's cover is the next test's)."""
    from tamp.sim.lots import skills

    monkeypatch.setattr(skills, "LOOK_AGAIN_COVER", 1.0)
    d = CellDriver(cell)
    assert d.run("LookAt(B)").detail == "saw=1,scissors=1"
    st = d.run(GRASP)
    assert st.status is Status.SUCCESS, d.skill_state().log
    st = d.run("LookAt(B)")
    obs = d.observation()
    # the scissors is not detected (the hammer covers it) but remembered: counted, occluded
    assert "scissors" not in {x.cls for x in obs.detections}
    assert [m.cls for m in obs.occluded] == ["scissors"]
    # in hand from depth; a scripted grasp picks no track, so its class is not known
    assert obs.counts == {"saw": 1, "scissors": 1} and obs.in_hand == ("unknown",)
    assert st.detail == "saw=1,scissors=1; occluded scissors"
    # the remembered point is the scissors' place (the arm's own kinematics, no plant pose)
    pc = d.plant_context()
    scissors = cell.cell.bodies["scissors_0"]
    true_xy = scissors.EvalPoseInWorld(pc).translation()[:2]
    assert np.linalg.norm(np.array(obs.occluded[0].position[:2]) - true_xy) < 0.02
    # the hammer goes down away from the scissors it cannot see; then all three are seen
    assert d.run("Place(B)").status is Status.SUCCESS
    hammer = cell.cell.bodies["hammer_0"].EvalPoseInWorld(pc).translation()
    assert hammer[2] < 0.01 and np.linalg.norm(hammer[:2] - true_xy) > 0.1
    assert d.run("LookAt(B)").detail == "hammer=1,saw=1,scissors=1"
    assert d.observation().occluded == ()
    # taken off the table (out of every view); its place is then in plain view: gone
    cell.plant.SetFreeBodyPose(pc, scissors, RigidTransform([0.2, 0.0, 0.0]))
    assert d.run("LookAt(B)").detail == "hammer=1,saw=1"
    assert d.observation().occluded == ()


def test_a_look_while_holding_is_taken_again_from_the_other_side(cell):
    """The held hammer covers part of the view: the look is taken again with the hand turned
    about half a turn, and the scissors behind the hammer is then seen, not only remembered
    (a person may have put something there while the robot carried the hammer)."""
    d = CellDriver(cell)  # the scene as built: never looked at W^B, nothing remembered
    st = d.run(GRASP)
    assert st.status is Status.SUCCESS, d.skill_state().log
    st = d.run("LookAt(B)")
    log = [text for _, text in d.skill_state().log]
    assert any("covers" in t and "look again" in t for t in log), log
    obs = d.observation()
    assert "scissors" in {x.cls for x in obs.detections}  # seen from the other side
    assert obs.counts == {"saw": 1, "scissors": 1} and st.status is Status.SUCCESS
