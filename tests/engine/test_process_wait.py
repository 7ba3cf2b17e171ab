"""Waiting for an engine process: the exit code as soon as it exits, a time-out as subprocess raises it."""

from __future__ import annotations

import subprocess
import sys

import pytest

from confront.engine.runner import wait_exit


def test_the_exit_code_of_a_process() -> None:
    proc = subprocess.Popen([sys.executable, "-c", "import sys; sys.exit(3)"])
    assert wait_exit(proc, 60) == 3


def test_a_process_that_has_exited_already() -> None:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    assert wait_exit(proc, 60) == 0


def test_a_process_that_runs_too_long() -> None:
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        with pytest.raises(subprocess.TimeoutExpired):
            wait_exit(proc, 0.2)
        assert proc.poll() is None  # still running: the caller kills it
    finally:
        proc.kill()
        proc.wait()
