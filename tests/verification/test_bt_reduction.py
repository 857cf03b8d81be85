"""The reduced BT exploration (what the gate runs) against the explicit one, and its scale.

Property: on random demonstrations of growing size, with random skill failures, obstacles,
and injected faults (a Place without its IsAreaFree precondition: an unsafe step; no
retries left after a failure, or no Place at all: an unachievable goal), every property's
verdict of the reduced exploration (`tamp.verification.bt.explore`, ``reduce=True``) equals the
explicit exploration's (``reduce=False``), which merges states only on the whole tree, and
the reduced system never has more states. Then: the reduced exploration grows linearly with
the goals, and ``tamp plan --execute`` runs the 72-goal demonstration (four objects, 18
steps each) through the gate.
"""

from __future__ import annotations

import dataclasses
import json
import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tamp.bt.executor import PaBtExecutor
from tamp.commands.main import main
from tamp.demo import load_demonstration
from tamp.verification import VerificationError
from tamp.verification.bt import DEFAULT_PROPERTIES, VerificationUnknown, check_tree, executor_for
from tamp.verification.gate import gate_tree
from tamp.world.events import Appear, Fail
from tamp.world.predicates import IsObjectAt
from tests.demo.generate import write_demo
from tests.rg.strategies import demonstrations

#: Examples per size (raise with VERIFY_EXAMPLES=200 for a longer sweep).
EXAMPLES = int(os.environ.get("VERIFY_EXAMPLES", "12"))

PROPERTIES = [
    *DEFAULT_PROPERTIES,
    "F failed | F goal",
    'G !"IsGraspedObject(O0)"',
    "G (action_failed -> F goal)",
    "G (goal -> G !holding)",
]


def _without_area_check(domain):
    """The unsafe step: Place no longer requires its target area to be free."""
    place = domain.templates["Place"]
    con = tuple(c for c in place.con if c.predicate != "IsAreaFree")
    return dataclasses.replace(
        domain, templates={**domain.templates, "Place": dataclasses.replace(place, con=con)}
    )


def _without_place(domain):
    """The unachievable goal: no template puts an object anywhere."""
    templates = {k: v for k, v in domain.templates.items() if k != "Place"}
    return dataclasses.replace(domain, templates=templates)


@st.composite
def trees(draw, max_steps: int):
    """A demonstration, its executor (maybe faulty), events, failures and a property set."""
    demo = draw(demonstrations(max_objects=3, max_steps=max_steps))
    fault = draw(st.sampled_from(["none", "none", "unsafe", "no_retry", "no_place"]))
    domain = demo.domain()
    if fault == "unsafe":
        domain = _without_area_check(domain)
    elif fault == "no_place":
        domain = _without_place(domain)
    c_goal = [IsObjectAt(g.object, g.area.name) for g in demo.goals]
    executor = PaBtExecutor(
        c_goal,
        domain,
        free_areas=list(demo.free_areas),
        max_retries=0 if fault == "no_retry" else 3,
    )
    events = []
    if draw(st.booleans()):  # an obstacle appears in a goal area
        goal = draw(st.sampled_from(demo.goals))
        events.append(Appear("X", goal.area.pos))
    max_failures = draw(st.integers(0, 2))
    failures = None
    if draw(st.booleans()):
        failures = [Fail(draw(st.sampled_from(["MoveTo", "Pick", "Place"])), None, 1)]
    props = draw(st.lists(st.sampled_from(PROPERTIES), min_size=1, max_size=3, unique=True))
    return demo, executor, events, failures, max_failures, props


def _both(case):
    demo, executor, events, failures, max_failures, props = case
    kw = dict(events=events, failures=failures, max_failures=max_failures)
    fast = check_tree(executor, demo.initial_world(), props, reduce=True, **kw)
    slow = check_tree(executor, demo.initial_world(), props, reduce=False, **kw)
    return fast, slow


@pytest.mark.parametrize(
    "max_steps",
    [2, 4, pytest.param(6, marks=pytest.mark.slow)],  # 6: 9 s, `make test` only
)
def test_reduced_verdicts_equal_the_explicit_exploration(max_steps) -> None:
    seen: set[str] = set()

    @settings(
        max_examples=EXAMPLES,
        deadline=None,
        derandomize=EXAMPLES <= 12,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(trees(max_steps))
    def check(case) -> None:
        fast, slow = _both(case)
        assert fast.explored <= slow.explored
        for f, s in zip(fast.verdicts, slow.verdicts, strict=True):
            assert f.formula == s.formula
            assert f.status == s.status, (f.formula, f.text(), s.text())
            seen.add(f.status)

    check()
    assert "holds" in seen and "violated" in seen  # both kinds of tree were drawn


@pytest.mark.parametrize("fault", ["unsafe", "no_place"])
def test_injected_faults_are_found_by_both(fault) -> None:
    """Case-2-like swap: O0 goes where O1 stands; the faults are refused by both ways."""
    from tamp.demo import make_demonstration
    from tamp.world import Point

    demo = make_demonstration(
        {"O0": Point(1.0, 0.0), "O1": Point(1.0, 1.0)},
        [("O1", Point(2.0, 1.0)), ("O0", Point(1.0, 1.0))],
        0.15,
    )
    domain = _without_area_check(demo.domain()) if fault == "unsafe" else None
    if fault == "no_place":
        domain = _without_place(demo.domain())
    order = ["G1", "G0"] if fault == "unsafe" else None  # O0 first: onto O1
    exe = executor_for(demo, order, domain=domain)
    case = (demo, exe, [], None, 0, list(DEFAULT_PROPERTIES))
    fast, slow = _both(case)
    assert fast.violated and slow.violated
    assert [v.status for v in fast.verdicts] == [v.status for v in slow.verdicts]
    with pytest.raises(VerificationError):
        gate_tree(exe, demo.initial_world(), max_failures=0)


@pytest.mark.parametrize("goals", [10, 30])
def test_states_grow_linearly_with_the_goals(tmp_path, goals) -> None:
    """Four chains of goals: the reduced exploration visits a bounded number of states per
    goal (one skill failure anywhere), where the explicit one grows quadratically."""
    demo = load_demonstration(write_demo(tmp_path / "d.yaml", goals, "multi", n_objects=4))
    report = check_tree(executor_for(demo), demo.initial_world())
    assert report.holds
    assert report.explored <= 20 * goals


def test_the_gate_says_unknown_beyond_its_budget(tmp_path) -> None:
    demo = load_demonstration(write_demo(tmp_path / "d.yaml", 10, "multi", n_objects=4))
    with pytest.raises(VerificationUnknown) as err:
        gate_tree(executor_for(demo), demo.initial_world(), budget=20)
    assert "budget of 20 states" in str(err.value) and "--verify-budget" in str(err.value)
    assert err.value.exit_code == 1
    report = gate_tree(executor_for(demo), demo.initial_world(), budget=20, allow_unknown=True)
    assert report.status == "unknown"


def test_plan_execute_verifies_the_72_goal_demonstration(tmp_path, capsys) -> None:
    """Four objects, 18 steps each: verified and executed (no wall time asserted)."""
    path = write_demo(tmp_path / "d72.yaml", 72, "multi", n_objects=4)
    code = main(["plan", str(path), "--execute", "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    doc = json.loads(out.out)
    assert doc["verified"] is True and doc["reached"] is True
    assert doc["goals_reached"] == 72
    assert "unknown" not in out.err and "warning" not in out.err
