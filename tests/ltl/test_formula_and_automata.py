"""`tamp.ltl` formulas, letters, lasso acceptance and Kripke runs."""

from __future__ import annotations

import pytest

from tamp import ltl
from tamp.errors import InputError
from tamp.ltl.automata import (
    Stepper,
    accepting_continuation,
    accepts_lasso,
    live_states,
    started_at,
)
from tamp.ltl.formula import check_aps, temporal_conjuncts, temporal_operators
from tamp.ltl.kripke import intersecting_lasso, kripke
from tamp.ltl.letters import bdd_letter, letter_bdd, word_text


def test_parse_errors_and_comparisons():
    with pytest.raises(InputError, match="does not parse") as err:
        ltl.parse("G (a &", field="--formula")
    assert err.value.field == "--formula"
    with pytest.raises(InputError, match="empty formula"):
        ltl.parse("  ")
    f = ltl.parse("G (holding_count <= 1) & F goal")
    assert ltl.ap_names(f) == ["goal", "holding_count<=1"]
    assert len(ltl.conjuncts(f)) == 2


def test_unknown_propositions_name_the_file():
    with pytest.raises(InputError, match=r"unknown proposition\(s\) \['q'\]") as err:
        check_aps(ltl.parse("F q & F p1"), ["p1"], file="t.yaml")
    assert err.value.file == "t.yaml" and err.value.field == "formula"


def test_temporal_counts():
    f = ltl.parse("GF a & (b U c) & d & X e")
    assert temporal_operators(f) == 4
    assert temporal_conjuncts(f) == 3


def test_letters_round_trip_through_bdds():
    aut = ltl.translate("G(a -> F b)")
    for letter in (frozenset(), frozenset({"a"}), frozenset({"a", "b"})):
        assert bdd_letter(aut, letter_bdd(aut, letter | {"unused"})) == letter
    assert word_text([{"a"}], [{"b"}], ["a", "b"]) == "a & !b; cycle{!a & b}"


def test_lasso_acceptance_from_the_initial_state_and_elsewhere():
    aut = ltl.translate("F(a & F b)")
    assert accepts_lasso(aut, [{"a"}, set()], [{"b"}])[0]
    assert not accepts_lasso(aut, [{"b"}], [set()])[0]
    # the state after reading a (alone): b is enough from there
    init = aut.get_init_state_number()
    (q,) = Stepper(aut, finite=False).step(frozenset({init}), {"a"}) - {init}
    assert accepts_lasso(aut, [{"b"}], [set()], start=q)[0]
    assert started_at(aut, q).get_init_state_number() == q
    assert aut.get_init_state_number() != q  # the shared automaton is unchanged


def test_live_states_and_accepting_continuation():
    aut = ltl.translate("G !bad & F goal")
    live = live_states(aut, finite=False)
    assert aut.get_init_state_number() in live
    prefix, cycle = accepting_continuation(aut, aut.get_init_state_number(), finite=False)
    assert accepts_lasso(aut, prefix, cycle)[0]


def test_kripke_run_violating_a_property():
    # 0 -> 1 -> 2 (bad) -> 2: "G !bad" fails along 0 1 2 2 …
    neg = ltl.translate(ltl.negate(ltl.parse("G !bad")), ltl.NEGATION)
    labels = [frozenset(), frozenset(), frozenset({"bad"})]
    k = kripke(labels, [[1], [2], []], ["bad"], neg)
    prefix, cycle = intersecting_lasso(k, neg)
    assert prefix == [0, 1] and cycle == [2]
    ok = kripke([frozenset(), frozenset()], [[1], [0]], ["bad"], neg)
    assert intersecting_lasso(ok, neg) is None
