"""Turns per second of bridged battles (BridgeBot tanks driven by a Python policy) against the same
battles with sample robots only, and against the same policy exported to Java (PolicyBot: identical
decisions, no Python), measured in one run. Goal: the bridge costs at most 25% of the speed.

Usage: python benchmarks/bridge_throughput.py [--rounds 10] [--cpu-ms 10] [--json]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from confront.engine.battle import BattleSpec, Team
from confront.engine.bridged import BRIDGE_BOT, BRIDGE_CPU_CONSTANT_MS, BridgedRun, run_bridged_battle
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.runner import EngineOptions, EngineRun, run_battle

OPPONENTS = ("Walls", "Tracker", "SpinBot", "RamFire")
STAND_IN = "Tracker"  # the sample robot that takes the bridged tank's place in the reference battle


def _spec(size: int, ours: str, rounds: int) -> BattleSpec:
    if size == 1:
        return BattleSpec((ours, "Walls"), rounds=rounds)
    return BattleSpec((Team("Ours4", (ours,) * size), Team("Them4", OPPONENTS[:size])), rounds=rounds)


def _record(name: str, mode: str, run: EngineRun, wall: float, bridged: BridgedRun | None = None) -> dict:
    busy = max(run.elapsed_s - run.setup_s, 1e-9)
    return {
        "scenario": name, "mode": mode, "turns": run.turns, "turns_per_s": run.turns / run.elapsed_s,
        "turns_per_s_excl_setup": run.turns / busy, "robot_turns_per_s": run.robot_turns / run.elapsed_s,
        "setup_s": run.setup_s, "elapsed_s": run.elapsed_s, "wall_s": wall,
        "skipped_turns": sum(run.skipped_turns.values()),
        "decisions": bridged.decisions if bridged else 0,
        "bridge_failures": len(bridged.failures) if bridged else 0,
        "rtt_mean_us": bridged.rtt_mean_us if bridged else None,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--cpu-ms", type=float, default=BRIDGE_CPU_CONSTANT_MS,
                    help="engine CPU constant (ms per robot turn)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--every", type=int, default=1, help="ask Python every k turns (SMDP step)")
    ap.add_argument("--json", action="store_true", help="print the records as one JSON list at the end")
    args = ap.parse_args()
    opts = EngineOptions(seed=args.seed, cpu_constant_ms=args.cpu_ms)
    policy = ExportedPolicy("qtable", q=np.random.default_rng(args.seed).normal(size=(320, 4)),
                            step_turns=args.every)
    records = []
    with tempfile.TemporaryDirectory(prefix="confront-bench-") as tmp:
        exported = export_robot(policy, Path(tmp) / "robots")
        for name, size in (("1v1", 1), ("4v4", 4)):
            t0 = time.perf_counter()
            ref = run_battle(_spec(size, STAND_IN, args.rounds), opts)
            records.append(_record(name, "sample robots", ref, time.perf_counter() - t0))
            t0 = time.perf_counter()
            spec = _spec(size, "confront.PolicyBot*" if size == 1 else "confront.PolicyBot", args.rounds)
            java = run_battle(spec, opts, extra_robots=[exported])
            records.append(_record(name, "same policy in Java", java, time.perf_counter() - t0))
            t0 = time.perf_counter()
            bridged = run_bridged_battle(_spec(size, BRIDGE_BOT, args.rounds), policy, opts, every=args.every)
            records.append(_record(name, "bridged", bridged.run, time.perf_counter() - t0, bridged))
    print(f"rounds={args.rounds} cpu_constant_ms={args.cpu_ms} seed={args.seed} every={args.every}")
    head = ("scenario", "mode", "turns", "turns/s", "turns/s excl set-up", "robot-turns/s", "set-up s",
            "skipped", "decisions", "failures", "mean round trip us")
    print(" | ".join(head))
    for r in records:
        print(f"{r['scenario']} | {r['mode']} | {r['turns']} | {r['turns_per_s']:.0f} | "
              f"{r['turns_per_s_excl_setup']:.0f} | {r['robot_turns_per_s']:.0f} | {r['setup_s']:.2f} | "
              f"{r['skipped_turns']} | {r['decisions']} | {r['bridge_failures']} | "
              f"{'-' if r['rtt_mean_us'] is None else round(r['rtt_mean_us'])}")
    for name in ("1v1", "4v4"):
        ref, java, br = (r for r in records if r["scenario"] == name)
        for label, base in (("sample robots", ref), ("the same policy in Java", java)):
            cost = 1 - br["turns_per_s_excl_setup"] / base["turns_per_s_excl_setup"]
            cost_all = 1 - br["turns_per_s"] / base["turns_per_s"]
            print(f"{name}: bridge cost vs {label}: {100 * cost:.1f}% of the speed excluding round set-up, "
                  f"{100 * cost_all:.1f}% including it (goal <= 25%)")
    if args.json:
        print(json.dumps(records))


if __name__ == "__main__":
    main()
