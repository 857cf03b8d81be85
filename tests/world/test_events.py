"""The run vocabulary: --appear OBJ@PLACE[@WHEN], --fail ACTION[(ARGS)][xTIMES], NAME(args)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tamp.errors import InputError
from tamp.world import Point
from tamp.world.actions import default_domain
from tamp.world.events import (
    AfterAction,
    Appear,
    AtTick,
    AtTime,
    Fail,
    check_events,
    override,
    parse_appear,
    parse_call,
    parse_fail,
)

names = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,6}", fullmatch=True)
coords = st.floats(-100, 100, allow_nan=False).map(lambda v: round(v, 3))


def test_call_forms():
    assert parse_call("Pick(O1)") == ("Pick", ("O1",))
    assert parse_call(" Place( O1 ,L1 ) ") == ("Place", ("O1", "L1"))
    assert parse_call("MoveTo") == ("MoveTo", ())
    assert parse_call("Wait()") == ("Wait", ())
    for bad in ("Pick(O1", "Pick(O1,)", "1Pick", "Pick(O1)(O2)", ""):
        with pytest.raises(InputError):
            parse_call(bad, field="x")


def test_appear_forms():
    assert parse_appear("Oa@L1") == Appear("Oa", "L1", None)
    assert parse_appear("Oa@2.2,0.8,0.1") == Appear("Oa", Point(2.2, 0.8, 0.1))
    assert parse_appear("Oa@2.2,0.8@5") == Appear("Oa", Point(2.2, 0.8, 0.0), AtTick(5))
    assert parse_appear("Oa@L1@t=2.5").when == AtTime(2.5)
    assert parse_appear("Oa@L1@after:Pick(O1)").when == AfterAction("Pick", ("O1",))


@pytest.mark.parametrize(
    "text",
    ["Oa", "@L1", "Oa@", "Oa@1,2,3,4", "Oa@L1@soon", "Oa@L1@t=-1", "Oa@1e999,0", "Oa@nan,0"],
)
def test_appear_refused_naming_the_flag(text):
    with pytest.raises(InputError) as err:
        parse_appear(text)
    assert err.value.field == "--appear"


def test_fail_forms():
    assert parse_fail("Pick") == Fail("Pick", None, 1)
    assert parse_fail("Pick(O1)") == Fail("Pick", ("O1",), 1)
    assert parse_fail("Place(O1, L1)x2") == Fail("Place", ("O1", "L1"), 2)
    assert parse_fail("MoveTox3") == Fail("MoveTo", None, 3)
    with pytest.raises(InputError):
        parse_fail("Pick(O1)x0")
    assert Fail("Pick", None).matches("Pick", ("O9",))
    assert not Fail("Pick", ("O1",)).matches("Pick", ("O2",))


@given(
    names,
    st.one_of(names, st.tuples(coords, coords, coords).map(lambda t: Point(*t))),
    st.one_of(
        st.none(),
        st.integers(0, 10_000).map(AtTick),
        st.floats(0, 1000, allow_nan=False).map(lambda v: AtTime(round(v, 3))),
        st.tuples(names, st.lists(names, max_size=3)).map(lambda t: AfterAction(t[0], tuple(t[1]))),
    ),
)
def test_appear_round_trip(obj, place, when):
    a = Appear(obj, place, when)
    assert parse_appear(str(a)) == a


@given(names, st.one_of(st.none(), st.lists(names, max_size=3).map(tuple)), st.integers(1, 99))
def test_fail_round_trip(action, args, times):
    f = Fail(action, args, times)
    assert parse_fail(str(f)) == f


def test_override_replaces_the_files_entry_of_an_object():
    base = [Appear("Oa", "L1"), Appear("Ob", "L0")]
    assert override(base, [Appear("Oa", "L0", AtTick(3))]) == [
        Appear("Ob", "L0"),
        Appear("Oa", "L0", AtTick(3)),
    ]


def test_check_events_names_what_is_unknown():
    domain = default_domain()
    ok = dict(objects=["O0", "O1"], areas=["L0", "L1"], domain=domain)
    check_events([Appear("Oa", "L1", AfterAction("Pick", ("O1",)))], [Fail("Pick", ("Oa",))], **ok)
    bad = [
        ([Appear("Oa", "L9")], [], "unknown area"),
        ([Appear("Oa", "L1", AfterAction("Fly", ()))], [], "unknown action"),
        ([], [Fail("Pick", ("O7",))], "unknown object"),
        ([], [Fail("Place", ("O1",))], "takes 2 argument"),
    ]
    for appear, fail, why in bad:
        with pytest.raises(InputError, match=why):
            check_events(appear, fail, **ok)
