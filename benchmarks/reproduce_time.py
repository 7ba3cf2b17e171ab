"""Wall time of one 500-round 4v4 arm (DMNN with AWM vs the TD team), the unit of `confront reproduce`.

Goal (issue 6): under 20 s on a 2-core machine. The TD team's pre-training is timed apart (it is cached and
shared by every arm of a seed). Usage: python benchmarks/reproduce_time.py [--rounds 500] [--seed 0]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rounds", type=int, default=500)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["CONFRONT_CACHE"] = str(Path(tmp) / "cache")
        from confront.experiments.spec import load_experiment
        from confront.experiments.train import td_team, train_run

        cfg = load_experiment("awm", [f"train.rounds={args.rounds}", f"train.seed={args.seed}", "train.replay=false"])
        t0 = time.perf_counter()
        td_team(cfg, 4)
        t1 = time.perf_counter()
        summary = train_run(cfg, Path(tmp) / "run", progress=False)
        t2 = time.perf_counter()
    rounds = summary["rounds"]
    print("| part | seconds | rounds/s |")
    print("|---|---:|---:|")
    print(f"| TD team pre-training ({cfg.opponent.pretrain_rounds} rounds, cached per seed) | {t1 - t0:.1f} | "
          f"{cfg.opponent.pretrain_rounds / (t1 - t0):.0f} |")
    print(f"| one {rounds}-round 4v4 arm (goal < 20 s) | {t2 - t1:.1f} | {rounds / (t2 - t1):.0f} |")
    print(f"decisions: {summary['decisions']}, battles side by side: {cfg.arena.battles}")


if __name__ == "__main__":
    main()
