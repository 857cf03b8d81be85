"""The only place that talks to Spot: formulas, translation (cached, guarded), letters, lassos.

- ``formula``    parsing (one parser; syntax errors are `InputError`), propositions, conjuncts
- ``translate``  LTL/LTLf → state-based Büchi automaton / NFA: options, cache, size and time guard
- ``letters``    letters as BDDs and as Spot word text, lasso word automata
- ``automata``   edges, copies started elsewhere, lasso acceptance, live states, a letter stepper
- ``kripke``     Kripke structures of explicit systems and their runs accepted by an automaton

Every other module of ``tamp`` (``tamp.verification`` too) reaches Spot through these.
"""

from tamp.ltl.automata import accepts_lasso, started_at
from tamp.ltl.formula import Formula, ap_names, as_formula, conjuncts, negate, parse
from tamp.ltl.letters import EMPTY, Letter
from tamp.ltl.translate import (
    BUCHI,
    FINITE,
    LIMITS,
    NEGATION,
    Limits,
    Options,
    cache_info,
    clear_cache,
    translate,
)

__all__ = [
    "BUCHI",
    "EMPTY",
    "FINITE",
    "LIMITS",
    "NEGATION",
    "Formula",
    "Letter",
    "Limits",
    "Options",
    "accepts_lasso",
    "ap_names",
    "as_formula",
    "cache_info",
    "clear_cache",
    "conjuncts",
    "negate",
    "parse",
    "started_at",
    "translate",
]
