"""The one SymbolicWorld: skill timing, outcome sources, events of the run vocabulary."""

from __future__ import annotations

import copy
import dataclasses

import pytest

from tamp.errors import InputError
from tamp.world import Area, ObjectState, Point, Pose, WorldState, default_domain
from tamp.world.actions import Domain
from tamp.world.events import AfterAction, Appear, AtTick, AtTime, Fail, Remove, parse_call
from tamp.world.interface import Status
from tamp.world.outcomes import BranchingOutcomes, ScriptedOutcomes
from tamp.world.symbolic import SymbolicWorld, state_key

S, F, R = Status.SUCCESS, Status.FAILURE, Status.RUNNING
D = default_domain()


def _state() -> WorldState:
    return WorldState(
        robot=Pose.at(0.0, 0.0),
        objects={"O1": ObjectState("O1", Pose.at(0.5, 0.0, 0.1))},
        areas={"L1": Area("L1", Point(3.0, 0.0), 0.15), "L2": Area("L2", Point(0.4, 0.3), 0.15)},
    )


def _run(world: SymbolicWorld, *actions: str, domain: Domain = D) -> list[Status]:
    """Start each action, stepping until it finishes; the statuses in order."""
    out = []
    for text in actions:
        name, args = parse_call(text)
        h = world.start(domain.action(name, *args))
        st = world.poll(h)
        while st is R:
            world.step()
            st = world.poll(h)
        out.append(st)
    return out


def test_skill_takes_its_ticks_and_applies_effects() -> None:
    w = SymbolicWorld(_state(), skill_ticks={"Pick": 3})
    h = w.start(D.action("Pick", "O1"))
    polls = [w.poll(h)]
    for _ in range(3):
        w.step()
        polls.append(w.poll(h))
    assert polls == [R, R, R, S] and w.state.held == "O1"
    assert [str(e) for e in w.history] == ["start Pick(O1)", "Pick(O1) -> SUCCESS"]
    assert w.poll(h) is S  # sticky


def test_scripted_failures_fail_the_first_times_attempts() -> None:
    w = SymbolicWorld(_state(), outcomes=ScriptedOutcomes([Fail("Pick", ("O1",), 2)]))
    assert _run(w, "Pick(O1)", "Pick(O1)", "Pick(O1)") == [F, F, S]
    assert w.history[1].what == "Pick(O1): scripted failure"


def test_per_tick_record_flags_failures_and_placing_into_an_occupied_area() -> None:
    place = D.template("Place")
    careless = dataclasses.replace(
        place, con=tuple(c for c in place.con if c.predicate != "IsAreaFree")
    )
    domain = Domain("careless", {**D.templates, "Place": careless})
    w = SymbolicWorld(_state().with_object_at("Ob", Pose.at(0.4, 0.3, 0.1)))
    w.step()
    assert _run(w, "Place(O1, L2)", domain=domain) == [F] and w.action_failed  # hand empty
    w.step()
    assert not w.action_failed
    assert _run(w, "Pick(O1)") == [S] and not w.placed_in_occupied
    w.step()
    assert _run(w, "Place(O1, L2)", domain=domain) == [S] and w.placed_in_occupied
    w.step()
    assert not w.placed_in_occupied


def test_appear_at_an_area_resolves_its_centre_and_unknown_areas_are_bad_input() -> None:
    w = SymbolicWorld(_state(), events=[Appear("Oa", "L1", AtTick(2))])
    w.step()
    assert "Oa" not in w.state.objects
    w.step()
    assert w.state.objects["Oa"].pos == Point(3.0, 0.0, 0.0)
    assert str(w.history[-1]) == "Oa appears at (3, 0)"
    with pytest.raises(InputError, match="unknown area 'L9'"):
        SymbolicWorld(_state(), events=[Appear("Oa", "L9")])


def test_at_time_uses_the_tick_period() -> None:
    w = SymbolicWorld(_state(), events=[Appear("Oa", "L1", AtTime(1.0))], tick_period=0.25)
    fired = []
    for _ in range(5):
        w.step()
        fired.append("Oa" in w.state.objects)
    assert fired == [False, False, False, True, True]


def test_after_action_fires_right_after_that_skill_succeeds() -> None:
    w = SymbolicWorld(
        _state(),
        events=[Appear("Oa", Point(0.4, 0.3), AfterAction("Pick", ("O1",)))],
        outcomes=ScriptedOutcomes([Fail("Pick")]),
    )
    assert _run(w, "Pick(O1)") == [F] and "Oa" not in w.state.objects
    w.step()
    assert _run(w, "Pick(O1)") == [S] and "Oa" in w.state.objects  # same tick
    assert [e.kind for e in w.tick_events()][-2:] == ["success", "appear"]


