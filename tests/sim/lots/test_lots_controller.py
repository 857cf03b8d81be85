"""The LOTS controller as a LeafSystem: what it observes (a camera view as a WorldState), the
skills it commands as its inputs change, and that only observation and skill status reach it."""

from __future__ import annotations

import copy

import pytest
from pydrake.systems.analysis import Simulator

from tamp.lots.cell import visible_counts
from tamp.lots.controller import LotsController
from tamp.lots.task import load_task
from tamp.sim.core.messages import Observation, SkillStatus
from tamp.sim.lots.controller_system import PERIOD, LotsControllerSystem, observed_state
from tamp.world.interface import Status


def test_observed_state_is_the_view_of_one_workspace():
    before = observed_state(Observation())
    assert visible_counts(before, "A") is None and visible_counts(before, "B") is None
    view = observed_state(Observation(id=4, side="B", counts={"body": 2, "peak": 1}))
    assert visible_counts(view, "B") == {"body": 2, "peak": 1}
    assert visible_counts(view, "A") is None  # the camera sees one workspace at a time


class Fixed:
    """The controller system alone, its inputs fixed by the test."""

    def __init__(self, task_name: str = "tower"):
        self.system = LotsControllerSystem(LotsController(load_task(task_name)))
        self.context = self.system.CreateDefaultContext()
        self.sim = Simulator(self.system, self.context)
        self.set(SkillStatus(), Observation())
        self.sim.AdvanceTo(1e-6)  # the first tick (t = 0)

    def set(self, status: SkillStatus, obs: Observation) -> None:
        self.system.skill_status_port.FixValue(self.context, status)
        self.system.observation_port.FixValue(self.context, obs)

    def advance(self, ticks: int = 1) -> None:
        self.sim.AdvanceTo(self.context.get_time() + ticks * PERIOD + 1e-9)

    def command(self):
        return self.system.command_port.Eval(self.context)


def test_controller_system_commands_skills_from_what_it_is_told():
    f = Fixed("tower")
    cmd = f.command()
    assert (cmd.id, cmd.name, cmd.args) == (1, "LookAt", ("A",))
    f.advance(3)  # the look is still running: no new command
    assert f.command().id == 1
    f.set(
        SkillStatus(1, Status.SUCCESS),
        Observation(1, 1.0, "A", {"bottom": 1, "body": 2, "peak": 1}),
    )
    f.advance(2)  # one tick decides, the next starts the pick
    cmd = f.command()
    assert (cmd.id, cmd.name, cmd.args) == (2, "Pick", ("bottom", "A"))
    f.set(SkillStatus(2, Status.SUCCESS), Observation(5, 6.0, "A", {"body": 2, "peak": 1}))
    f.advance(2)
    assert (f.command().name, f.command().args) == ("LookAt", ("B",))
    f.set(SkillStatus(3, Status.SUCCESS), Observation(6, 8.0, "B", {}))
    f.advance(2)
    assert (f.command().id, f.command().name, f.command().args) == (4, "Place", ("B",))
    s = f.system.state(f.context)
    assert [a.action for a in s.log] == ["LookAt(A)", "Pick(bottom, A)", "LookAt(B)", "Place(B)"]
    assert [a.status for a in s.log[:3]] == ["SUCCESS"] * 3 and s.log[3].status is None
    assert s.result is None and s.controller.belief.held == 0


def test_a_failed_pick_is_retried_with_a_fresh_look():
    f = Fixed("tower")
    f.set(
        SkillStatus(1, Status.SUCCESS),
        Observation(1, 1.0, "A", {"bottom": 1, "body": 2, "peak": 1}),
    )
    f.advance(2)
    f.set(SkillStatus(2, Status.FAILURE, "missed"), Observation(1, 1.0, "A", {}))
    f.advance(2)
    cmd = f.command()
    assert (cmd.id, cmd.name, cmd.args) == (3, "LookAt", ("A",))
    assert f.system.state(f.context).controller.failures == 1


def test_state_copies_do_not_share_the_controller():
    f = Fixed("tower")
    s = f.system.state(f.context)
    twin = copy.deepcopy(s)
    assert twin.controller is not s.controller and twin.log is not s.log
    twin.controller.belief.picked(0)
    assert s.controller.belief.held is None


@pytest.mark.slow
def test_only_observation_and_skill_status_reach_the_controller():
    from tamp.sim.lots.scenario import load_cell_scenario
    from tamp.sim.lots.simulate import build_lots_diagram

    built = build_lots_diagram(load_cell_scenario("tower"), LotsController(load_task("tower")))
    d, ctrl, cell = built.diagram, built.controller, built.cell.diagram
    fed = {
        (src.get_name(), src.get_output_port(i).get_name())
        for (dst, _), (src, i) in d.connection_map().items()
        if dst.get_name() == ctrl.get_name()
    }
    assert fed == {(cell.get_name(), "observation"), (cell.get_name(), "skill_status")}
    assert d.num_input_ports() == 0  # nothing outside feeds the diagram
    # the controller's own ports: exactly these two inputs
    assert [ctrl.get_input_port(i).get_name() for i in range(ctrl.num_input_ports())] == [
        "observation",
        "skill_status",
    ]
