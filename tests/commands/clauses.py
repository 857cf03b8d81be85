"""What "an error line says each thing once" means, for the CLI's error lines.

An error line is ``PROG: error: <file>: <field>: <reason>``: clauses separated by ``": "``.
It repeats itself when a clause occurs twice (a wrapper that re-raised with the original
text added) or when a clause is followed by one that starts with it (``formula: formula
'…'``: the field named again by the message).
"""

from __future__ import annotations


def repeated_clause(line: str) -> str | None:
    """The clause ``line`` says twice, or None."""
    clauses = [c.strip() for c in line.split(": ") if c.strip()]
    seen: set[str] = set()
    for k, clause in enumerate(clauses):
        if clause in seen:
            return clause
        seen.add(clause)
        if k + 1 < len(clauses) and clauses[k + 1].startswith(clause + " "):
            return clause
    return None
