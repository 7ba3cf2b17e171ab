"""Robocode's sample team (sampleteam.MyFirstTeam: a leader and droids) as an opponent: the seeded engine battle and
the simulator's play the same rounds."""

from __future__ import annotations

import pytest

from confront.engine.install import EngineInstall
from confront.engine.runner import run_scenario
from confront.experiments.evaluate import sim_bot_battle


def _numbers(markdown: str) -> list[list[str]]:
    """The score table's rows without the rank and the name."""
    return [[c.strip() for c in row.split("|")[3:-1]] for row in markdown.splitlines()
            if row.startswith("| ") and row[2].isdigit()]


@pytest.mark.parametrize("seed", [1, 2])
def test_myfirstteam_battle_is_the_engines(install: EngineInstall, seed: int) -> None:
    # generous CPU time: at the default 10 ms a robot that skips a turn under load plays another battle
    run = run_scenario("4v4", "SpinBot", "MyFirstTeam", rounds=3, seed=seed, cpu_constant_ms=100.0)
    assert run.skipped_turns == {}
    sim = sim_bot_battle("4v4", ["SpinBot", "MyFirstTeam"], 3, seed)
    engine_rows = _numbers(run.results.to_markdown())
    assert "confrontteams.MyFirstTeam4" in run.results.to_markdown()
    assert len(engine_rows) == 2 and all(float(r[0]) > 0 for r in engine_rows)  # both teams scored
    assert engine_rows == _numbers(sim.to_markdown())  # every score part, firsts, seconds and thirds
