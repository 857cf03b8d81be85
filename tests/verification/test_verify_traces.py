"""Known verdicts and explanations for trace checking (paper formulas, order, stutter, empty)."""

from __future__ import annotations

import pytest
import spot

from tamp import ltl
from tamp.errors import InputError
from tamp.verification.traces import check_trace
from tamp.verification.words import Word, load_trace, parse_word
from tests.verification.ltlf_oracle import lasso_violates, ltlf_holds, prefix_is_bad

# Zhou et al. §IV Example 1 / §VI-A (model building) and §VI-B (tower, an F-chain).
PHI_MODEL = "GF p1 & GF p2 & GF p3 & GF p4"
PHI_TOWER = "F(p1 & F(p2 & F p3))"


def verdict(formula: str, word: str, finite: bool | None = None):
    return check_trace(formula, parse_word(word), finite=finite)


# -- known verdicts -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("word", "holds"),
    [
        ("cycle{p1; p2; p3; p4}", True),
        ("{}; {}; cycle{p4; p3; p2 & p1}", True),  # order is not part of GF conjunctions
        ("cycle{p1 & p2 & p3 & p4}", True),
        ("p1; p2; p3; p4; cycle{p1; p2; p3}", False),  # p4 stops recurring
        ("cycle{{}}", False),
    ],
)
def test_model_building_gf_conjunction(word: str, holds: bool) -> None:
    v = verdict(PHI_MODEL, word)
    assert v.holds is holds
    assert v.semantics == "infinite"
    if not holds:
        ce = v.counterexample
        # A GF violation has no finite bad prefix: only the repetition of the cycle fails.
        assert ce.position is None
        assert check_trace(PHI_MODEL, ce.accepting_word).holds
        assert ce.accepting_word.prefix[: len(ce.word.prefix)] == ce.word.prefix


@pytest.mark.parametrize(
    ("word", "holds"),
    [
        ("p1; p2; p3", True),
        ("{}; p1; {}; p2; p2; p3", True),
        ("p1 & p2 & p3", True),  # all three at once: F-chain allows the same instant
        ("p2; p1; p3", False),  # body before bottom: the chain needs p2 after p1
        ("p1; p3; p2", False),
        ("p1; p2", False),  # ends before the peak
    ],
)
def test_tower_f_chain_finite(word: str, holds: bool) -> None:
    v = verdict(PHI_TOWER, word, finite=True)
    assert v.holds is holds
    assert v.holds == ltlf_holds(spot.formula(PHI_TOWER), list(parse_word(word).prefix))
    if not holds:
        acc = v.counterexample.accepting_word
        assert ltlf_holds(spot.formula(PHI_TOWER), list(acc.prefix))


def test_tower_wrong_order_lasso_is_not_a_bad_prefix_but_stopping_is() -> None:
    # p2, p1, p3 then idle forever: p1 happened but p2/p3 never again after it.
    v = verdict(PHI_TOWER, "p2; p1; p3; cycle{{}}")
    assert not v.holds
    assert v.counterexample.position is None  # any prefix could still be completed
    assert verdict(PHI_TOWER, "p2; p1; p3; p2; p3; cycle{{}}").holds


def test_safety_violation_reports_first_bad_position_and_comparison_word() -> None:
    v = verdict("G !bad & F done", "a; a; bad; done", finite=True)
    ce = v.counterexample
    assert not v.holds and ce.position == 2
    assert ce.violated == ["G!bad"]
    assert ce.accepting_word.prefix[:2] == ce.word.prefix[:2]
    assert "bad" not in ce.accepting_word.prefix[2]
    assert check_trace("G !bad & F done", ce.accepting_word).holds


def test_safety_violation_lasso_inside_cycle() -> None:
    v = verdict("G(req -> X ack)", "{}; cycle{{}; req; {}}")
    ce = v.counterexample
    assert not v.holds
    assert ce.position == 3  # positions: 0 prefix, 1 {}, 2 req, 3 {} (no ack) -> dead
    assert prefix_is_bad(
        spot.formula("G(req -> X ack)"), [ce.word.letter(i) for i in range(4)], finite=False
    )
    assert not prefix_is_bad(
        spot.formula("G(req -> X ack)"), [ce.word.letter(i) for i in range(3)], finite=False
    )


def test_stutter_does_not_change_verdict_of_next_free_formulas() -> None:
    f = "(!p2 U p1) & F p2"
    for base, stuttered in [
        ("p1; p2; cycle{{}}", "p1; p1; p1; p2; p2; cycle{{}; {}}"),
        ("p2; p1; cycle{p2}", "p2; p2; p2; p1; cycle{p2; p2}"),
    ]:
        assert verdict(f, base).holds == verdict(f, stuttered).holds
    # but X sees stutter
    assert verdict("p1 & X p2", "p1; p2; cycle{{}}").holds
    assert not verdict("p1 & X p2", "p1; p1; p2; cycle{{}}").holds


def test_empty_traces() -> None:
    # LTLf traces are non-empty: the empty trace satisfies nothing, not even `true`.
    for f in ("1", "G a", "F a", "!a"):
        v = verdict(f, "", finite=True)
        assert not v.holds
        assert "empty trace" in v.counterexample.reason
    # the empty prefix of a lasso is fine
    assert verdict("G a", "cycle{a}").holds
    assert not verdict("G a", "cycle{{}}").holds


def test_letters_are_full_valuations_and_extra_props_are_ignored() -> None:
    # `p1` alone means p2 is false: a partial letter must not make `p1 & p2` hold.
    assert not verdict("p1 & p2", "p1; cycle{{}}").holds
    assert verdict("p1 & !p2", "p1; cycle{{}}").holds
    # a proposition the formula does not mention is allowed and ignored
    assert verdict("G p1", "cycle{p1 & other}").holds
    assert verdict("G p1", "p1 & !zzz; cycle{p1 & zzz}").holds


