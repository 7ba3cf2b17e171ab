"""Strength of the technique robots in Robocode: a robot's score share against opponents, 35-round 1v1 battles.

Usage: ``python benchmarks/technique_strength.py [--robot SurfVG] [--against Tracker,SpinBot,Walls,Crazy]
[--tank JAR] [--seeds 1,2,3] [--rounds 35] [--out FILE]``. ``--tank``: a robot jar written by
``confront export RUN --out X.jar`` (e.g. of docs/results/tanks/run); its ``confront.TankBot`` joins the opponents.
Prints one JSON line per opponent and seed (the robot's share of the total score) and the mean per opponent.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from technique_shares import emit  # benchmarks/technique_shares.py

from confront.engine.battle import BattleSpec
from confront.engine.runner import EngineOptions, run_battle

TANK = "confront.TankBot 1.0"


def share(robot: str, opponent: str, rounds: int, seed: int, extra: list[Path], cpu_ms: float) -> float:
    """The robot's share of the total score in one seeded engine battle."""
    run = run_battle(BattleSpec((robot, opponent), rounds=rounds), EngineOptions(seed=seed, cpu_constant_ms=cpu_ms),
                     extra_robots=extra)
    totals = [c.total for c in run.results.robots]
    return totals[0] / sum(totals)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="SurfVG")
    ap.add_argument("--against", default="Tracker,SpinBot,Walls,Crazy")
    ap.add_argument("--tank", default="", help="a jar written by confront export: its TankBot joins the opponents")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--rounds", type=int, default=35)
    ap.add_argument("--cpu-ms", type=float, default=20.0)
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    opponents = [o for o in args.against.split(",") if o]
    extra = [Path(args.tank)] if args.tank else []
    if args.tank:
        opponents.append(TANK)
    for opp in opponents:
        got = []
        for seed in (int(s) for s in args.seeds.split(",")):
            got.append(share(args.robot, opp, args.rounds, seed, extra, args.cpu_ms))
            print(json.dumps({"robot": args.robot, "opponent": opp, "seed": seed, "rounds": args.rounds,
                              "share": round(got[-1], 4)}), flush=True)
        row = {"robot": args.robot, "opponent": opp, "mean_share": round(float(np.mean(got)), 4),
               "min_share": round(min(got), 4), "seeds": len(got)}
        emit(row, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
