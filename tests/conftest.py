"""Test-wide settings: no network for Drake models, headless plotting, hypothesis profile."""

import os

os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")
os.environ.setdefault("MPLBACKEND", "Agg")

import pytest  # noqa: E402
from hypothesis import HealthCheck, settings  # noqa: E402

settings.register_profile(
    "ci", deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
settings.register_profile("dev", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("ci" if os.environ.get("CI") else "dev")


@pytest.fixture(autouse=True)
def _cli_error_lines_say_each_clause_once(monkeypatch):
    """Every CLI error line a test provokes (the hostile-input tests) has no repeated clause."""
    from tamp.commands import main as cli
    from tests.commands.clauses import repeated_clause

    lines: list[str] = []
    original = cli.error_line

    def record(prog, exc):
        line = original(prog, exc)
        lines.append(line)
        return line

    monkeypatch.setattr(cli, "error_line", record)
    yield
    for line in lines:
        first = line.splitlines()[0] if line else line
        assert repeated_clause(first) is None, f"error line repeats a clause: {first}"
