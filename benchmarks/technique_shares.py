"""Technique robots (confront.tech.*) in the simulator and in the real engine: score shares and identical rounds.

Usage: ``python benchmarks/technique_shares.py [--rounds 100] [--seeds 1,2,3] [--only NAME,...] [--out FILE]``.
Each matchup is one battle of ``rounds`` rounds with ``-DRANDOMSEED=seed`` in the engine (CPU constant ``--cpu-ms``,
default 50 ms: no skipped turns on a busy machine) and one seeded simulator battle (the engine's start positions and
random order; the robots keep their battle memory for all the battle's rounds, as their static fields live for the
engine's battle). Prints, per matchup and seed, each contestant's score share (%) in both, the difference, and how
many rounds are identical (same length and the same score parts for every robot).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from sample_shares import Matchup, shares  # benchmarks/sample_shares.py: the same matchups and shares

from confront.arena.scenarios import get_scenario
from confront.arena.tech import tech_battle
from confront.engine.runner import EngineOptions, run_battle


def _duel(a: str, b: str) -> Matchup:
    return Matchup(f"{a} vs {b}", ((a,), (b,)))


MATCHUPS = (
    _duel("RamHeadOn", "SpinBot"),
    _duel("OrbitLinear", "Tracker"),
    _duel("StopGoCircular", "Fire"),
    _duel("OrbitCircular", "Walls"),
    _duel("OrbitGF", "Crazy"),
    _duel("OrbitVG", "SpinBot"),
    _duel("SurfCircular", "OrbitLinear"),
    _duel("SurfGF", "OrbitCircular"),
    _duel("SurfVG", "SurfGF"),
    _duel("SurfVG", "RamFire"),
    _duel("OrbitLinear", "RamHeadOn"),
    _duel("StopGoCircular", "OrbitGF"),
    Matchup("melee RiskGF/SpinBot/Walls/Tracker", (("RiskGF",), ("SpinBot",), ("Walls",), ("Tracker",))),
    Matchup("4v4 RiskGF x4 vs Walls x4", (("RiskGF",) * 4, ("Walls",) * 4)),
)


def simulate(m: Matchup, rounds: int, seed: int) -> tuple[np.ndarray, list[int]]:
    """One seeded simulator battle: total score per robot, round lengths."""
    sc = get_scenario("melee").replace(teams=m.teams)
    parts, _, lengths = tech_battle(m.robots, rounds, seed=seed, n_battles=1, scenario=sc, rounds_per_battle=rounds)
    return parts.sum(axis=1), lengths


def engine(m: Matchup, rounds: int, seed: int, cpu_ms: float) -> tuple[dict, list[int], float]:
    """One seeded engine battle: the run's summary, round lengths, wall seconds."""
    t = time.time()
    run = run_battle(m.spec(rounds), EngineOptions(seed=seed, cpu_constant_ms=cpu_ms, timeout_s=3600))
    return run.summary, list(run.round_turns), time.time() - t


def compare(m: Matchup, rounds: int, seed: int, cpu_ms: float) -> dict:
    """One matchup and seed in both: shares, their largest difference, identical rounds."""
    sim_tot, sim_len = simulate(m, rounds, seed)
    summ, eng_len, wall = engine(m, rounds, seed, cpu_ms)
    eng_tot = np.array([r["score"]["total"] for r in summ["robots"]])
    same = 0
    for a, b in zip(sim_len, eng_len, strict=False):
        if a != b:
            break
        same += 1
    sim, eng = shares(sim_tot, m.teams), shares(eng_tot, m.teams)
    diff = max(abs(a - b) for a, b in zip(sim, eng, strict=True))
    return {"matchup": m.name, "seed": seed, "rounds": rounds, "sim": [round(v, 2) for v in sim],
            "engine": [round(v, 2) for v in eng], "diff": round(diff, 2),
            "same_length_rounds": same, "skipped": sum(summ["skipped_turns"].values()), "engine_wall_s": round(wall, 1)}


def emit(row: dict, out: str) -> None:
    """Print a result row as JSON; also append it to ``out`` unless empty."""
    print(json.dumps(row), flush=True)
    if out:
        with open(out, "a") as f:
            f.write(json.dumps(row) + "\n")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=100)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--only", default="", help="comma list of matchup names (default: all)")
    ap.add_argument("--out", default="")
    ap.add_argument("--cpu-ms", type=float, default=50.0, help="engine CPU constant: generous, so no turn is skipped")
    args = ap.parse_args()
    only = set(filter(None, args.only.split(",")))
    for m in (m for m in MATCHUPS if not only or m.name in only):
        for seed in map(int, args.seeds.split(",")):
            emit(compare(m, args.rounds, seed, args.cpu_ms), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
