"""The technique robots against each other and the sample robots in the simulator: a round robin of 1v1 battles.

Usage: ``python benchmarks/technique_ladder.py [--rounds 35] [--seeds 1,2,3] [--out FILE]``. Each pairing is one
35-round battle per seed (the RoboRumble's battle; the robots' memory lives for the battle), seeded as the engine
(benchmarks/technique_shares.py shows the engine scores the same). Prints each robot's APS (mean share over its
pairings with the other technique robots) and its mean share against the sample robots, one JSON line per robot.
"""

from __future__ import annotations

import argparse
import itertools

import numpy as np
from technique_shares import emit  # benchmarks/technique_shares.py

from confront.arena.scenarios import get_scenario
from confront.arena.tech import TECH_ROBOTS, tech_battle

SAMPLES = ("Tracker", "SpinBot", "Walls", "Crazy", "RamFire", "Fire")


def share(a: str, b: str, rounds: int, seeds: list[int]) -> float:
    """a's mean share of the total score over one battle per seed."""
    got = []
    for seed in seeds:
        parts, _, _ = tech_battle([a, b], rounds, seed=seed, scenario=get_scenario("1v1"), rounds_per_battle=rounds)
        tot = parts.sum(axis=1)
        got.append(tot[0] / tot.sum())
    return float(np.mean(got))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=35)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    robots = list(TECH_ROBOTS)
    pair: dict[tuple[str, str], float] = {}
    for a, b in itertools.combinations(robots, 2):
        pair[a, b] = share(a, b, args.rounds, seeds)
        pair[b, a] = 1.0 - pair[a, b]
    for r in robots:
        row = {"robot": r, "aps_vs_technique": round(float(np.mean([pair[r, o] for o in robots if o != r])), 4),
               "vs_samples": round(float(np.mean([share(r, s, args.rounds, seeds) for s in SAMPLES])), 4),
               "pairs": {o: round(pair[r, o], 3) for o in robots if o != r}}
        emit(row, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
