"""Fixture datasets for the grasp tests (see tests/grasp/data.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.grasp.data import write_cornell_set, write_jacquard_set


@pytest.fixture
def jacquard_dir(tmp_path: Path) -> Path:
    return write_jacquard_set(tmp_path / "jacquard")


@pytest.fixture
def cornell_dir(tmp_path: Path) -> Path:
    return write_cornell_set(tmp_path / "cornell")
