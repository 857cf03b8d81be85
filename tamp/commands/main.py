"""The `tamp` command: one subcommand per layer, each defined in `tamp/commands/<name>.py`.

Every subcommand module exposes ``register(subparsers)`` that adds its parser and sets
``func(args) -> int``. Heavy imports (Drake, torch, Spot) happen inside ``func`` so that
``tamp --help`` stays fast. Errors become one line on stderr and an exit status:
0 success, 1 infeasible task or failed check, 2 bad input (or an optional extra the command
needs is not installed: the message names it, `tamp.extras`), 3 internal error. Under
``--json`` an error is also one JSON document on stdout:
``{"schema": 1, "error": ..., "exit": 2, "file": ..., "field": ...}``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import logging
import os
import sys
import traceback
from collections.abc import Callable, Sequence
from importlib.metadata import PackageNotFoundError, version

from tamp.errors import EXIT_BAD_INPUT, TampError
from tamp.extras import DISTRIBUTION, from_import_error

EXIT_INTERNAL = 3

#: Subcommand modules under tamp.commands, in the order `tamp --help` lists them.
COMMANDS = (
    "plan",
    "lots",
    "simulate",
    "refine",
    "grasp",
    "detect",
    "campaign",
    "serve",
    "schema",
    "scenarios",
    "completion",
)


def package_version() -> str:
    """The installed distribution's version (the source tree's when not installed)."""
    try:
        return version(DISTRIBUTION)
    except PackageNotFoundError:  # pragma: no cover - running from an uninstalled tree
        return "unknown"


def add_version(parser: argparse.ArgumentParser) -> None:
    """``--version``: print ``PROG VERSION`` and exit 0."""
    parser.add_argument("--version", action="version", version=f"%(prog)s {package_version()}")


def build_parser(prog: str, modules: Sequence[str], package: str) -> argparse.ArgumentParser:
    """Parser with one subcommand per module of ``package``."""
    parser = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    add_version(parser)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in modules:
        importlib.import_module(f"{package}.{name}").register(sub)
    return parser


def configure_logging(prog: str) -> None:
    """Diagnostics go through `logging` to stderr as ``PROG: message``; ``TAMP_LOG`` sets
    the level (default INFO; DEBUG shows the progress lines that ``--json`` quiets)."""
    logger = logging.getLogger("tamp")
    if not any(getattr(h, "_tamp", False) for h in logger.handlers):
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter(f"{prog}: %(message)s"))
        handler._tamp = True  # type: ignore[attr-defined]
        logger.addHandler(handler)
    # said once: not again by a root handler (Drake's Meshcat configures one when it starts)
    logger.propagate = False
    level = os.environ.get("TAMP_LOG", "INFO").upper()
    if level not in logging.getLevelNamesMapping():
        logger.setLevel(logging.INFO)
        logger.warning("TAMP_LOG=%s is not a logging level; using INFO", level[:20])
    else:
        logger.setLevel(level)


def error_line(prog: str, exc: TampError) -> str:
    """What the user reads for a handled error: ``PROG: error: <where>: <reason>``, said once.

    The exception's text already names its file and field (`tamp.errors.InputError`), so
    nothing is added but the program's name; messages name the value, not the field again
    (``formula: 'GF p1 & …' is too large``, never ``formula: formula '…'``).
    """
    return f"{prog}: error: {exc}"


def _error_json(message: str, code: int, exc: BaseException | None = None) -> None:
    """The ``--json`` form of an error: one document on stdout, beside the stderr line."""
    from tamp.fileio import JSON_SCHEMA

    doc = {
        "schema": JSON_SCHEMA,
        "error": message,
        "exit": code,
        "file": getattr(exc, "file", None),
        "field": getattr(exc, "field", None),
    }
    sys.stdout.write(json.dumps(doc, indent=2) + "\n")


def run(
    argv: Sequence[str] | None,
    make_parser: Callable[[], argparse.ArgumentParser],
) -> int:
    """Parse, dispatch, and turn every error into one line plus the right exit status."""
    parser = make_parser()
    configure_logging(parser.prog)
    argv = list(sys.argv[1:] if argv is None else argv)
    as_json = "--json" in argv
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: usage errors are bad input (it printed the usage)
        if exc.code in (0, None):
            return 0
        if as_json:
            _error_json("bad command-line arguments (see the usage on stderr)", EXIT_BAD_INPUT)
        return EXIT_BAD_INPUT
    as_json = bool(getattr(args, "json", False))
    try:
        return int(args.func(args) or 0)
    except TampError as exc:
        print(error_line(parser.prog, exc), file=sys.stderr)
        if as_json:
            _error_json(str(exc), exc.exit_code, exc)
        return exc.exit_code
    except ModuleNotFoundError as exc:  # an optional extra that is not installed
        missing = from_import_error(exc, f"{parser.prog} {getattr(args, 'command', '')}".strip())
        if missing is None:
            return _internal(parser.prog, exc, as_json)
        print(error_line(parser.prog, missing), file=sys.stderr)
        if as_json:
            _error_json(str(missing), missing.exit_code, missing)
        return missing.exit_code
    except KeyboardInterrupt:
        print(f"{parser.prog}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:  # never a bare traceback
        return _internal(parser.prog, exc, as_json)


def _internal(prog: str, exc: BaseException, as_json: bool) -> int:
    """An unexpected error: one line (the traceback with ``TAMP_DEBUG=1``), exit 3."""
    if os.environ.get("TAMP_DEBUG"):
        traceback.print_exception(exc)
    message = f"internal error: {type(exc).__name__}: {exc}"
    print(f"{prog}: {message} (set TAMP_DEBUG=1 for the traceback)", file=sys.stderr)
    if as_json:
        _error_json(message, EXIT_INTERNAL, exc)
    return EXIT_INTERNAL


def main(argv: Sequence[str] | None = None) -> int:
    return run(argv, lambda: build_parser("tamp", COMMANDS, "tamp.commands"))


if __name__ == "__main__":
    sys.exit(main())
