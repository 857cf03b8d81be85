"""Old names of the LTL helpers, kept only for `verification.bt` (re-point it at `tamp.ltl`).

Everything Spot-related lives in `tamp.ltl`; remove this module once ``verification/bt.py``
imports `tamp.ltl.formula` directly (``COMPARISON_AP``, ``parse`` and ``ap_names``).
"""

from tamp.ltl.formula import COMPARISON_AP, ap_names
from tamp.ltl.formula import parse as parse_formula

__all__ = ["COMPARISON_AP", "ap_names", "parse_formula"]
