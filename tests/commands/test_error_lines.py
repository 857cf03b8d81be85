"""CLI error lines say each clause once (the whole suite's lines are checked by the
autouse fixture of tests/conftest.py; here the checker itself and the formula guard)."""

from __future__ import annotations

from tamp.commands.verify import main as verify_main
from tests.commands.clauses import repeated_clause


def test_the_checker_finds_a_field_named_twice_and_a_repeated_reason():
    assert repeated_clause("tamp: error: formula: formula 'G a' is too large") == "formula"
    assert repeated_clause("tamp: error: x.yaml: too large: 3: too large") == "too large"
    assert repeated_clause("tamp: error: x.yaml: steps[2].to: expected 3 numbers") is None


def test_a_formula_refused_by_the_size_guard_is_named_once(capsys):
    formula = "F(" + " & ".join(f"p{i}" for i in range(70)) + ")"  # 70 propositions
    assert verify_main(["trace", "--formula", formula, "--word", "p0; cycle{p1}"]) == 2
    err = capsys.readouterr().err
    assert err.count("is too large to translate") == 1
    assert repeated_clause(err.splitlines()[0]) is None
