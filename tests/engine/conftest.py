"""Shared fixtures for engine tests: skip cleanly when the Robocode engine is not installed."""

from __future__ import annotations

import pytest

from confront.engine.install import EngineInstall, EngineNotFoundError, find_engine


@pytest.fixture(scope="session")
def install() -> EngineInstall:
    """The installed engine, or skip with the reason and the install command."""
    try:
        return find_engine()
    except EngineNotFoundError as err:
        pytest.skip(f"Robocode engine not installed: {err}")
