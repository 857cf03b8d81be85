"""The verification gate on every table the LOTS controller builds, from where it is built."""

from __future__ import annotations

import dataclasses

import pytest

from tamp.lots.cell import held_kind, side_counts
from tamp.lots.controller import LotsController
from tamp.lots.person import ScriptedPerson
from tamp.lots.planner import Table
from tamp.lots.run import lots_world, run_task
from tamp.lots.task import Event, load_task
from tamp.verification import gate
from tamp.verification.lots import check_controller, check_run
from tamp.verification.verdict import VerificationError

from .helpers import events

#: after the robot placed the bottom, a person puts a peak into W^B: (1, 0, 1) is on no
#: planned run, so the controller replans from the automaton state after p1
PEAK_EARLY = (Event(after=1, kind="add", cls="peak", side="B"),)


def test_replanned_table_is_checked_from_where_the_replan_happened():
    task = load_task("tower.yaml")
    seen = []
    report = run_task(task, PEAK_EARLY, check=lambda c: seen.append((c.build, gate(c))))
    assert report.satisfied and report.replans == 1
    assert [b.label for b, _ in seen] == ["initial", "replan 1 at W^B bottom^1 body^0 peak^1"]
    build, passed = seen[-1]
    c = report.controller
    q, b = build.start
    assert b == (1, 0, 1) and q != c.aut.initial
    assert build.history == (frozenset({"p1"}), frozenset({"p3"}))  # the tree path to (q, b)
    assert passed.holds and all("replan 1" in v.subject for v in passed.verdicts)
    # the old check read the replanned run from q_0: a false violation (p1 is never seen)
    assert not check_run(c.aut, c.plan.prefix, c.plan.cycle).holds
    assert check_controller(c).holds  # after the run, the table in use still checks


@pytest.mark.parametrize(
    "task_name, ev",
    [
        ("example1.yaml", "example1_interference.yaml"),
        ("tower.yaml", "tower_interference.yaml"),
        ("model_building.yaml", "model_building_fig8.yaml"),
        ("model_building.yaml", "model_building_fig9.yaml"),
    ],
)
def test_every_build_of_the_packaged_interference_runs_holds(task_name, ev):
    task = load_task(task_name)
    reports = []
    report = run_task(task, events(ev, task), check=lambda c: reports.append(gate(c)))
    assert report.satisfied
    assert len(reports) == 1 + report.replans and all(r.holds for r in reports)


def _corrupt_replans(monkeypatch):
    """Tables rebuilt after a replan deliver their first two objects in swapped order."""
    real = Table.from_plan.__func__

    def from_plan(cls, plan, lots):
        t = real(cls, plan, lots)
        if plan.start[1] == (1, 0, 1):
            moves = [s for s in plan.steps if s.kind == "move"]
            steps = [s for s in plan.steps if s.kind != "move"] + moves[::-1]
            t = real(cls, dataclasses.replace(plan, steps=steps), lots)
        return t

    monkeypatch.setattr(Table, "from_plan", classmethod(from_plan))


def test_a_corrupted_rebuilt_table_is_stopped_before_the_robot_acts(monkeypatch):
    _corrupt_replans(monkeypatch)
    task = load_task("tower.yaml")
    c = LotsController(task, check=gate)
    world, person = lots_world(task), ScriptedPerson(PEAK_EARLY)

    def step():
        world.step()
        person.act(world)

    with pytest.raises(VerificationError) as err:
        c.run(world, step=step)
    assert "replan 1" in err.value.report.failed[0].subject
    # only the action before the replan happened; nothing was done with the bad table: the
    # body was picked under the initial table (p2), the replan came when the camera saw W^B
    assert [a.key() for a in c.actions] == [("move", "p1")]
    assert side_counts(world.state)["B"] == {"bottom": 1, "peak": 1}
    assert held_kind(world.state) == "body"
    assert c.running is None and not world.busy  # no skill was started on the bad table
    assert str(world.executed()[-1]) == "LookAt(B)"


def test_run_task_propagates_the_rejection_instead_of_calling_it_infeasible(monkeypatch):
    _corrupt_replans(monkeypatch)
    with pytest.raises(VerificationError):
        run_task(load_task("tower.yaml"), PEAK_EARLY, check=gate)
