"""Helpers for the refinement tests: packaged programs, edited copies written to tmp files."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from tamp.refine.loader import load_program, program_to_dict
from tamp.refine.program import Program
from tamp.scenarios import path


def task(n: int) -> Program:
    return load_program(path(f"refine/task{n}.yaml"))


def task_dict(n: int) -> dict[str, Any]:
    return yaml.safe_load(path(f"refine/task{n}.yaml").read_text())


def write(tmp: Path, data: dict[str, Any], name: str = "prog.yaml") -> Path:
    p = tmp / name
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return p


def reload(program: Program, tmp: Path) -> Program:
    """Write ``program`` in the file format and read it back."""
    return load_program(write(tmp, program_to_dict(program), "round.yaml"))
