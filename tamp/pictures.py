"""Pictures from the command line: the format is the file's suffix, the same for every export.

Every graph a command writes (the reachability graph, the grown behavior tree, a Büchi
automaton, a counterexample trace on its automaton, a Drake diagram) is Graphviz DOT text;
`write_graph` writes it as ``.dot`` (the text), ``.svg`` or ``.png`` (rendered by Graphviz
``dot``). Plots drawn with matplotlib (a run's timeline) take ``.svg``, ``.png`` or
``.pdf``. `check_picture` refuses any other suffix *before* the command does its work, as
bad input naming the flag (exit 2), and a missing Graphviz is said the same way with the
``.dot`` alternative.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

from tamp.errors import InputError

#: Suffixes of a graph export, and Graphviz's output format for each (None: the DOT text).
GRAPH_FORMATS: dict[str, str | None] = {".dot": None, ".svg": "svg", ".png": "png"}
#: Suffixes of a matplotlib plot.
PLOT_FORMATS: tuple[str, ...] = (".svg", ".png", ".pdf")


def check_picture(
    path: str | Path, flag: str, formats: Sequence[str] = tuple(GRAPH_FORMATS)
) -> Path:
    """``path`` when its suffix is one of ``formats`` (`InputError` naming ``flag`` else)."""
    out = Path(path)
    suffix = out.suffix.lower()
    if suffix not in formats:
        said = f"suffix {out.suffix!r}" if out.suffix else "no suffix"
        raise InputError(
            f"{out.name}: {said}; the picture's format is its suffix: {', '.join(formats)}",
            field=flag,
        )
    if GRAPH_FORMATS.get(suffix) and ".dot" in formats:
        graphviz(flag)
    return out


def graphviz(flag: str = "") -> str:
    """The path of Graphviz ``dot`` (`InputError` naming ``flag`` when it is missing)."""
    exe = shutil.which("dot")
    if exe is None:
        raise InputError(
            "Graphviz 'dot' is not installed (apt-get install graphviz); "
            "or write the DOT text with a .dot suffix",
            field=flag or None,
        )
    return exe


def render(dot: str, fmt: str, flag: str = "") -> bytes:
    """``dot`` text rendered by Graphviz in format ``fmt`` (``svg``, ``png``)."""
    proc = subprocess.run([graphviz(flag), f"-T{fmt}"], input=dot.encode(), capture_output=True)
    if proc.returncode != 0:
        raise RuntimeError(f"Graphviz dot failed: {proc.stderr.decode(errors='replace')[:300]}")
    return proc.stdout


def write_graph(dot: str, path: str | Path, flag: str) -> Path:
    """Write the DOT text ``dot`` at ``path`` in the format of its suffix (`GRAPH_FORMATS`)."""
    out = check_picture(path, flag)
    fmt = GRAPH_FORMATS[out.suffix.lower()]
    out.parent.mkdir(parents=True, exist_ok=True)
    if fmt is None:
        out.write_text(dot)
    else:
        out.write_bytes(render(dot, fmt, flag))
    return out
