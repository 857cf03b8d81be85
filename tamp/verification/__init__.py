"""Verification of plans against LTL, on Spot: traces, RG orders and graphs, BTs, LOTS tables.

Every plan is checked against its LTL automaton before it is executed or simulated. `gate`
is what the planner front ends call; `check_trace` checks one finite
(LTLf) or lasso trace; `VerificationError` (exit 1) carries the counterexample.
Depends on the data types of the planning layers, never on `tamp.sim` or Drake.
"""

from tamp.verification.gate import gate
from tamp.verification.traces import check_trace
from tamp.verification.verdict import Counterexample, Report, Verdict, VerificationError
from tamp.verification.words import Word, load_trace, parse_word

__all__ = [
    "Counterexample",
    "Report",
    "Verdict",
    "VerificationError",
    "Word",
    "check_trace",
    "gate",
    "load_trace",
    "parse_word",
]
