"""The test-only workcell (`faulty.FAKE`) registered for the campaign tests, and its file."""

from __future__ import annotations

import pytest

from tamp.campaign.kinds import register, unregister
from tests.campaign.faulty import FAKE


@pytest.fixture
def fake_kind():
    register(FAKE)
    yield FAKE
    unregister(FAKE.name)


@pytest.fixture
def fake_file(tmp_path):
    path = tmp_path / "fake.yaml"
    path.write_text("version: 1\ntest_fake: true\n")
    return path
