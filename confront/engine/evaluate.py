"""Playing an exported policy in the real engine against sample robots (what ``confront evaluate
--engine robocode`` needs), or against another exported policy: either as the standalone PolicyBot (no Python)
or through the bridge."""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from pathlib import Path

from confront.engine.battle import scenario_battle, single_star
from confront.engine.bridged import BRIDGE_BOT, BRIDGE_CPU_CONSTANT_MS, run_bridged_battle
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.runner import EngineOptions, EngineRun, run_battle
from confront.results import BattleResults

MODES = ("export", "bridge")
# Both sides as exported PolicyBots: each its own jar, told apart by the version (a loose robots folder beside a
# jar of the same class would stand in for the jar's robot in team files).
OURS_JAR, THEIRS_JAR = "1.0", "2.0"


def exported_battle(robot: str | Path, scenario: str, opponents: str | Sequence[str], rounds: int,
                    options: EngineOptions) -> EngineRun:
    """The exported PolicyBot (``robot``: the folder or jar ``export_robot`` wrote) for our side of ``scenario``
    against ``opponents``: the engine run (results, turns, round set-up time)."""
    spec = single_star(scenario_battle(scenario, "confront.PolicyBot", opponents, rounds=rounds), "confront.PolicyBot*")
    return run_battle(spec, options, extra_robots=[robot])


def evaluate_policy(
    policy: ExportedPolicy,
    scenario: str,
    opponents: str | Sequence[str],
    rounds: int = 100,
    seed: int = 0,
    mode: str = "export",
    cpu_constant_ms: float | None = None,
    opponent_policy: ExportedPolicy | None = None,
    visible: bool = False,
) -> tuple[BattleResults, float]:
    """Play ``policy`` for our side of ``scenario`` and return (results, our score ratio); with
    ``opponent_policy`` (export mode only) against that policy exported as PolicyBot too (e.g. the TD team).

    ``mode="export"`` plays the compiled PolicyBot (no Python in the loop); ``"bridge"`` lets the Python
    twin pick the move every ``policy.step_turns`` turns through the bridge, with the gun/radar controller run
    by the robot in Java (the exported robot's code) every turn. Both decide identically on identical
    observations. ``cpu_constant_ms`` defaults to ``BRIDGE_CPU_CONSTANT_MS`` (100 ms, fewer skipped turns)
    for the bridge and 10 ms for the export. ``visible``: in Robocode's battle window (``EngineOptions.visible``).
    """
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    if opponent_policy is not None and mode != "export":
        raise ValueError("an opponent policy plays in export mode only")
    cpu = cpu_constant_ms or (BRIDGE_CPU_CONSTANT_MS if mode == "bridge" else 10.0)
    opts = EngineOptions(seed=seed, cpu_constant_ms=cpu, visible=visible)
    name = "confront."  # our robot's name in 1v1 (its contestants: ours and sample robots)
    if mode == "bridge":
        spec = scenario_battle(scenario, BRIDGE_BOT.rstrip("*"), opponents, rounds=rounds)
        spec = single_star(spec, BRIDGE_BOT)
        res = run_bridged_battle(spec, policy, opts, every=policy.step_turns, controller=policy.control).run.results
    elif opponent_policy is not None:
        with tempfile.TemporaryDirectory(prefix="confront-eval-") as tmp:
            robots = [export_robot(policy, Path(tmp) / "ours.jar", version=OURS_JAR),
                      export_robot(opponent_policy, Path(tmp) / "theirs.jar", version=THEIRS_JAR)]
            spec = scenario_battle(scenario, f"confront.PolicyBot {OURS_JAR}", f"confront.PolicyBot {THEIRS_JAR}",
                                   rounds=rounds)
            res = run_battle(spec, opts, extra_robots=robots).results
        name = f"confront.PolicyBot {OURS_JAR}"
    else:
        with tempfile.TemporaryDirectory(prefix="confront-eval-") as tmp:
            res = exported_battle(export_robot(policy, Path(tmp) / "robots"), scenario, opponents, rounds, opts).results
    ours = next(r for r in res.contestants if r.name.startswith((name, "confrontteams.Ours")))
    return res, res.score_ratio(ours.name)
