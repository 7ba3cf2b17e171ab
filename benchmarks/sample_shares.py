"""Sample-robot battles in the simulator and in the real engine: score shares and identical rounds.

Usage: ``python benchmarks/sample_shares.py [--rounds 100] [--seeds 1,2,3] [--only NAME,...] [--out FILE]``.
Each matchup is one battle of ``rounds`` rounds with ``-DRANDOMSEED=seed`` in the engine (CPU constant
``--cpu-ms``, default 50 ms: no skipped turns on a busy machine) and one seeded simulator battle (the engine's
start positions and random order). Prints, per matchup and seed, each contestant's score share in both and
how many rounds are identical (same length and the same score parts for every robot); once a round differs,
the battles' random draws part and later rounds differ too.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import dataclass

import numpy as np

from confront.arena.bots import ScriptedBots
from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario
from confront.engine.battle import BattleSpec, Team
from confront.engine.runner import EngineOptions, run_battle

SAMPLE_TEAM = {"MyFirstLeader": "sampleteam.MyFirstLeader", "MyFirstDroid": "sampleteam.MyFirstDroid"}
MY_FIRST_TEAM = ("MyFirstLeader",) + ("MyFirstDroid",) * 4


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
        conts: list[str | Team] = []
        for k, c in enumerate(self.contestants):
            members = tuple(SAMPLE_TEAM.get(r, r) for r in c)
            conts.append(members[0] if len(c) == 1 else Team(f"T{k}{c[0]}", members))
        return BattleSpec(tuple(conts), rounds=rounds)


MATCHUPS = (
    Matchup("SpinBot vs Walls", (("SpinBot",), ("Walls",))),
    Matchup("Tracker vs RamFire", (("Tracker",), ("RamFire",))),
    Matchup("Fire vs Corners", (("Fire",), ("Corners",))),
    Matchup("Fire vs RamFire", (("Fire",), ("RamFire",))),
    Matchup("Crazy vs SittingDuck", (("Crazy",), ("SittingDuck",))),
    Matchup("TrackFire vs Tracker", (("TrackFire",), ("Tracker",))),
    Matchup("TrackFire vs SpinBot", (("TrackFire",), ("SpinBot",))),
    Matchup("melee SpinBot/Walls/Tracker/RamFire", (("SpinBot",), ("Walls",), ("Tracker",), ("RamFire",))),
    Matchup("4v4 SpinBot,Walls,Tracker,RamFire vs Walls,Tracker,Crazy,Fire",
            (("SpinBot", "Walls", "Tracker", "RamFire"), ("Walls", "Tracker", "Crazy", "Fire"))),
    Matchup("4v4 TrackFire x4 vs RamFire x4", (("TrackFire",) * 4, ("RamFire",) * 4)),
    Matchup("MyFirstTeam (5) vs Tracker x4", (MY_FIRST_TEAM, ("Tracker",) * 4)),
)


def simulate(m: Matchup, rounds: int, seed: int) -> tuple[np.ndarray, list[int], list[np.ndarray]]:
    """One seeded simulator battle: score parts per robot, round lengths, per-round robot scores."""
    sc = get_scenario("melee").replace(teams=m.teams, turns_after_end=150, max_turns=100000)
    arena = Arena(sc, 1, seed=seed, order="engine")
    bots = ScriptedBots(arena, m.robots)
    cmd = arena.idle_commands()
    s = arena.state
    lengths, per_round = [], []
    last = np.zeros(len(m.robots))
    while len(lengths) < rounds:
        bots.commands(cmd)
        arena.step(cmd)
        if s.done[0]:
            lengths.append(int(s.time[0]))
            tot = s.score_total[0].sum(axis=1)
            per_round.append(tot - last)
            last = tot.copy()
            if len(lengths) < rounds:
                arena.reset(s.done.copy())
    return s.score_total[0].copy(), lengths, per_round


def engine(m: Matchup, rounds: int, seed: int, cpu_ms: float) -> tuple[dict, list[int], list[np.ndarray], float]:
    """One seeded engine battle: the run's summary, round lengths, per-round robot scores, wall seconds."""
    t = time.time()
    run = run_battle(m.spec(rounds), EngineOptions(seed=seed, cpu_constant_ms=cpu_ms, timeout_s=3600))
    wall = time.time() - t
    per_round, last = [], np.zeros(len(m.robots))
    for rs in run.summary["round_scores"]:
        tot = np.array([r["score"]["total"] for r in rs["robots"]])  # battle totals after the round
        per_round.append(tot - last)
        last = tot
    return run.summary, list(run.round_turns), per_round, wall


def shares(totals: np.ndarray, teams: tuple[int, ...]) -> list[float]:
    """Score share (%) of each contestant."""
    edges = np.cumsum((0,) + teams)
    per = np.array([totals[a:b].sum() for a, b in zip(edges[:-1], edges[1:], strict=True)])
    return (100 * per / per.sum()).tolist()


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
        if only and not any(o in m.name for o in only):
            continue
        for seed in seeds:
            sim_tot, sim_len, sim_rounds = simulate(m, args.rounds, seed)
            summ, eng_len, eng_rounds, wall = engine(m, args.rounds, seed, args.cpu_ms)
            eng_tot = np.array([r["score"]["total"] for r in summ["robots"]])
            same = 0
            for a, b, pa, pb in zip(sim_len, eng_len, sim_rounds, eng_rounds, strict=False):
                if a != b or np.abs(pa - pb).max() > 1e-6:
                    break
                same += 1
            row = {"matchup": m.name, "seed": seed, "rounds": args.rounds,
                   "sim": shares(sim_tot.sum(axis=1), m.teams), "engine": shares(eng_tot, m.teams),
                   "identical_rounds": same, "skipped": sum(summ["skipped_turns"].values()),
                   "engine_wall_s": round(wall, 1), "setup_s": round(summ["setup_s"], 2)}
            print(json.dumps(row), flush=True)
            if args.out:
                with open(args.out, "a") as f:
                    f.write(json.dumps(row) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
