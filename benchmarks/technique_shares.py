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
from dataclasses import dataclass

import numpy as np

from confront.arena.scenarios import get_scenario
from confront.arena.tech import tech_battle
from confront.engine.battle import BattleSpec, Team
from confront.engine.runner import EngineOptions, run_battle


@dataclass(frozen=True)
class Matchup:
    """Contestants as tuples of robot names (one name: a single robot; more: a team)."""

    name: str
    contestants: tuple[tuple[str, ...], ...]

    @property
    def robots(self) -> list[str]:
        return [r for c in self.contestants for r in c]

    @property
    def teams(self) -> tuple[int, ...]:
        return tuple(len(c) for c in self.contestants)

    def spec(self, rounds: int) -> BattleSpec:
        conts: list[str | Team] = [c[0] if len(c) == 1 else Team(f"T{k}{c[0]}", c)
                                   for k, c in enumerate(self.contestants)]
        return BattleSpec(tuple(conts), rounds=rounds)


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


def shares(totals: np.ndarray, teams: tuple[int, ...]) -> list[float]:
    """Score share (%) of each contestant."""
    edges = np.cumsum((0,) + teams)
    per = np.array([totals[a:b].sum() for a, b in zip(edges[:-1], edges[1:], strict=True)])
    return (100 * per / per.sum()).tolist()


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


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=100)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--only", default="")
    ap.add_argument("--out", default="")
    ap.add_argument("--cpu-ms", type=float, default=50.0, help="engine CPU constant: generous, so no turn is skipped")
    args = ap.parse_args()
    seeds = [int(x) for x in args.seeds.split(",")]
    only = [x for x in args.only.split(",") if x]
    for m in MATCHUPS:
        if only and not any(o == m.name for o in only):
            continue
        for seed in seeds:
            row = compare(m, args.rounds, seed, args.cpu_ms)
            print(json.dumps(row), flush=True)
            if args.out:
                with open(args.out, "a") as f:
                    f.write(json.dumps(row) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
