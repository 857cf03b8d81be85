"""The closed-loop descent in the workcell (Zhou et al. §IV-B, Fig. 6): with a prediction
that every view repeats the hand commits after the fewest views and goes straight down;
with one that scatters it explores (slowly, the camera shifted sideways, many views) and
fails the attempt at the lowest point. The final approach (closed loop by default): a body
that slides until the fingers close is held, and missed with the open approach; one taken
away during the approach is said to be lost. The grasp network is replaced by scripted
predictors so that the tests are about the descent, not about the network."""

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


def _on_target(cell) -> None:
    """A scripted predictor: every view's grasp on the target's detected centre, closing
    across the body (world y at yaw 0): the tests are about the approach, not the network."""
    from pydrake.math import RigidTransform

    from tamp.sim.core.camera import backproject

    K = cell.planner.intrinsics

    def scripted(crop, X_WC, view_height):
        d = crop.detection
        p = backproject(d.u, d.v, d.depth, K, RigidTransform(np.asarray(X_WC)))
        return [GraspCandidate(p[0], p[1], p[2], math.pi / 2, 0.04, 0.9, view_height)]

    cell.planner.candidates = scripted


def _slide(tmp_path, approach: str | None) -> tuple[Status, list[str], float, np.ndarray | None]:
    """One ``Pick(body)`` (one attempt) of a body that slides across the closing line at
    2 cm/s from 1.5 s after the pick starts until the fingers close on it (set on the plant
    every 20 ms: a conveyor). ``approach``: the scenario's ``grasp.descent.approach`` (None:
    the default). Returns the status, the skill log, the body's height at the end and where
    it was when the fingers closed."""
    from pydrake.math import RigidTransform
    from pydrake.multibody.math import SpatialVelocity

    from tamp.sim.lots.skills import CLOSED

    descent = {} if approach is None else {"approach": approach}
    path = write_scenario(
        tmp_path,
        [{"class": "body", "workspace": "A", "xy": [0.0, -0.05], "yaw": 0}],
        grasp={"network": "hrgnet", "attempts": 1, "descent": descent},
    )
    cell = build_station(load_cell_scenario(path))
    _on_target(cell)
    plant, body = cell.plant, cell.cell.bodies["body_0"]
    velocity = np.array([0.0, 0.02, 0.0])
    driver = CellDriver(cell, tick=0.02)
    h = driver.start("Pick(body)")
    origin, closed_at = None, None
    while driver.poll(h) is Status.RUNNING and driver.context.get_time() < 20.0:
        t, ctx = driver.context.get_time(), driver.plant_context()
        if t < 1.5 or closed_at is not None:
            continue
        X = plant.EvalBodyPoseInWorld(ctx, body)
        if driver.skill_state().finger == CLOSED:
            closed_at = X.translation().copy()
            plant.SetFreeBodySpatialVelocity(ctx, body, SpatialVelocity.Zero())
            continue
        origin = X.translation().copy() if origin is None else origin
        p = origin + (t - 1.5) * velocity
        p[2] = X.translation()[2]
        plant.SetFreeBodyPose(ctx, body, RigidTransform(X.rotation(), p))
        plant.SetFreeBodySpatialVelocity(ctx, body, SpatialVelocity(np.zeros(3), velocity))
    z = float(plant.EvalBodyPoseInWorld(driver.plant_context(), body).translation()[2])
    log = [m for _, m in driver.skill_state().log]
    return driver.status().status, log, z, closed_at


def test_the_closed_approach_follows_a_target_that_slides_until_the_fingers_close(tmp_path):
    """The body slides across the closing line through the descent and the final approach
    (6 cm or more between the view the grasp was fused in and the fingers closing). The
    closed approach (the default) keeps viewing on its way down, carries the grasp with the
    body, goes on at the body's velocity where the gripper hides it, and holds it; the open
    one (fixed moves from the last view of the descent) closes where the body was."""
    status, log, z, closed_at = _slide(tmp_path, None)
    assert status is Status.SUCCESS and z > 0.05, log
    start = next(i for i, m in enumerate(log) if m.startswith("grasp at"))
    x0, y0 = (float(v) for v in log[start].split("(")[1].split(",")[:2])
    assert any(m.startswith("view ") for m in log[start:])  # it looked on the way down
    last = next(m for m in log if m.startswith("approach: last view"))
    vx, vy = (float(v) for v in last.split("goes on at (")[1].split(")")[0].split(","))
    assert abs(vx) < 4 and abs(vy - 20) < 4, last  # mm/s: the body's velocity, from its views
    at = next(m for m in log if m.startswith("at the grasp"))
    x, y = (float(v) for v in at.split("(")[1].split(",")[:2])
    assert closed_at is not None and closed_at[1] - y0 > 0.02  # it slid on after the choice ...
    assert math.dist((x, y), closed_at[:2]) < 0.005  # ... and the fingers closed round it

    status, log, z, closed_at = _slide(tmp_path, "open")
    assert status is Status.FAILURE and z < 0.05
    assert any("missed: the fingers closed on nothing" in m for m in log)
    assert not any(m.startswith("approach") for m in log)


def test_a_target_lost_in_the_final_approach_is_said_and_fails_the_attempt(tmp_path):
    """The body is taken out of the workspace once the approach starts: the approach's views
    say ``target lost``, the hand does not go down where it cannot see, and the attempt
    fails (retried as any failed attempt; here the only one)."""
    from pydrake.math import RigidTransform

    path = write_scenario(
        tmp_path,
        [{"class": "body", "workspace": "A", "xy": [0.0, 0.0], "yaw": 0}],
        grasp={"network": "hrgnet", "attempts": 1},
    )
    cell = build_station(load_cell_scenario(path))
    _on_target(cell)
    driver = CellDriver(cell)
    h = driver.start("Pick(body)")
    taken = False
    while driver.poll(h) is Status.RUNNING and driver.context.get_time() < 20.0:
        s = driver.skill_state()
        if not taken and any(m.startswith("grasp at") for _, m in s.log):
            body = cell.cell.bodies["body_0"]
            cell.plant.SetFreeBodyPose(driver.plant_context(), body, RigidTransform([0.2, 0, 0]))
            taken = True
        if taken:  # the fingers stay a gate's height over the table: never down blind
            assert cell.skills.kin.tcp_pose(s.q).translation()[2] > 0.1
    log = [m for _, m in driver.skill_state().log]
    assert taken and driver.status().cause == "object_not_found"
    assert sum("target lost" in m for m in log) >= 3
    failed = next(m for m in log if "attempt 1 failed" in m)
    assert "left the view during the final approach" in failed
    assert not any(m.startswith("at the grasp") for m in log)
