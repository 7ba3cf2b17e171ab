"""What the tank's skills (confront.arena.tank: the technique brain, surf, the gf lead, the knowledge block) cost.

Simulator: ``TeamBattleEnv.step`` turns per second (battles x turns) of tank actions without and with skills (T = 5,
random joint actions, B battles, 1v1 against SpinBot and 4v4 against SpinBot teams).
Robocode: the exported TankBot with and without skills (random weights; with skills it surfs about a third of its
steps) in 1v1 battles against SurfVG (whose waves the brain surfs), the time TankBot spends per turn (its run loop up
to execute(), System.nanoTime, reported per round as ``turn_us_mean``, ``first_turn_us``, ``turn_us_max`` of the
other turns and ``turns_over_1ms``) and the skipped turns;
Robocode's time per turn on this machine is its CPU constant, 2.7 ms (robocode-facts.md, section 10).

Usage: ``python benchmarks/tank_skills_speed.py [--seconds 3] [--battles 64] [--rounds 3] [--no-engine] [--json]``.
"""

from __future__ import annotations

import argparse
import json
import re
import tempfile
import time
from pathlib import Path

import numpy as np

from confront.arena.control import ControlConfig
from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.tank import TankSpace

PLAIN = TankSpace()
SKILLS = TankSpace(leads=("none", "circular", "gf"), surf=True, knowledge=True)


def sim_rate(scenario: str, space: TankSpace, battles: int, seconds: float) -> dict:
    """Battle-turns per second of the SMDP step (after a warm-up), wall and per CPU second."""
    env = TeamBattleEnv(scenario, n_battles=battles, seed=0, opponents="SpinBot",
                        config=SMDPConfig(turns_per_step=5, tank=space, reward="score"))
    env.reset()
    rng = np.random.default_rng(0)
    acts = [rng.integers(0, env.n_actions, size=(battles, env.n_robots)) for _ in range(16)]
    for i in range(10):
        env.step(acts[i % 16])
    n, t0, c0 = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < seconds:
        env.step(acts[n % 16])
        n += 1
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    turns = n * 5 * battles
    return {"where": "simulator", "scenario": scenario, "skills": space.skills, "battles": battles,
            "turns_per_s": turns / wall, "turns_per_cpu_s": turns / max(cpu, 1e-9)}


def engine_times(space: TankSpace, rounds: int, seed: int = 1) -> dict:
    """TankBot's per-turn time in Robocode (1v1 against SurfVG), from its round reports."""
    from confront.engine.battle import BattleSpec
    from confront.engine.runner import EngineOptions, run_battle
    from confront.engine.tank_export import TankPolicy, export_tank_robot

    rng = np.random.default_rng(6)
    sizes = [space.n_features, 64, 64, sum(space.dims)]
    biases = [rng.normal(0, 0.5, size=o) for o in sizes[1:]]
    if space.surf:
        biases[-1][len(space.distances)] += 1.5  # surf often
    policy = TankPolicy(tuple(rng.normal(0, 1.0, size=(o, i)) for i, o in zip(sizes, sizes[1:], strict=False)),
                        tuple(biases), space, ControlConfig(), 5)
    with tempfile.TemporaryDirectory() as tmp:
        jar = export_tank_robot(policy, Path(tmp) / "tankbot.jar")
        run = run_battle(BattleSpec(("confront.TankBot 1.0", "SurfVG"), rounds=rounds),
                         EngineOptions(seed=seed, cpu_constant_ms=10.0), extra_robots=[jar])
    reports = [r for r in run.summary["robot_reports"] if "tank-round" in r]
    mean = [int(m) for r in reports for m in re.findall(r"turn_us_mean=(\d+)", r)]
    top = [int(m) for r in reports for m in re.findall(r"turn_us_max=(\d+)", r)]
    at = [int(m) for r in reports for m in re.findall(r"at_turn=(\d+)", r)]
    first = [int(m) for r in reports for m in re.findall(r"first_turn_us=(\d+)", r)]
    slow = sum(int(m) for r in reports for m in re.findall(r"turns_over_1ms=(\d+)", r))
    turns = sum(int(m) for r in reports for m in re.findall(r" turns=(\d+)", r))
    return {"where": "robocode", "scenario": "1v1:SurfVG", "skills": space.skills, "rounds": rounds,
            "turn_us_mean": float(np.mean(mean)) if mean else None, "turn_us_max": max(top) if top else None,
            "turn_us_max_per_round": top, "at_turns": at, "first_turn_us": first, "turns_over_1ms": slow,
            "turns": turns,
            "skipped_turns": int(sum(run.skipped_turns.values()))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--battles", type=int, default=64)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--no-engine", action="store_true")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    rows = [sim_rate(sc, sp, args.battles, args.seconds) for sc in ("1v1", "4v4") for sp in (PLAIN, SKILLS)]
    for r in rows:
        print(f"simulator {r['scenario']:4s} skills={r['skills']!s:5s} B={r['battles']}: "
              f"{r['turns_per_s']:10.0f} battle-turns/s ({r['turns_per_cpu_s']:10.0f} per CPU s)")
    if not args.no_engine:
        for sp in (PLAIN, SKILLS):
            r = engine_times(sp, args.rounds)
            rows.append(r)
            print(f"robocode  1v1:SurfVG skills={r['skills']!s:5s}: TankBot {r['turn_us_mean']} us/turn mean, "
                  f"{r['turn_us_max']} us max (per round {r['turn_us_max_per_round']} at turns "
                  f"{r['at_turns']}), {r['turns_over_1ms']} of "
                  f"{r['turns']} turns over 1 ms (first turns, which get 10 times the time: {r['first_turn_us']} us), "
                  f"{r['skipped_turns']} skipped turns")
    if args.json:
        print(json.dumps(rows))


if __name__ == "__main__":
    main()
