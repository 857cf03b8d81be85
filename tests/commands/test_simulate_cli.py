"""The flags every ``tamp simulate`` workcell has, checked on a stand-in cell (no simulation):
``--meshcat`` reaches the cell and the view is held open after the run, ``--timeline`` draws
the run's skills, ``--diagram`` renders the cell's diagram, and each refuses a wrong suffix."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import pytest

# the live view and the timeline are the sim extra's (Drake's Meshcat, matplotlib)
pytest.importorskip("pydrake", reason="needs the sim extra (pip install 'tamp-hrc[sim]')")

from tamp.commands import simulate as simulate_cmd  # noqa: E402
from tamp.commands.main import main  # noqa: E402
from tamp.perturbation import Applied  # noqa: E402
from tamp.sim.core.workcell import Option, RunResult, register, unregister  # noqa: E402


@dataclass(kw_only=True)
class LiveResult(RunResult):
    actions: list[dict] = field(default_factory=list)

    def details_json(self) -> dict:
        return {"actions": self.actions}


class FakeDiagram:
    def GetGraphvizString(self, max_depth: int = -1) -> str:  # noqa: N802 (Drake's name)
        return 'digraph d { plant -> controller [label="state"]; }'


class LiveCell:
    """A `Workcell` with a live view; ``seen`` keeps what its last run was given."""

    name = "test-live"
    title = "a stand-in with a live view (tests)"
    folder = "sim"
    key = "test_live"
    main = Option("scenario", "the scenario", flag="scenario")
    options: tuple[Option, ...] = ()
    replay = "tamp simulate test-live {scenario} --seed {seed}"

    def __init__(self) -> None:
        self.seen: dict = {}

    def load(self, name_or_path):
        return str(name_or_path)

    def perturbed(self, scenario, seed):
        return scenario, Applied(seed=seed)

    def build(self, scenario, **options):
        return FakeDiagram()

    def run(self, scenario, *, seed=0, record=None, max_sim_time=None, verify=True, meshcat=False):
        self.seen = {"meshcat": meshcat, "max_sim_time": max_sim_time, "verify": verify}
        if meshcat:
            from tamp.sim.core.recording import new_meshcat

            self.seen["viewer"] = new_meshcat()
        actions = [
            {"action": "MoveTo(O1)", "start": 0.0, "end": 2.0, "status": "HALTED"},
            {"action": "Pick(O1)", "start": 2.0, "end": 3.5, "status": "FAILURE"},
            {"action": "Pick(O1)", "start": 3.5, "end": 5.0, "status": "SUCCESS"},
        ]
        return LiveResult(
            workcell=self.name, scenario=scenario, status="SUCCESS", reason="done",
            sim_time=5.0, seed=seed, actions=actions,
        )  # fmt: skip


class ViewlessCell(LiveCell):
    name = "test-viewless"

    def run(self, scenario, *, seed=0, record=None, max_sim_time=None, verify=True):
        raise AssertionError("never reached: --meshcat is refused first")


@pytest.fixture
def cells():
    live, viewless = LiveCell(), ViewlessCell()
    register(live)
    register(viewless)
    yield live, viewless
    unregister(live.name)
    unregister(viewless.name)


def test_meshcat_reaches_the_cell_and_the_view_stays_open_after_the_run(cells, monkeypatch):
    live, _ = cells
    held = []
    monkeypatch.setattr(simulate_cmd, "wait_for_close", held.append)
    assert main(["simulate", "test-live", "x", "--meshcat", "--max-sim-time", "3"]) == 0
    assert live.seen["meshcat"] is True and live.seen["max_sim_time"] == 3.0
    assert held == [live.seen["viewer"]]  # the run drew into the view that is held open
    assert main(["simulate", "test-live", "x"]) == 0
    assert live.seen == {"meshcat": False, "max_sim_time": None, "verify": True}
    assert len(held) == 1  # no view, nothing held


def test_meshcat_on_a_cell_without_a_live_view_is_refused(cells, capsys):
    assert main(["simulate", "test-viewless", "x", "--meshcat"]) == 2
    assert "--meshcat" in capsys.readouterr().err


def test_every_registered_workcell_has_a_live_view():
    """`--meshcat` wherever a run happens: each packaged cell's run takes it."""
    from tamp.commands.simulate import check_meshcat
    from tamp.sim.core.workcell import get, workcells

    for name in workcells():
        check_meshcat(get(name))  # raises for a cell without one


def test_hold_open_waits_for_the_user_and_takes_ctrl_c(capsys):
    from tamp.sim.core.recording import hold_open

    class Viewer:
        def web_url(self) -> str:
            return "http://localhost:7000"

    waited = []
    hold_open(Viewer(), waited.append)
    out, err = capsys.readouterr()
    assert waited and out == ""  # stdout stays the run's report
    assert "http://localhost:7000" in err and "Enter" in err

    def interrupted(prompt: str) -> None:
        raise KeyboardInterrupt

    hold_open(Viewer(), interrupted)  # returns: Ctrl-C closes the view, no traceback


def test_timeline_draws_the_runs_skills(cells, tmp_path, capsys):
    out = tmp_path / "pics" / "run.svg"
    assert main(["simulate", "test-live", "x", "--timeline", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["schema"] == 1
    svg = out.read_text()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    assert "MoveTo" in svg and "Pick" in svg  # one row per skill


def test_diagram_is_rendered_by_its_suffix(cells, tmp_path):
    dot, svg = tmp_path / "d.dot", tmp_path / "d.svg"
    assert main(["simulate", "test-live", "x", "--diagram", str(dot)]) == 0
    assert dot.read_text().startswith("digraph d")
    assert main(["simulate", "test-live", "x", "--diagram", str(svg)]) == 0
    assert "<svg" in svg.read_text() and "controller" in svg.read_text()


@pytest.mark.parametrize(
    "flag, name", [("--timeline", "run.dot"), ("--diagram", "d.pdf"), ("--timeline", "run")]
)
def test_a_wrong_picture_suffix_exits_2_naming_the_flag(cells, tmp_path, capsys, flag, name):
    assert main(["simulate", "test-live", "x", flag, str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert flag in err and "suffix" in err
    assert cells[0].seen == {}  # refused before the run
    assert not Path(tmp_path / name).exists()
