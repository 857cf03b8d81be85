"""Execute the notebooks in place and save them with their outputs.

    python notebooks/execute.py [NOTEBOOK.ipynb ...]   # default: every notebooks/*.ipynb

Each notebook runs top to bottom as ``tests/test_notebooks.py`` runs it (kernel ``python3``,
working directory ``notebooks/``, ``TAMP_NOTEBOOK_OUT`` set to a fresh temporary folder), and
is written back with its outputs so that a reader sees the results without running it. The
saved file is kept small and its diffs quiet (`clean`), and a stream output longer than
``MAX_STREAM_LINES`` lines keeps its head and tail. A cell error stops the run with the
notebook left unchanged on disk.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
import time
from pathlib import Path

import nbclient
import nbformat

HERE = Path(__file__).resolve().parent
MAX_STREAM_LINES = 80
# Drake logs the address of each Meshcat server it starts: a port that changes every run and
# points at a server that is gone once the kernel exits.
NOISE = re.compile(r"^INFO:drake:Meshcat listening for connections at .*\n?", re.MULTILINE)


def _truncate(text: str, limit: int = MAX_STREAM_LINES) -> str:
    """Keep the first and last lines of a long stream, naming how many were cut."""
    lines = text.splitlines(keepends=True)
    if len(lines) <= limit:
        return text
    head, tail = lines[: limit // 2], lines[-limit // 4 :]
    cut = len(lines) - len(head) - len(tail)
    return "".join([*head, f"... ({cut} lines cut from the saved output)\n", *tail])


def clean(nb: nbformat.NotebookNode, out_dir: str) -> nbformat.NotebookNode:
    """Drop what changes from run to run or machine to machine without changing the result.

    Timing metadata and Meshcat server addresses go; the run's temporary output folder is
    written ``$TAMP_NOTEBOOK_OUT`` and paths inside the repository relative to its root.
    """
    for cell in nb.cells:
        cell.metadata.pop("execution", None)
        if cell.cell_type != "code":
            continue
        for out in cell.outputs:
            if out.output_type == "stream":
                text = NOISE.sub("", out.text).lstrip("\n")
                text = text.replace(out_dir, "$TAMP_NOTEBOOK_OUT").replace(f"{HERE.parent}/", "")
                out.text = _truncate(text)
        cell.outputs = [o for o in cell.outputs if o.output_type != "stream" or o.text]
    return nb


def execute(path: Path, timeout: int = 1800) -> nbformat.NotebookNode:
    """Run one notebook as the test suite does and return it with its outputs."""
    nb = nbformat.read(path, as_version=4)
    env_before = dict(os.environ)
    with tempfile.TemporaryDirectory(prefix=f"nb_{path.stem}_") as out_dir:
        os.environ["TAMP_NOTEBOOK_OUT"] = out_dir
        os.environ.pop("MPLBACKEND", None)  # the kernel's inline backend draws the figures
        os.environ["PYTHONHASHSEED"] = "0"  # set orders printed the same way on every run
        try:
            nbclient.NotebookClient(
                nb,
                timeout=timeout,
                kernel_name="python3",
                record_timing=False,
                coalesce_streams=True,  # one stream output per cell, however it was flushed
                resources={"metadata": {"path": str(path.parent)}},
            ).execute()
        finally:
            os.environ.clear()
            os.environ.update(env_before)
    return clean(nb, out_dir)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebooks", nargs="*", type=Path, help="default: notebooks/*.ipynb")
    parser.add_argument("--timeout", type=int, default=1800, help="seconds per cell")
    args = parser.parse_args(argv)
    paths = args.notebooks or sorted(HERE.glob("*.ipynb"))
    for path in paths:
        if not path.is_file():
            print(f"{path}: not a file", file=sys.stderr)
            return 2
    for path in paths:
        wall = time.perf_counter()
        try:
            nb = execute(path.resolve(), args.timeout)
        except nbclient.exceptions.CellExecutionError as err:
            print(f"{path}: a cell failed, file left unchanged\n{err}", file=sys.stderr)
            return 1
        nbformat.write(nb, path)
        print(
            f"{path.name}: {path.stat().st_size / 1e3:.0f} kB, "
            f"wall {time.perf_counter() - wall:.0f} s",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
