"""Battles per second of ``confront rumble`` with 1 and 2 local workers (issue 31: 2 workers >= 1.7x one).

sample.Tracker against jars of eight sample robots made from the installed engine (1v1, ``--rounds`` rounds on
800x600, CPU constant 10 ms), each battle its own JVM and working directory. The two settings alternate over
``--repeats`` repetitions (1, 2, 2, 1, ...: both see the same machine load on average), each into a fresh output
folder; battles/s = battles played / wall time of the call that played them (a worker pool's start included).
The last line is JSON: median (and mean) battles/s of each, their ratio, and the load average before and after
(the machine's other work shares the cores).

Usage: python benchmarks/rumble_throughput.py [--rounds 10] [--repeats 3] [--robots 8]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
from pathlib import Path

from confront.engine.rumble import sample_jars
from confront.experiments.rumble import RumbleSettings, run_rumble

OPPONENTS = ("SpinBot", "Walls", "Crazy", "Fire", "Corners", "RamFire", "TrackFire", "VelociRobot", "Target",
             "SittingDuck", "MyFirstRobot")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--robots", type=int, default=8, help=f"opponents (at most {len(OPPONENTS)})")
    ap.add_argument("--one-cpu", action="store_true", help="each battle's JVM on one claimed CPU (C1 only)")
    args = ap.parse_args()
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="rumble-bench-") as tmp:
        folder = Path(tmp) / "robots"
        sample_jars(folder, OPPONENTS[: args.robots])
        settings = RumbleSettings("1v1", seeds=1, rounds=args.rounds, one_cpu=args.one_cpu)
        rates: dict[int, list[float]] = {1: [], 2: []}
        order = [w for rep in range(args.repeats) for w in ((1, 2) if rep % 2 == 0 else (2, 1))]
        for i, workers in enumerate(order):
            report = run_rumble("sample.Tracker", folder, settings, Path(tmp) / f"out{i}", workers=workers,
                                progress=False)
            st = report.stats
            rate = st.played / st.elapsed_s
            rates[workers].append(rate)
            print(f"workers {workers}: {st.played} battles in {st.elapsed_s:.1f} s = {rate:.3f} battles/s", flush=True)
    one, two = statistics.median(rates[1]), statistics.median(rates[2])
    mean1, mean2 = statistics.mean(rates[1]), statistics.mean(rates[2])
    load = (load_before, os.getloadavg()[0])
    print(f"median: 1 worker {one:.3f} battles/s, 2 workers {two:.3f} battles/s: {two / one:.2f}x (goal >= 1.7x); "
          f"mean {mean1:.3f} and {mean2:.3f}: {mean2 / mean1:.2f}x; load average {load[0]:.1f} before, {load[1]:.1f} "
          "after")
    print(json.dumps({"benchmark": "rumble_throughput", "rounds": args.rounds, "battles": args.robots,
                      "repeats": args.repeats, "one_cpu": args.one_cpu, "battles_per_s_1": round(one, 4),
                      "battles_per_s_2": round(two, 4), "speedup": round(two / one, 3),
                      "mean_speedup": round(mean2 / mean1, 3), "load_average": [round(v, 2) for v in load],
                      "runs_1": [round(r, 4) for r in rates[1]], "runs_2": [round(r, 4) for r in rates[2]]}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
