"""The closed-loop descent in the workcell (Zhou et al. §IV-B, Fig. 6): with a prediction
that every view repeats the hand commits after the fewest views and goes straight down;
with one that scatters it explores (slowly, the camera shifted sideways, many views) and
fails the attempt at the lowest point. The grasp network is replaced by two scripted
predictors so that the test is about the descent, not about the network."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tamp.sim.lots.driver import CellDriver
from tamp.sim.lots.grasping import GraspCandidate
from tamp.sim.lots.scenario import load_cell_scenario
from tamp.sim.lots.station import build_station
from tamp.world.interface import Status
from tests.sim.lots.helpers import write_scenario

pytestmark = pytest.mark.slow

XY = (0.5, 0.25)  # W^A's centre: the body lies there


def _cell(tmp_path):
    """One tower body at W^A's centre; one attempt, half a second of hovering."""
    path = write_scenario(
        tmp_path, [{"class": "body", "workspace": "A", "xy": [0.0, 0.0], "yaw": 0}]
    )
    scenario = load_cell_scenario(path)
    d = dataclasses.replace(scenario.grasp.descent, hover=0.5)
    scenario = dataclasses.replace(
        scenario, grasp=dataclasses.replace(scenario.grasp, attempts=1, descent=d)
    )
    return build_station(scenario)


def _pick(cell, scatter: float) -> tuple[Status, list[tuple[float, str]], object, list]:
    """One ``Pick(body)`` with a predictor that puts every view's grasp on the body's centre
    (``scatter`` 0) or on one of four points ``scatter`` apart in turn; up to the first
    grasp's approach (or the end). Returns the status, the skill log, the final skill state
    and the cameras of the views."""
    cameras = []

    def scripted(crop, X_WC, view_height):
        cameras.append(np.asarray(X_WC)[:3, 3].copy())
        # scattered: four grasps ``scatter`` apart in turn, so that no three of any six
        # consecutive views agree (the fused cluster never has the views to commit)
        k = len(cameras) % 4
        dx, dy = (scatter * (k % 2), scatter * (k // 2))
        return [GraspCandidate(XY[0] + dx, XY[1] + dy, 0.05, math.pi / 2, 0.04, 0.9, view_height)]

    cell.planner.candidates = scripted
    driver = CellDriver(cell)
    h = driver.start("Pick(body)")
    status = Status.RUNNING
    while status is Status.RUNNING and driver.context.get_time() < 40.0:
        status = driver.poll(h)
        if any(m.startswith("grasp at") for _, m in driver.skill_state().log):
            break
    return status, driver.skill_state().log, driver.skill_state(), cameras


def test_a_confident_prediction_commits_early_and_an_uncertain_one_explores(tmp_path):
    cell = _cell(tmp_path)
    status, log, s, cams = _pick(cell, 0.0)
    assert status is Status.RUNNING  # stopped at the grasp's approach
    commit = next(t for t, m in log if m.startswith("commit after 3 views"))
    grasp_t = next(t for t, m in log if m.startswith("grasp at"))
    start = next(t for t, m in log if m.startswith("view 1 "))
    assert s.committed and s.explored == 1  # view 2 explored, view 3 committed
    # straight down once committed: the camera over the body (within 1 cm) at the last views
    assert all(math.dist(c[:2], XY) < 0.01 for c in cams[-2:])

    status2, log2, s2, cams2 = _pick(cell, 0.03)
    assert status2 is Status.FAILURE
    assert any("no confident grasp on the body at the lowest point" in m for _, m in log2)
    assert not any(m.startswith("commit") for _, m in log2)
    start2 = next(t for t, m in log2 if m.startswith("view 1 "))
    end2 = next(t for t, m in log2 if "attempt 1 failed" in m)
    # it explored: more views, a slower way down, the camera beside the target
    assert len(cams2) > len(cams) + 5
    assert end2 - start2 > 2 * (grasp_t - start)
    assert max(math.dist(c[:2], XY) for c in cams2[2:]) > 0.02
    assert commit - start < 1.0


def test_a_descent_that_loses_its_target_says_so_and_never_takes_another(tmp_path):
    """Two bodies in W^A; once the descent follows the one at the centre, it is taken away
    (out of every view). The views say ``target lost`` and the attempt fails: the other body,
    in view at the look pose, is not followed silently. The next attempt states that it
    re-acquires, then follows the other body (a new track)."""
    from pydrake.math import RigidTransform

    path = write_scenario(
        tmp_path,
        [
            {"class": "body", "workspace": "A", "xy": [0.0, 0.0], "yaw": 0},
            {"class": "body", "workspace": "A", "xy": [0.1, -0.1], "yaw": 0},
        ],
    )
    cell = build_station(load_cell_scenario(path))
    cell.planner.candidates = lambda crop, X_WC, h: [
        GraspCandidate(XY[0], XY[1], 0.05, math.pi / 2, 0.04, 0.9, h)
    ]
    driver = CellDriver(cell)
    h = driver.start("Pick(body)")
    taken = None
    while driver.context.get_time() < 60.0 and driver.poll(h) is Status.RUNNING:
        s = driver.skill_state()
        if taken is None and any(m.startswith("view 1 ") for _, m in s.log):
            taken = s.track
            body = cell.cell.bodies["body_0"]
            cell.plant.SetFreeBodyPose(driver.plant_context(), body, RigidTransform([0.2, 0, 0]))
        if sum(m.startswith("view 1 ") for _, m in s.log) == 2:  # the next attempt's first
            break
    log = [m for _, m in driver.skill_state().log]
    assert taken is not None
    lost = [m for m in log if f"target lost (track {taken} not in view)" in m]
    assert len(lost) >= 3, log
    failed = next(i for i, m in enumerate(log) if "attempt 1 failed" in m)
    assert f"target lost: the body (track {taken}) left the view" in log[failed]
    assert not any(m.startswith("grasp at") for m in log[:failed])  # nothing grasped instead
    assert any(f"track {taken} not in view at the look pose; re-acquiring" in m for m in log)
    assert driver.skill_state().track not in (None, taken)  # the other body, its own track
