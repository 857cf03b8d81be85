"""The `tamp` command: one subcommand per layer, each defined in `tamp/commands/<name>.py`.

Every subcommand module exposes ``register(subparsers)`` that adds its parser and sets
``func(args) -> int``. Heavy imports (Drake, torch, Spot) happen inside ``func`` so that
``tamp --help`` stays fast. Errors become one line on stderr and an exit status:
0 success, 1 infeasible task or failed check, 2 bad input, 3 internal error.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import traceback
from collections.abc import Callable, Sequence

from tamp.errors import EXIT_BAD_INPUT, TampError

EXIT_INTERNAL = 3

#: Subcommand modules under tamp.commands, in the order `tamp --help` lists them.
COMMANDS = ("plan", "lots", "refine", "simulate", "grasp")


def build_parser(prog: str, modules: Sequence[str], package: str) -> argparse.ArgumentParser:
    """Parser with one subcommand per module that exists in ``package``."""
    parser = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in modules:
        try:
            module = importlib.import_module(f"{package}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"{package}.{name}":
                continue  # layer not built yet
            raise
        module.register(sub)
    return parser


def run(
    argv: Sequence[str] | None,
    make_parser: Callable[[], argparse.ArgumentParser],
) -> int:
    """Parse, dispatch, and turn every error into one line plus the right exit status."""
    parser = make_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: usage errors are bad input
        code = exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
        return EXIT_BAD_INPUT if code not in (0,) else 0
    try:
        return int(args.func(args) or 0)
    except TampError as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print(f"{parser.prog}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:  # never a bare traceback
        if os.environ.get("TAMP_DEBUG"):
            traceback.print_exc()
        print(
            f"{parser.prog}: internal error: {type(exc).__name__}: {exc} "
            "(set TAMP_DEBUG=1 for the traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


def main(argv: Sequence[str] | None = None) -> int:
    return run(argv, lambda: build_parser("tamp", COMMANDS, "tamp.commands"))


if __name__ == "__main__":
    sys.exit(main())
