"""Robot-turns per second of the arena (engine column ``sim``) and, when installed, the real engine.

Usage: ``python benchmarks/sim_throughput.py [--json] [--seconds S] [--order engine|shuffle|fixed]``.
Prints a table; with ``--json`` the last line is one JSON list of records with keys scenario, batch,
engine, turns_per_s, robot_turns_per_s.

Workloads (``--workload``): ``bots`` (default) plays the same sample robots as the engine column
(confront.engine.bench's teams: ours SpinBot, Walls, Tracker, RamFire; them Walls, Tracker, Crazy,
Fire, SpinBot, cycled) with the compiled scripted bots, their decisions included in the time
(``ScriptedBots.play``: decisions, turn and restart of finished rounds in compiled code, 16 turns a call);
``random`` drives every robot with a random AdvancedRobot command stream (new commands every 16
turns, fire power 0.5-3 every turn: many more bullets than real battles). Finished rounds restart at
once inside the timed loop. Robot-turns count the robots alive in each turn, as the engine figures
in robocode-facts.md do. ``sim-raw-step`` rows time ``Arena.step`` alone with fixed commands (one
battle, Python call included) for the single-battle goal.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from confront.arena.bots import ScriptedBots  # noqa: E402
from confront.arena.core import Arena  # noqa: E402
from confront.arena.scenarios import get_scenario  # noqa: E402

SCENARIOS = ("1v1", "4v4", "4v10")
BATCHES = (1, 64, 256, 1024)
OURS = ("SpinBot", "Walls", "Tracker", "RamFire")
THEM = ("Walls", "Tracker", "Crazy", "Fire", "SpinBot")


def bot_names(scenario: str) -> list[str]:
    """The engine benchmark's sample robots for a scenario (each side cycles its list)."""
    teams = get_scenario(scenario).teams
    if len(teams) != 2:
        return [([OURS[0]] + list(THEM))[i % (len(THEM) + 1)] for i in range(sum(teams))]
    return [OURS[i % len(OURS)] for i in range(teams[0])] + [THEM[i % len(THEM)] for i in range(teams[1])]


def command_pool(b: int, r: int, n: int, rng: np.random.Generator) -> np.ndarray:
    """n command arrays (B, R, 5); NaN in between refreshes keeps the remaining values."""
    pool = np.full((n, b, r, 5), np.nan)
    pool[..., 0] = rng.uniform(-300, 300, (n, b, r))
    pool[..., 1] = rng.uniform(-np.pi, np.pi, (n, b, r))
    pool[..., 2] = rng.uniform(-np.pi, np.pi, (n, b, r))
    pool[..., 3] = rng.uniform(-2 * np.pi, 2 * np.pi, (n, b, r))
    pool[..., 4] = rng.uniform(0.5, 3.0, (n, b, r))
    return pool


def sim_throughput(scenario: str, batch: int, seconds: float, order: str, threads: int | None,
                   workload: str = "bots") -> dict:
    """Battle-turns and alive-robot-turns per second for a batch of battles (best of 3 timings)."""
    arena = Arena(scenario, batch, seed=1, order=order, threads=threads)
    rng = np.random.default_rng(0)
    pool = command_pool(batch, arena.n_robots, 8, rng)
    keep = arena.idle_commands()
    keep[..., 4] = pool[0, ..., 4]
    bots = ScriptedBots(arena, bot_names(scenario)) if workload == "bots" else None
    arena.step(pool[0])  # compile / warm up
    if bots is not None:
        bots.play(1)
    best = (0.0, 0.0)
    for _ in range(3):
        turns = 0
        robot_turns = 0
        t0 = time.perf_counter()
        i = 0
        while True:
            if bots is not None:  # 16 x (bots' decisions, one turn, count the alive, restart finished rounds)
                robot_turns += bots.play(16)
            else:
                for k in range(16):
                    arena.step(pool[i % 8] if k == 0 else keep)
                    robot_turns += int(arena.state.alive.sum())
                    done = arena.state.done
                    if done.any():
                        arena.reset(done)
            i += 1
            turns += 16 * batch
            if time.perf_counter() - t0 >= seconds / 3:
                break
        dt = time.perf_counter() - t0
        if robot_turns / dt > best[1]:
            best = (turns / dt, robot_turns / dt)
    return {"scenario": scenario, "batch": batch, "engine": f"sim-{workload}", "turns_per_s": best[0],
            "robot_turns_per_s": best[1]}


def raw_step(scenario: str, seconds: float, order: str) -> dict:
    """Single battle, fixed commands, Arena.step only (includes the Python call)."""
    arena = Arena(scenario, 1, seed=1, order=order, threads=1)
    arena.params[3] = 1e9  # no inactivity drain: the battle keeps running
    cmd = arena.idle_commands()
    cmd[..., 0], cmd[..., 1], cmd[..., 3] = 40.0, 0.3, 1.0
    arena.step(cmd)
    n = 0
    alive = 0
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        for _ in range(1000):
            arena.step(cmd)
        alive += int(arena.state.alive.sum()) * 1000
        n += 1000
        if arena.state.done[0]:
            arena.reset()
    dt = time.perf_counter() - t0
    return {"scenario": scenario, "batch": 1, "engine": "sim-raw-step", "turns_per_s": n / dt,
            "robot_turns_per_s": alive / dt}


def engine_rows(scenario: str) -> list[dict]:
    """The real engine's rate on the same scenario, if helper code and the engine are available."""
    try:
        from confront.engine.bench import engine_throughput  # type: ignore[import-not-found]
    except Exception:
        return []
    try:
        rec = engine_throughput(scenario)
    except Exception as exc:  # engine not installed or failed: leave the column out
        print(f"# engine {scenario}: {exc}", file=sys.stderr)
        return []
    return [{"scenario": scenario, "batch": 1, "engine": "robocode", "turns_per_s": float(rec["turns_per_s"]),
             "robot_turns_per_s": float(rec["robot_turns_per_s"])}]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--seconds", type=float, default=1.5)
    ap.add_argument("--order", default="engine", choices=["engine", "shuffle", "fixed"])
    ap.add_argument("--threads", type=int, default=None, help="worker threads (default: CPUs available)")
    ap.add_argument("--scenarios", default=",".join(SCENARIOS))
    ap.add_argument("--workload", default="bots", choices=["bots", "random"])
    ap.add_argument("--no-engine", action="store_true", help="skip the real engine")
    args = ap.parse_args()
    rows: list[dict] = []
    for sc in args.scenarios.split(","):
        for b in BATCHES:
            rows.append(sim_throughput(sc, b, args.seconds, args.order, args.threads, args.workload))
        rows.append(raw_step(sc, args.seconds, args.order))
        if not args.no_engine:
            rows.extend(engine_rows(sc))
    eng = {r["scenario"]: r["robot_turns_per_s"] for r in rows if r["engine"] == "robocode"}
    print(f"order={args.order}, threads={args.threads or 'all CPUs'}, load average {os.getloadavg()[0]:.1f}")
    print(f"{'scenario':<8} {'batch':>6} {'engine':<13} {'turns/s':>14} {'robot-turns/s':>15} {'x engine':>9}")
    for r in rows:
        ratio = r["robot_turns_per_s"] / eng[r["scenario"]] if r["scenario"] in eng else float("nan")
        print(f"{r['scenario']:<8} {r['batch']:>6} {r['engine']:<13} {r['turns_per_s']:>14,.0f} "
              f"{r['robot_turns_per_s']:>15,.0f} {ratio:>9,.0f}")
    if args.json:
        print(json.dumps(rows))


if __name__ == "__main__":
    main()
