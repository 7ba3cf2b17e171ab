"""The engine's round-start wait (a lost wake-up in RobotPeer.startRound) removed by RoundStartAgent."""

from __future__ import annotations

import pytest

from confront.engine.battle import BattleSpec
from confront.engine.install import EngineInstall
from confront.engine.runner import EngineOptions, run_battle

pytestmark = pytest.mark.engine


def test_agent_removes_round_start_wait_and_keeps_the_battle(install: EngineInstall) -> None:
    spec = BattleSpec(("SpinBot", "Walls", "Tracker", "RamFire"), rounds=6)
    fixed = run_battle(spec, EngineOptions(seed=1, cpu_constant_ms=10.0), install=install)
    plain = run_battle(spec, EngineOptions(seed=1, cpu_constant_ms=10.0, round_start_fix=False), install=install)
    # the plain engine loses a wake-up by chance (then 300 x 10 ms); with the agent never a full time-out
    assert fixed.setup_s < 1.5
    assert fixed.round_turns == plain.round_turns
    assert [r.total for r in fixed.results.robots] == [r.total for r in plain.results.robots]
