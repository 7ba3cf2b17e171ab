"""A PPO run's share against some entries over its training rounds, from its ``metrics/rounds.csv``: the mean
share of each entry's rounds in consecutive windows of the run's rounds (docs/results/tanks-tech: the skill
prior's share falls in the first thousands of rounds, then climbs back).

Usage: ``python benchmarks/share_trajectory.py RUN --entries 1v1:SurfGF,1v1:OrbitGF [--edges 0,500,1000,...]``.
Prints one row per entry, then one JSON line."""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path


def trajectory(run: Path, entries: list[str], edges: list[int]) -> dict[str, list[float | None]]:
    """Per entry, its mean share in rounds [edges[i], edges[i+1]) of the run (None: no round of it there)."""
    with (run / "metrics" / "rounds.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    out: dict[str, list[float | None]] = {}
    for e in entries:
        means: list[float | None] = []
        for lo, hi in zip(edges, edges[1:], strict=False):
            got = [float(r["score_ours"]) / max(float(r["score_ours"]) + float(r["score_theirs"]), 1e-9)
                   for r in rows[lo:hi] if r["opponent"] == e]
            means.append(sum(got) / len(got) if got else None)
        out[e] = means
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path)
    ap.add_argument("--entries", default="1v1:SurfGF,1v1:SurfVG,1v1:OrbitGF")
    ap.add_argument("--edges", default="0,500,1000,2000,4000,8000,12000,20000,30000,40000,50000,60000")
    args = ap.parse_args()
    edges = [int(x) for x in args.edges.split(",")]
    shares = trajectory(args.run, args.entries.split(","), edges)
    print("rounds: " + " ".join(f"{lo}-{hi}" for lo, hi in zip(edges, edges[1:], strict=False)))
    for e, v in shares.items():
        print(f"{e:20s} " + " ".join("-" if x is None else f"{x:.2f}" for x in v))
    print(json.dumps({"bench": "share_trajectory", "run": str(args.run), "edges": edges, "shares": shares}))


if __name__ == "__main__":
    main()
