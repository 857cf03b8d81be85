"""Listing the registered workcells builds nothing: ``tamp --help`` and a campaign's driver
read every cell's declarations without importing Drake."""

from __future__ import annotations

import subprocess
import sys


def test_listing_every_workcell_does_not_import_drake():
    code = (
        "import sys, tamp.sim.core.workcell as w; cells = w.workcells(); "
        "assert set(cells) >= set(w.CELL_PACKAGES), cells; "
        "assert 'pydrake' not in sys.modules, 'pydrake imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
