"""Error types shared by every layer, and the exit codes the CLI maps them to.

Bad input (a file that does not load, an impossible value) is an `InputError` (exit 2);
a well-formed task that cannot be achieved is an `InfeasibleError` (exit 1). Both carry
enough context (file, field) for one clear line of output.
"""

from __future__ import annotations

EXIT_OK = 0
EXIT_INFEASIBLE = 1
EXIT_BAD_INPUT = 2


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
