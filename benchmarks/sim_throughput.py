"""Robot-turns per second of the arena (engine column ``sim``) and, when installed, the real engine.

Usage: ``python benchmarks/sim_throughput.py [--json] [--seconds S] [--order engine|shuffle|fixed] [--plot PNG]``.
Prints a table; with ``--json`` the last line is one JSON list of records with keys scenario, batch,
engine, turns_per_s, robot_turns_per_s (simulator rows add robot_turns_per_cpu_s; team-env rows add
decisions_per_s, decisions_per_cpu_s, threads). The "per CPU-s" column divides by the process's CPU time (all
its threads): on a machine shared with other jobs it moves less than the wall-clock rates.

``team-env`` rows: :class:`TeamBattleEnv` with learner actions, the learner-facing path: 4v4 against SpinBot,
T = 10, uniformly random actions of the paper's 4 moves for the 4 learning tanks, ``batch`` battles;
``decisions_per_s`` = learner decisions (alive or not) per second, ``robot_turns_per_s`` = alive robots x turns.
``--team-opponents 1v1:SurfVG,4v4:OrbitGF`` plays those SCENARIO:OPPONENT entries instead (the technique robots of
confront.arena.tech, or any sample robot; rows name them as ``env:OPPONENT``); ``--scenarios ""`` skips the
arena rows, e.g. ``python benchmarks/sim_throughput.py --scenarios "" --no-engine --team-opponents
1v1:SurfVG,4v4:OrbitGF --team-batches 64``.
``--plot PNG`` (``confront bench sim --plot``) writes the scaling figure instead: scripted 4v4 and the team env,
throughput against batch size at 1 and 2 threads.

Workloads (``--workload``): ``bots`` (default) plays the same sample robots as the engine column
(confront.engine.bench's teams: ours SpinBot, Walls, Tracker, RamFire; them Walls, Tracker, Crazy,
Fire, SpinBot, cycled) with the compiled scripted bots, their decisions included in the time
(``ScriptedBots.play``: decisions, turn and restart of finished rounds in compiled code, 16 turns a call, or
``--turns-per-call``);
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
                   workload: str = "bots", per_call: int = 16) -> dict:
    """Battle-turns and alive-robot-turns per second for a batch of battles (best of 3 timings); the bots play
    ``per_call`` turns a call."""
    arena = Arena(scenario, batch, seed=1, order=order, threads=threads)
    rng = np.random.default_rng(0)
    pool = command_pool(batch, arena.n_robots, 8, rng)
    keep = arena.idle_commands()
    keep[..., 4] = pool[0, ..., 4]
    bots = ScriptedBots(arena, bot_names(scenario)) if workload == "bots" else None
    arena.step(pool[0])  # compile / warm up
    if bots is not None:
        bots.play(1)
    best = (0.0, 0.0, 0.0)
    for _ in range(3):
        turns = 0
        robot_turns = 0
        t0, c0 = time.perf_counter(), time.process_time()
        i = 0
        while True:
            if bots is not None:  # per_call x (bots' decisions, one turn, count the alive, restart finished rounds)
                robot_turns += bots.play(per_call)
                turns += per_call * batch
            else:
                turns += 16 * batch
                for k in range(16):
                    arena.step(pool[i % 8] if k == 0 else keep)
                    robot_turns += int(arena.state.alive.sum())
                    done = arena.state.done
                    if done.any():
                        arena.reset(done)
            i += 1
            if time.perf_counter() - t0 >= seconds / 3:
                break
        dt, cpu = time.perf_counter() - t0, time.process_time() - c0
        if robot_turns / dt > best[1]:
            best = (turns / dt, robot_turns / dt, robot_turns / cpu)
    return {"scenario": scenario, "batch": batch, "engine": f"sim-{workload}", "turns_per_s": best[0],
            "robot_turns_per_s": best[1], "robot_turns_per_cpu_s": best[2]}


def raw_step(scenario: str, seconds: float, order: str) -> dict:
    """Single battle, fixed commands, Arena.step only (includes the Python call)."""
    arena = Arena(scenario, 1, seed=1, order=order, threads=1)
    arena.params[3] = 1e9  # no inactivity drain: the battle keeps running
    cmd = arena.idle_commands()
    cmd[..., 0], cmd[..., 1], cmd[..., 3] = 40.0, 0.3, 1.0
    arena.step(cmd)
    n = 0
    alive = 0
    t0, c0 = time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < seconds:
        for _ in range(1000):
            arena.step(cmd)
        alive += int(arena.state.alive.sum()) * 1000
        n += 1000
        if arena.state.done[0]:
            arena.reset()
    dt, cpu = time.perf_counter() - t0, time.process_time() - c0
    return {"scenario": scenario, "batch": 1, "engine": "sim-raw-step", "turns_per_s": n / dt,
            "robot_turns_per_s": alive / dt, "robot_turns_per_cpu_s": alive / cpu}


def team_env(scenario: str, batch: int, seconds: float, threads: int | None = None, opponents: str = "SpinBot",
             turns: int = 10) -> dict:
    """TeamBattleEnv with random learner actions: decisions and alive robot-turns per second (best of 3)."""
    import numba

    from confront.arena.smdp import SMDPConfig, TeamBattleEnv

    old = numba.get_num_threads()
    if threads is not None:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        env = TeamBattleEnv(scenario, batch, seed=1, opponents=opponents, config=SMDPConfig(turns_per_step=turns))
    finally:
        numba.set_num_threads(old)
    env.reset()
    learners = int(env.learner.sum())
    acts = np.random.default_rng(0).integers(0, env.n_actions, size=(16, batch, env.n_robots))
    env.step(acts[0])
    best = (0.0, 0.0, 0.0, 0.0)
    for _ in range(3):
        steps, robot_turns, i = 0, 0.0, 0
        t0, c0 = time.perf_counter(), time.process_time()
        while True:
            alive = env.arena.state.alive.sum()
            env.step(acts[i % 16])
            robot_turns += (alive + env.arena.state.alive.sum()) / 2 * turns  # alive robots over the step, about
            steps += 1
            i += 1
            if time.perf_counter() - t0 >= seconds / 3:
                break
        dt, cpu = time.perf_counter() - t0, time.process_time() - c0
        if steps / dt > best[0]:
            best = (steps / dt, robot_turns / dt, steps * batch * turns / dt, steps / cpu)
    return {"scenario": scenario, "batch": batch, "engine": "team-env", "opponents": opponents,
            "threads": len(env._ranges),
            "decisions_per_s": best[0] * batch * learners, "robot_turns_per_s": float(best[1]),
            "turns_per_s": best[2], "decisions_per_cpu_s": best[3] * batch * learners}


def scaling_plot(path: str, seconds: float) -> list[dict]:
    """Throughput against batch size at 1 and 2 threads (scripted 4v4, team env 4v4): the figure at ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    batches = (1, 4, 16, 64, 256, 1024)
    rows: list[dict] = []
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for threads in (1, 2):
        scripted = [sim_throughput("4v4", b, seconds, "engine", threads) for b in batches]
        team = [team_env("4v4", b, seconds, threads) for b in batches]
        for r in scripted + team:
            r["threads"] = threads
        rows += scripted + team
        axes[0].plot(batches, [r["robot_turns_per_s"] / 1e6 for r in scripted], "o-", label=f"{threads} thread(s)")
        axes[1].plot(batches, [r["decisions_per_s"] / 1e3 for r in team], "o-", label=f"{threads} thread(s)")
    axes[0].set_title("scripted 4v4 (sample robots)")
    axes[0].set_ylabel("alive robot-turns/s (M)")
    axes[1].set_title("TeamBattleEnv 4v4 vs SpinBot, T=10, random actions")
    axes[1].set_ylabel("learner decisions/s (k)")
    for ax in axes:
        ax.set_xscale("log", base=2)
        ax.set_xlabel("battles (batch)")
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle(f"confront simulator scaling (load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    return rows


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
    ap.add_argument("--turns-per-call", type=int, default=16,
                    help="turns of each ScriptedBots.play call (the bots workload); each call's first turn is slower")
    ap.add_argument("--no-engine", action="store_true", help="skip the real engine")
    ap.add_argument("--team-batches", default="64,256", help="batches of the team-env rows ('' for none)")
    ap.add_argument("--team-opponents", default="4v4:SpinBot",
                    help="SCENARIO:OPPONENT entries of the team-env rows, e.g. 1v1:SurfVG,4v4:OrbitGF")
    ap.add_argument("--plot", default=None, metavar="PNG", help="write the scaling figure (and print its rows)")
    args = ap.parse_args()
    if args.turns_per_call < 1:
        ap.error(f"--turns-per-call must be >= 1, got {args.turns_per_call}")
    if args.plot:
        rows = scaling_plot(args.plot, args.seconds)
        for r in rows:
            rate = r.get("decisions_per_s", r["robot_turns_per_s"])
            unit = "decisions/s" if "decisions_per_s" in r else "robot-turns/s"
            print(f"{r['engine']:<10} threads {r['threads']} batch {r['batch']:>5}: {rate:>14,.0f} {unit}")
        if args.json:
            print(json.dumps(rows))
        return
    rows: list[dict] = []
    entries = [e.partition(":") for e in args.team_opponents.split(",") if e]
    if any(not scen or not opp for scen, _, opp in entries):
        ap.error(f"--team-opponents takes SCENARIO:OPPONENT entries, got {args.team_opponents!r}")
    for sc in [v for v in args.scenarios.split(",") if v]:
        for b in BATCHES:
            rows.append(sim_throughput(sc, b, args.seconds, args.order, args.threads, args.workload,
                                       args.turns_per_call))
        rows.append(raw_step(sc, args.seconds, args.order))
        if not args.no_engine:
            rows.extend(engine_rows(sc))
    for scen, _, opp in entries:
        for b in [int(v) for v in args.team_batches.split(",") if v]:
            rows.append(team_env(scen, b, args.seconds, args.threads, opponents=opp))
    eng = {r["scenario"]: r["robot_turns_per_s"] for r in rows if r["engine"] == "robocode"}
    print(f"order={args.order}, threads={args.threads or 'all CPUs'}, {args.turns_per_call} turns a play() call, "
          f"load average {os.getloadavg()[0]:.1f}")
    print(f"{'scenario':<8} {'batch':>6} {'engine':<13} {'turns/s':>14} {'robot-turns/s':>15} {'x engine':>9}"
          f" {'per CPU-s':>13} {'decisions/s':>13}")
    for r in rows:
        ratio = r["robot_turns_per_s"] / eng[r["scenario"]] if r["scenario"] in eng else float("nan")
        dec = f"{r['decisions_per_s']:>13,.0f}" if "decisions_per_s" in r else ""
        # robot-turns (decisions for the team env) per second of the process's CPU time: steadier on a busy machine
        cpu = r.get("decisions_per_cpu_s", r.get("robot_turns_per_cpu_s"))
        per_cpu = f"{cpu:>13,.0f}" if cpu is not None else f"{'':>13}"
        engine = f"env:{r['opponents']}" if r["engine"] == "team-env" and r["opponents"] != "SpinBot" else r["engine"]
        print(f"{r['scenario']:<8} {r['batch']:>6} {engine:<13} {r['turns_per_s']:>14,.0f} "
              f"{r['robot_turns_per_s']:>15,.0f} {ratio:>9,.0f} {per_cpu} {dec}")
    if args.json:
        print(json.dumps(rows))


if __name__ == "__main__":
    main()