def test_a_known_object_is_moved_and_dropped_from_the_hand() -> None:
    w = SymbolicWorld(_state(), events=[Appear("O1", "L1", AtTick(3))])
    assert _run(w, "Pick(O1)") == [S] and w.state.held == "O1"
    while w.clock < 3:
        w.step()
    assert w.state.held is None and w.state.objects["O1"].pos == Point(3.0, 0.0, 0.0)
    assert w.history[-1].kind == "move" and str(w.history[-1]) == "O1 is moved to (3, 0)"


@pytest.mark.parametrize("on_arrival", [True, False])
def test_discovery_on_arrival_or_at_the_next_step(on_arrival: bool) -> None:
    w = SymbolicWorld(_state(), events=[Appear("Oa", "L1")], discover_on_arrival=on_arrival)
    assert _run(w, "MoveTo(L1)") == [S]
    assert ("Oa" in w.state.objects) is on_arrival
    w.step()
    assert "Oa" in w.state.objects


def test_branching_outcomes_record_decisions_within_the_bound() -> None:
    out = BranchingOutcomes([Fail("Pick", ("O1",))], max_failures=1)
    w = SymbolicWorld(_state(), outcomes=out)
    out.choose([F])
    assert _run(w, "MoveTo(L2)", "Pick(O1)") == [S, F]  # MoveTo may not fail: no decision
    assert out.decisions == [F] and out.failures_left == 0
    out.choose([F])
    assert _run(w, "Pick(O1)") == [S] and out.decisions == []  # bound reached


def test_deepcopy_is_independent_and_fingerprints_compare() -> None:
    out = BranchingOutcomes(max_failures=1)
    w = SymbolicWorld(_state(), outcomes=out, events=[Appear("Oa", "L1", AtTick(5))])
    h = w.start(D.action("Pick", "O1"))
    twin = copy.deepcopy(w)
    assert twin.fingerprint() == w.fingerprint()
    twin.outcomes.choose([F])
    twin.step()
    assert twin.poll(h) is F and w.running is not None and w.outcomes.failures_left == 1
    assert twin.fingerprint() != w.fingerprint()
    w.step()
    assert w.poll(h) is S and twin.state.held is None and w.state.held == "O1"


def test_happen_applies_a_person_s_appear_or_remove_now() -> None:
    w = SymbolicWorld(_state())
    w.happen(Appear("cube", "L1", AtTick(99), kind="cube"))  # WHEN is ignored: now
    assert w.state.objects["cube"].kind == "cube" and w.state.objects["cube"].pos == Point(3, 0)
    w.happen(Appear("cube", "L2", kind="other"))  # a known object keeps its kind
    assert w.state.objects["cube"].kind == "cube"
    _run(w, "MoveTo(O1)", "Pick(O1)")
    w.happen(Remove("O1"))  # taken out of the hand
    assert "O1" not in w.state.objects and w.state.held is None
    assert [(e.kind, e.what) for e in w.history if e.kind in ("appear", "move", "remove")] == [
        ("appear", "cube at (3, 0)"),
        ("move", "cube at (0.4, 0.3)"),
        ("remove", "O1"),
    ]
    for bad in (Remove("nope"), Appear("cube", "L9")):
        with pytest.raises(ValueError):
            w.happen(bad)


# -- piles: objects known by class stay counts -----------------------------------------------


def _pile_world(n: int) -> SymbolicWorld:
    from tamp.lots.cell import initial_state

    return SymbolicWorld(initial_state({"A": {"body": n}, "B": {}}))


def test_a_pile_is_one_entry_whatever_its_count():
    world = _pile_world(10_000_000)
    assert len(world.state.objects) == 1
    assert world.state.kinds_in(world.state.area("A")) == {"body": 10_000_000}
    assert world.state.summary()["counts"] == {"body_1": 10_000_000}


def test_picking_from_a_pile_splits_one_object_off():
    from tamp.lots.cell import held_kind, lots_domain, side_counts

    world = _pile_world(5)
    assert _run(world, "Pick(body,A)", domain=lots_domain()) == [Status.SUCCESS]
    assert held_kind(world.state) == "body"
    assert side_counts(world.state)["A"] == {"body": 4}
    assert _run(world, "Place(B)", domain=lots_domain()) == [Status.SUCCESS]
    assert side_counts(world.state)["B"] == {"body": 1}
    assert len(world.state.objects) == 2


def test_a_person_moves_and_removes_part_of_a_pile():
    from tamp.lots.cell import side_counts

    world = _pile_world(7)
    world.happen(Appear("body_1", "B", count=3))
    assert side_counts(world.state)["A"] == {"body": 4}
    assert side_counts(world.state)["B"] == {"body": 3}
    moved = next(u for u in world.state.objects if u != "body_1")
    world.happen(Remove(moved, count=2))
    assert side_counts(world.state)["B"] == {"body": 1}
    world.happen(Remove("body_1"))  # the whole pile
    assert side_counts(world.state)["A"] == {}
    with pytest.raises(ValueError, match="only 1"):
        world.happen(Remove(moved, count=2))


def test_piles_of_different_counts_are_different_states():
    assert state_key(_pile_world(2).state) != state_key(_pile_world(3).state)
