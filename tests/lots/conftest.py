"""Shared fixtures: packaged LOTS scenarios and a small runner."""

from __future__ import annotations

import pytest

from tamp.lots.task import load_task

from .helpers import scenario


@pytest.fixture(scope="session")
def example1():
    return load_task(scenario("example1.yaml"))


@pytest.fixture(scope="session")
def tower():
    return load_task(scenario("tower.yaml"))


@pytest.fixture(scope="session")
def model_building():
    return load_task(scenario("model_building.yaml"))
