"""LTL formulas: parsing (one parser for every layer), propositions, conjuncts.

A syntax error is bad input (`InputError`, exit 2) naming the file and field. Comparisons
``name OP integer`` (e.g. ``holding_count <= 1``) are not LTL syntax; they become one quoted
proposition (``"holding_count<=1"``) whose truth the labelling of a system computes, so
properties over counters read naturally.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import TypeAlias

import spot
import spot.impl

from tamp.errors import InputError

#: Spot's formula type (the only name other layers need for annotations and isinstance).
#: Spot defines it in ``spot.impl`` and extends it in ``spot`` under the same name
#: (``spot.formula is spot.impl.formula``); a type checker sees its methods on the former.
Formula: TypeAlias = spot.impl.formula

_COMPARISON = re.compile(r"(?<![\"\w])([A-Za-z_][\w.]*)\s*(<=|>=|==|!=|<|>)\s*(-?\d+)(?![\w\"])")
#: A proposition made from a comparison: ``holding_count<=1`` -> (name, operator, integer).
COMPARISON_AP = re.compile(r"^([A-Za-z_][\w.]*)(<=|>=|==|!=|<|>)(-?\d+)$")

#: Operators whose automaton needs memory: what the size guard counts.
_TEMPORAL = frozenset({"X", "strong_X", "F", "G", "U", "R", "W", "M", "EConcat", "UConcat"})


def _quote_comparisons(text: str) -> str:
    return _COMPARISON.sub(lambda m: f'"{m.group(1)}{m.group(2)}{m.group(3)}"', text)


def parse(text: str, *, field: str = "formula", file: str | None = None) -> Formula:
    """Parse an LTL formula in Spot's syntax; a syntax error is an `InputError` (exit 2)."""
    if not isinstance(text, str) or not text.strip():
        raise InputError("empty formula", file=file, field=field)
    try:
        return Formula(_quote_comparisons(text))
    except SyntaxError as exc:
        lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
        reason = next((ln for ln in lines if not ln.startswith((">>>", "^"))), "syntax error")
        raise InputError(f"{text!r} does not parse: {reason}", file=file, field=field) from None


def as_formula(f: str | Formula, *, field: str = "formula") -> Formula:
    """``f`` itself when it is already a formula, else `parse` of the text."""
    return f if isinstance(f, Formula) else parse(f, field=field)


def ap_names(f: Formula) -> list[str]:
    """The atomic propositions of ``f``, as plain names, sorted."""
    return sorted(ap.ap_name() for ap in spot.atomic_prop_collect(f))


def check_aps(f: Formula, declared: Iterable[str], *, file: str | None = None) -> None:
    """`InputError` on field ``formula`` when ``f`` names a proposition not in ``declared``."""
    declared = list(declared)
    unknown = sorted(set(ap_names(f)) - set(declared))
    if unknown:
        raise InputError(
            f"unknown proposition(s) {unknown} (declared: {declared})", file=file, field="formula"
        )


def conjuncts(f: Formula) -> list[Formula]:
    """Top-level conjuncts of ``f`` (``[f]`` when ``f`` is not a conjunction)."""
    if f.kind() == spot.op_And:
        return [f[i] for i in range(f.size())]
    return [f]


def negate(f: Formula) -> Formula:
    """``!f``."""
    return Formula.Not(f)


def atom(name: str) -> str:
    """A proposition as formula text (quoted when it is not a plain identifier)."""
    return str(Formula.ap(name))


def temporal_conjuncts(f: Formula) -> int:
    """Top-level conjuncts of ``f`` that contain a temporal operator.

    The automaton of a conjunction of k such formulas can need 2^k states (or k-fold
    degeneralisation with expensive simplifications): what the size guard limits.
    """
    return sum(1 for c in conjuncts(f) if temporal_operators(c) > 0)


def temporal_operators(f: Formula) -> int:
    """Number of temporal operators in ``f`` (each occurrence counted)."""
    count = 0

    def visit(g: Formula) -> bool:
        nonlocal count
        if g.kindstr() in _TEMPORAL:
            count += 1
        return False

    f.traverse(visit)  # pyright: ignore[reportAttributeAccessIssue]  (added by spot.formula)
    return count


def short(text: str, n: int = 60) -> str:
    """The first ``n`` characters of a formula's text (for error messages)."""
    text = " ".join(text.split())
    return text if len(text) <= n else text[: n - 1] + "…"
