"""Helpers shared by subcommands: JSON printing (every document carries ``"schema": 1``),
progress on stderr, output-file checks, and the ``--no-verify`` flag with its warning line."""

from __future__ import annotations

import json
import logging
import os
import sys
from pathlib import Path
from typing import Any

from tamp.errors import InputError
from tamp.fileio import with_schema


def print_json(payload: Any) -> None:
    """Print a JSON document on stdout (what ``--json`` promises), with its ``"schema"``."""
    json.dump(with_schema(payload), sys.stdout, indent=2, default=_default)
    sys.stdout.write("\n")


def _default(obj: Any) -> Any:
    if hasattr(obj, "tolist"):
        return obj.tolist()
    if isinstance(obj, set | frozenset):
        return sorted(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def progress(message: str, *, quiet: bool = False) -> None:
    """A progress line on stderr (through `logging`, logger ``tamp``), so stdout stays clean
    for --json; ``quiet`` lowers it to DEBUG."""
    logging.getLogger("tamp").log(logging.DEBUG if quiet else logging.INFO, message)


def add_no_verify(parser) -> None:
    """``--no-verify``: skip the verification gate (a warning line says so on stderr)."""
    parser.add_argument(
        "--no-verify",
        action="store_true",
        help="skip the verification gate (not recommended: an unverified plan runs)",
    )


def warn_unverified(prog: str, what: str) -> None:
    """The warning line every command prints when ``--no-verify`` skips the gate."""
    print(
        f"{prog}: warning: --no-verify: {what} runs without passing the verification gate",
        file=sys.stderr,
        flush=True,
    )


def output_file(path: str | Path, option: str, *, make_parents: bool = False) -> Path:
    """Check that ``path`` can be written *before* any work is done; returns it as a Path.

    A directory, a missing parent directory (unless ``make_parents``) or a parent that cannot
    be written is bad input (`InputError` naming ``option``, exit 2), not an internal error
    after a long run.
    """
    out = Path(path)
    if out.is_dir():
        raise InputError(f"{out} is a directory, expected a file name", field=option)
    parent = out.parent
    if make_parents:
        existing = next((p for p in (parent, *parent.parents) if p.exists()), Path("."))
        if not existing.is_dir():
            raise InputError(f"{existing} is not a directory", field=option)
        parent = existing
    elif not parent.is_dir():
        raise InputError(f"directory {parent} does not exist", field=option)
    if not os.access(parent, os.W_OK):
        raise InputError(f"directory {parent} is not writable", field=option)
    return out


def output_dir(path: str | Path, option: str) -> Path:
    """The folder an ``--out`` option names, checked *before* any work (`output_file`): a file
    in its place, or a parent that cannot be written, is bad input naming ``option`` (exit 2).
    Nothing is created here (the command makes the folder when it writes, so a refused run
    leaves nothing behind). ``--out`` is a folder for every command."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out} is a file, expected a folder", field=option)
    output_file(out / "probe", option, make_parents=True)
    return out
