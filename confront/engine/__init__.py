"""The real Robocode engine (Debian ``robocode`` 1.9.3.9): discovery, battles, results, traces, bridge."""

from confront.engine.battle import BattleSpec, Team, scenario_battle
from confront.engine.install import EngineInstall, EngineNotFoundError, engine_available, find_engine
from confront.engine.runner import EngineOptions, EngineRun, run_battle
from confront.results import BattleResults, ScoreRow, parse_results_text

__all__ = [
    "BattleResults", "BattleSpec", "EngineInstall", "EngineNotFoundError", "EngineOptions", "EngineRun",
    "ScoreRow", "Team", "engine_available", "find_engine", "parse_results_text", "run_battle",
    "scenario_battle",
]
