"""Shared fixtures for engine tests: skip cleanly when the Robocode engine is not installed."""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from collections.abc import Iterator

import pytest

from confront.engine.install import EngineInstall, EngineNotFoundError, find_engine


@pytest.fixture(scope="session")
def install() -> EngineInstall:
    """The installed engine, or skip with the reason and the install command."""
    try:
        return find_engine()
    except EngineNotFoundError as err:
        pytest.skip(f"Robocode engine not installed: {err}")


@pytest.fixture
def display() -> Iterator[str]:
    """A virtual X display (Xvfb) for the test, or skip when Xvfb is not installed."""
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        pytest.skip("Xvfb not installed (apt-get install xvfb)")
    for n in range(90, 120):
        if os.path.exists(f"/tmp/.X11-unix/X{n}") or os.path.exists(f"/tmp/.X{n}-lock"):
            continue
        proc = subprocess.Popen([xvfb, f":{n}", "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for _ in range(50):
            if os.path.exists(f"/tmp/.X11-unix/X{n}"):
                break
            time.sleep(0.1)
        if proc.poll() is None:
            try:
                yield f":{n}"
            finally:
                proc.terminate()
                proc.wait(10)
            return
    pytest.skip("no free X display number for Xvfb")
