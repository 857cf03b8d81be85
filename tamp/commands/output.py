"""Helpers shared by subcommands: JSON printing and progress on stderr."""

from __future__ import annotations

import json
import sys
from typing import Any


def print_json(payload: Any) -> None:
    """Print a JSON document on stdout (what ``--json`` promises)."""
    json.dump(payload, sys.stdout, indent=2, default=_default)
    sys.stdout.write("\n")


def _default(obj: Any) -> Any:
    if hasattr(obj, "tolist"):
        return obj.tolist()
    if isinstance(obj, set | frozenset):
        return sorted(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def progress(message: str, *, quiet: bool = False) -> None:
    """A progress line on stderr, so stdout stays clean for --json."""
    if not quiet:
        print(message, file=sys.stderr, flush=True)
