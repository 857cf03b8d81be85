"""The test-only kind (`faulty.FAKE`) registered for the campaign tests, and its file."""

from __future__ import annotations

import pytest

from tamp.campaign.kinds import KINDS, register
from tests.campaign.faulty import FAKE


@pytest.fixture
def fake_kind():
    register(FAKE)
    yield FAKE
    KINDS.pop(FAKE.name, None)


@pytest.fixture
def fake_file(tmp_path):
    path = tmp_path / "fake.yaml"
    path.write_text("version: 1\ntest_fake: true\n")
    return path