def test_unsatisfiable_formula_explained() -> None:
    v = verdict("G a & F !a", "cycle{a}")
    assert not v.holds
    assert "unsatisfiable" in v.counterexample.reason
    assert v.counterexample.accepting_word is None


def test_large_conjunction_is_checked_conjunct_by_conjunct() -> None:
    n = 12  # the whole-formula automaton would have 2^12 states
    f = " & ".join(f"F g{i}" for i in range(n))
    letters = [frozenset(f"g{j}" for j in range(i)) for i in range(n + 1)]
    assert check_trace(f, Word.lasso(letters, [letters[-1]])).holds
    bad = check_trace(f, Word.lasso(letters[:-1], [letters[-2]]))
    assert not bad.holds
    assert bad.counterexample.violated == [f"Fg{n - 1}"]


@pytest.mark.parametrize("n", [8, 9, 12])
@pytest.mark.parametrize("finite", [False, True])
def test_unsatisfiable_conjunction_is_explained_at_any_size(n: int, finite: bool) -> None:
    # beyond 8 conjuncts `F a` alone was explained ("every finite prefix can still
    # be extended"), but the conjunction is unsatisfiable
    f = "G !a & F a & " + " & ".join(f"F g{i}" for i in range(n - 2))
    assert len(ltl.conjuncts(ltl.parse(f))) == n
    letter = frozenset(f"g{i}" for i in range(n - 2))
    word = Word.finite([letter]) if finite else Word.lasso([], [letter])
    v = check_trace(f, word, finite=finite)
    assert not v.holds
    assert "unsatisfiable" in v.counterexample.reason
    assert "extended" not in v.counterexample.reason
    assert v.counterexample.violated == ["Fa"]
    assert v.counterexample.accepting_word is None


def test_too_large_conjunction_explanation_names_its_conjunct() -> None:
    n = 12  # 2^12 states: the whole automaton does not translate within EXPLAIN_LIMITS
    f = " & ".join(f"F g{i}" for i in range(n))
    letters = [frozenset(f"g{j}" for j in range(i)) for i in range(n)]
    ce = check_trace(f, Word.lasso(letters, [letters[-1]])).counterexample
    assert ce.reason.startswith(f"conjunct Fg{n - 1} alone (the whole formula is too large")
    assert "repeating the cycle forever never satisfies it" in ce.reason


def test_semantics_mismatch_is_bad_input() -> None:
    with pytest.raises(InputError):
        check_trace("F a", parse_word("a; cycle{a}"), finite=True)
    with pytest.raises(InputError):
        check_trace("F a", parse_word("a"), finite=False)


def test_oracles_agree_on_a_known_case() -> None:
    f = spot.formula("a U b")
    assert lasso_violates(f, [frozenset({"a"})], [frozenset()])
    assert not lasso_violates(f, [frozenset({"a"})], [frozenset({"b"})])


# -- word syntax and trace files ------------------------------------------------------------


def test_parse_word_forms() -> None:
    w = parse_word('p1 & !p2; {}; "holding_count<=1"; cycle{p2; !p1}')
    assert w.prefix == (frozenset({"p1"}), frozenset(), frozenset({"holding_count<=1"}))
    assert w.cycle == (frozenset({"p2"}), frozenset())
    assert parse_word("") == Word((), None)
    assert parse_word("a; b;").prefix == (frozenset({"a"}), frozenset({"b"}))


@pytest.mark.parametrize(
    "text",
    ["a | b", "a & !a", "a;;b", "cycle{a}; b", "cycle{}", "a & (b)", "true", '"a', "a b"],
)
def test_parse_word_rejects(text: str) -> None:
    with pytest.raises(InputError):
        parse_word(text)


def test_formula_parse_errors_and_comparisons() -> None:
    with pytest.raises(InputError, match="does not parse"):
        ltl.parse("G (a &")
    f = ltl.parse("G (holding_count <= 1) & F goal")
    assert ltl.ap_names(f) == ["goal", "holding_count<=1"]


def test_trace_file_yaml_and_json(tmp_path) -> None:
    y = tmp_path / "t.yaml"
    y.write_text("version: 1\ntrace:\n  - [p1]\n  - 'p2 & !p1'\n  - []\ncycle:\n  - [p2]\n")
    w = load_trace(y)
    assert w.prefix == (frozenset({"p1"}), frozenset({"p2"}), frozenset())
    assert w.cycle == (frozenset({"p2"}),)
    j = tmp_path / "t.json"
    j.write_text('{"version": 1, "trace": [["a"], ["a", "b"]]}')
    assert load_trace(j) == Word.finite([{"a"}, {"a", "b"}])


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("version: 1\ntrace: [[p1], 3]\n", "trace[1]"),
        ("version: 1\ntrace: [[p1]]\ncycle: []\n", "cycle"),
        ("version: 1\ntrace: [[p1]]\nloop: [[p1]]\n", "loop"),
        ("version: 1\n", "trace"),
        ("version: 1\ntrace: [['a | b']]\n", None),
        ("version: 1\ntrace: ['a | b']\n", "trace[0]"),
    ],
)
def test_trace_file_errors_name_the_field(tmp_path, text: str, field: str | None) -> None:
    p = tmp_path / "bad.yaml"
    p.write_text(text)
    if field is None:  # a list names propositions verbatim: odd names are allowed
        assert load_trace(p).prefix == (frozenset({"a | b"}),)
        return
    with pytest.raises(InputError) as err:
        load_trace(p)
    assert err.value.field is not None and field in err.value.field
    assert err.value.file == str(p)
