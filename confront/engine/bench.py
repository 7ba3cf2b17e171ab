"""Throughput of the real engine with sample robots, for the simulator benchmark to compare against."""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from confront.engine.battle import scenario_battle
from confront.engine.runner import EngineOptions, run_battle

DEFAULT_OURS: tuple[str, ...] = ("SpinBot", "Walls", "Tracker", "RamFire")
DEFAULT_OPPONENTS: tuple[str, ...] = ("Walls", "Tracker", "Crazy", "Fire", "SpinBot")


def engine_throughput(
    scenario_name: str,
    rounds: int = 10,
    ours: Sequence[str] = DEFAULT_OURS,
    opponents: Sequence[str] = DEFAULT_OPPONENTS,
    seed: int = 1,
    cpu_constant_ms: float = 2.7,
) -> dict[str, Any]:
    """Play ``rounds`` rounds of a scenario with sample robots headless and measure the engine's speed.

    ``turns_per_s`` and ``robot_turns_per_s`` are over the battle inside the JVM (all turns, including the
    150 after each round and the engine's wait at each round start); the ``*_excl_setup`` figures leave out
    the time before each round's first turn; ``wall_s`` is the whole process (JVM start included).
    cpu_constant_ms 2.7 is what the engine measured for itself on our 2-core machine.
    """
    spec = scenario_battle(scenario_name, list(ours), list(opponents), rounds=rounds)
    t0 = time.perf_counter()
    run = run_battle(spec, EngineOptions(seed=seed, cpu_constant_ms=cpu_constant_ms))
    wall = time.perf_counter() - t0
    busy = max(run.elapsed_s - run.setup_s, 1e-9)
    return {
        "scenario": scenario_name,
        "batch": 1,
        "engine": "robocode",
        "turns_per_s": run.turns / run.elapsed_s,
        "robot_turns_per_s": run.robot_turns / run.elapsed_s,
        "turns_per_s_excl_setup": run.turns / busy,
        "robot_turns_per_s_excl_setup": run.robot_turns / busy,
        "turns": run.turns,
        "robot_turns": run.robot_turns,
        "rounds": rounds,
        "robots": spec.robot_count,
        "elapsed_s": run.elapsed_s,
        "setup_s": run.setup_s,
        "wall_s": wall,
        "skipped_turns": sum(run.skipped_turns.values()),
        "cpu_constant_ms": cpu_constant_ms,
    }
