"""The notebooks under notebooks/: committed with their outputs, and still executed.

The fast tests read the committed files: every code cell was executed, in order, in one run
(``python notebooks/execute.py`` writes them so), none ended in an error, every notebook that
draws carries its pictures, and each file stays small enough to review and to render on a
repository page. The slow test executes every notebook top to bottom; a cell error fails it.
"""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parent.parent / "notebooks").glob("*.ipynb"))
MAX_BYTES = 1_500_000  # a notebook with its outputs, recordings left out
IMAGE_TYPES = ("image/png", "image/jpeg", "image/svg+xml")
DRAWS = re.compile(r"plt\.show\(\)|display\((Image\(|SVG\(|fig\))")


def _code_cells(path: Path) -> list[dict]:
    return [c for c in json.loads(path.read_text())["cells"] if c["cell_type"] == "code"]


def test_there_are_notebooks() -> None:
    assert len(NOTEBOOKS) >= 5, NOTEBOOKS


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_is_committed_executed(path: Path) -> None:
    cells = _code_cells(path)
    counts = [c["execution_count"] for c in cells]
    assert counts == list(range(1, len(cells) + 1)), (
        f"{path.name}: not executed top to bottom in one run (execution counts {counts}); "
        "run python notebooks/execute.py"
    )
    errors = [o for c in cells for o in c["outputs"] if o["output_type"] == "error"]
    assert not errors, f"{path.name}: saved with an error output"
    assert path.stat().st_size < MAX_BYTES, f"{path.name}: {path.stat().st_size} bytes"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_drawing_cells_carry_their_pictures(path: Path) -> None:
    for k, cell in enumerate(_code_cells(path)):
        if not DRAWS.search("".join(cell["source"])):
            continue
        kinds = {t for o in cell["outputs"] for t in o.get("data", {})}
        assert kinds & set(IMAGE_TYPES), f"{path.name}: code cell {k} draws but saved no image"


def _executor():
    """``notebooks/execute.py``, the one way the notebooks are run (saved or tested)."""
    pytest.importorskip("nbclient")
    path = NOTEBOOKS[0].parent / "execute.py"
    spec = importlib.util.spec_from_file_location("notebooks_execute", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow  # executes every notebook
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path: Path, monkeypatch) -> None:
    # the campaign notebook's committed outputs are its 20 seeds (`make notebooks`); the
    # suite checks that it runs, on 4
    monkeypatch.setenv("TAMP_NOTEBOOK_RUNS", "4")
    nb = _executor().execute(path, timeout=600)  # raises on a cell error
    assert all(c.execution_count for c in nb.cells if c.cell_type == "code")
