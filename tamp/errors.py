"""Error types shared by every layer, and the exit codes the CLI maps them to.

Bad input (a file that does not load, an impossible value) is an `InputError` (exit 2);
a well-formed task that cannot be achieved is an `InfeasibleError` (exit 1). Both carry
enough context (file, field) for one clear line of output.
"""

from __future__ import annotations

import reprlib

EXIT_OK = 0
EXIT_INFEASIBLE = 1
EXIT_BAD_INPUT = 2
#: tamp-verify only: a bounded check found no violation but could not establish the property
EXIT_UNKNOWN = 4


def short_repr(value: object, limit: int = 60) -> str:
    """A quoted prefix of ``value`` for error messages: never a huge input line whole.

    Bounded work too: `reprlib` stops at a few levels and items, so a YAML alias bomb
    (shared sub-lists, exponential when printed in full) costs nothing here.
    """
    r = reprlib.Repr()
    r.maxlevel, r.maxlist, r.maxtuple, r.maxdict, r.maxset = 3, 6, 6, 6, 6
    r.maxstring = r.maxother = r.maxlong = limit
    text = r.repr(value)
    return text if len(text) <= limit else f"{text[: limit - 3]}..."


class TampError(Exception):
    """Base class of the errors the CLI turns into one line and an exit status."""

    exit_code = EXIT_INFEASIBLE


class InputError(TampError, ValueError):
    """Bad input: names the file and the field (dotted path) that is wrong."""

    exit_code = EXIT_BAD_INPUT

    def __init__(self, message: str, *, file: str | None = None, field: str | None = None):
        self.file = file
        self.field = field
        self.reason = message
        where = ""
        if file and field:
            where = f"{file}: {field}: "
        elif file:
            where = f"{file}: "
        elif field:
            where = f"{field}: "
        super().__init__(f"{where}{message}")


class InfeasibleError(TampError):
    """A well-formed task that no plan achieves (exit 1), with the reason."""

    exit_code = EXIT_INFEASIBLE
