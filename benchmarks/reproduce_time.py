"""Wall time of the units of `confront reproduce`: one 500-round 4v4 arm, and the whole migration experiment.

Goals: one arm (DMNN with AWM vs the TD team) under 20 s on a 2-core machine (issue 6), its TD team's
pre-training timed apart (cached and shared by every arm of a seed); `confront reproduce migration` (1000 seeds
of SSAQ, Greedy and Dgreedy, 4000 episodes, tests, figure, report) under 60 s (issue 13).
Usage: python benchmarks/reproduce_time.py [--part arm|migration|all] [--rounds 500] [--seed 0] [--seeds 1000]
Prints a table; the last line is one JSON list of records {part, seconds, cpu_s (migration), goal_s, ...}.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def arm(rounds: int, seed: int) -> list[dict]:
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["CONFRONT_CACHE"] = str(Path(tmp) / "cache")
        from confront.train.factory import train_run
        from confront.train.league import td_team
        from confront.train.spec import load_experiment

        cfg = load_experiment("awm", [f"train.rounds={rounds}", f"train.seed={seed}", "train.replay=false"])
        t0 = time.perf_counter()
        td_team(cfg, 4)
        t1 = time.perf_counter()
        summary = train_run(cfg, Path(tmp) / "run", progress=False)
        t2 = time.perf_counter()
    pre = cfg.opponent.pretrain_rounds
    return [{"part": f"TD team pre-training ({pre} rounds, cached per seed)", "seconds": t1 - t0, "goal_s": None,
             "rounds_per_s": pre / (t1 - t0)},
            {"part": f"one {summary['rounds']}-round 4v4 arm", "seconds": t2 - t1, "goal_s": 20.0,
             "rounds_per_s": summary["rounds"] / (t2 - t1), "decisions": summary["decisions"],
             "battles": cfg.arena.battles}]


def migration(seeds: int) -> list[dict]:
    from confront.experiments.migration import run_migration

    run_migration(seeds=2, episodes=2)  # compile (or load) the kernel first
    t0, c0 = time.perf_counter(), time.process_time()
    res = run_migration(seeds=seeds)
    t1, c1 = time.perf_counter(), time.process_time()
    with tempfile.TemporaryDirectory() as tmp:
        t2, k2 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
        cmd = [sys.executable, "-m", "confront.cli.main", "reproduce", "migration", "--seeds", str(seeds),
               "--out", tmp]
        subprocess.run(cmd, check=True, capture_output=True)
        t3, k3 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    runs = seeds * len(res.convergence) * res.settings["episodes"]
    child_cpu = (k3.ru_utime + k3.ru_stime) - (k2.ru_utime + k2.ru_stime)
    return [{"part": f"run_migration: {seeds} seeds x {len(res.convergence)} methods x {res.settings['episodes']} "
                     "episodes", "seconds": t1 - t0, "cpu_s": c1 - c0, "goal_s": None,
             "episodes_per_s": runs / (t1 - t0)},
            {"part": f"`confront reproduce migration --seeds {seeds}` (process start to report)", "seconds": t3 - t2,
             "cpu_s": child_cpu, "goal_s": 60.0}]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--part", choices=["arm", "migration", "all"], default="all")
    ap.add_argument("--rounds", type=int, default=500)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--seeds", type=int, default=1000, help="migration seeds")
    args = ap.parse_args()
    if args.rounds < 1 or args.seeds < 1:
        ap.error("--rounds and --seeds must be at least 1")
    rows: list[dict] = []
    if args.part in ("migration", "all"):
        rows += migration(args.seeds)
    if args.part in ("arm", "all"):
        rows += arm(args.rounds, args.seed)
    print(f"load average {os.getloadavg()[0]:.1f}, {os.cpu_count()} CPUs")
    print("| part | wall (s) | CPU (s) | goal, wall (s) |")
    print("|---|---:|---:|---:|")
    for r in rows:
        cpu = f"{r['cpu_s']:.1f}" if "cpu_s" in r else "-"
        print(f"| {r['part']} | {r['seconds']:.1f} | {cpu} | {r['goal_s'] or '-'} |")
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
