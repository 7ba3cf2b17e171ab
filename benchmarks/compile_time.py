"""First-use compile time of `confront demo`: CPU and wall seconds before training starts, with an empty numba
cache and with a warm one (docs/arena.md, "First-use compile time").

Each run is a fresh Python process (``--child``) that imports the trainer, builds the demo's league
(``TankTrainer(load_experiment("tanks-demo"))``: pool, reset, PPO) and runs the first rollout (S pool steps; the
first rollout has no PPO update before it), with ``NUMBA_CACHE_DIR`` a temporary folder: empty for the cold runs,
the same folder again for the warm ones. The TD team comes from confront's cache as usual (``--fresh-td``: an
empty ``CONFRONT_CACHE`` too, so its pre-training is timed as on a fresh machine).

Then the run time of the shipped kernels against kernels compiled here (``--runtime K`` pairs of processes, in
turn, one thread each; 0 skips it): CPU microseconds per alive robot-turn of scripted 4v4 x 256
(``ScriptedBots.play``) and CPU milliseconds per ``TeamBattleEnv`` step (4v4 x 256 against SpinBot: paper
observations, T = 10; the tank view and score reward, T = 5), best of 15 timings in each process.

Usage: python benchmarks/compile_time.py [--repeats 3] [--runtime 4] [--top 15] [--fresh-td]
Prints tables of medians (CPU = user + system of the process) and the compiled functions of the last cold-compile
run (exclusive CPU seconds of each compile); the last line is one JSON record.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections import defaultdict
from pathlib import Path


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _sys() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_stime


def child() -> None:
    """One start-up of the demo's trainer; prints one JSON record of its phases and compiles."""
    t0, c0 = time.perf_counter(), _cpu()
    from numba.core import event

    stacks: dict[int, list[list]] = defaultdict(list)
    excl: dict[str, float] = defaultdict(float)
    incl: dict[str, float] = defaultdict(float)
    count: dict[str, int] = defaultdict(int)

    class Compiles(event.Listener):
        """Thread CPU seconds of each numba compile, without the compiles nested in it."""

        def on_start(self, ev: event.Event) -> None:
            f = ev.data["dispatcher"].py_func
            stacks[threading.get_ident()].append([f"{f.__module__}.{f.__qualname__}", time.thread_time(), 0.0])

        def on_end(self, ev: event.Event) -> None:
            st = stacks[threading.get_ident()]
            name, start, nested = st.pop()
            dt = time.thread_time() - start
            incl[name] += dt
            excl[name] += dt - nested
            count[name] += 1
            if st:
                st[-1][2] += dt

    event.register("numba:compile", Compiles())
    from confront.train.ppo_sim import TankTrainer
    from confront.train.spec import load_experiment

    t1, c1 = time.perf_counter(), _cpu()
    trainer = TankTrainer(load_experiment("tanks-demo", ()))
    t2, c2 = time.perf_counter(), _cpu()
    trainer.update()
    t3, c3, s3 = time.perf_counter(), _cpu(), _sys()
    trainer.close()
    funcs = sorted(({"name": k, "compiles": count[k], "excl_cpu_s": round(excl[k], 3), "incl_cpu_s": round(incl[k], 3)}
                    for k in excl), key=lambda r: -r["excl_cpu_s"])
    print(json.dumps({"import_cpu_s": c1 - c0, "import_wall_s": t1 - t0, "build_cpu_s": c2 - c1,
                      "build_wall_s": t2 - t1, "rollout_cpu_s": c3 - c2, "rollout_wall_s": t3 - t2, "cpu_s": c3 - c0,
                      "sys_s": s3, "wall_s": t3 - t0, "compile_cpu_s": sum(excl.values()), "functions": funcs}))


def runtime_child() -> None:
    """CPU per unit of work of the kernels this process loads; prints one JSON record."""
    import numba
    import numpy as np

    numba.set_num_threads(1)
    from confront.arena.bots import ScriptedBots
    from confront.arena.core import Arena
    from confront.arena.smdp import SMDPConfig, TeamBattleEnv
    from confront.arena.tank import TankSpace

    def best(work: object, repeats: int = 15) -> float:
        times = []
        for _ in range(repeats):
            c0 = time.process_time()
            units = work()  # type: ignore[operator]
            times.append((time.process_time() - c0) / units)
        return min(times)

    out = {}
    arena = Arena("4v4", 256, seed=1, threads=1)
    bots = ScriptedBots(arena, ["SpinBot", "Walls", "Tracker", "RamFire", "Walls", "Tracker", "Crazy", "Fire"])
    bots.play(16)
    out["play_us_per_robot_turn"] = best(lambda: bots.play(32)) * 1e6
    for name, cfg in (("team_env_paper_ms", SMDPConfig(turns_per_step=10)),
                      ("team_env_tank_ms", SMDPConfig(turns_per_step=5, tank=TankSpace(), reward="score"))):
        env = TeamBattleEnv("4v4", 256, seed=1, opponents="SpinBot", config=cfg)
        env.reset()
        acts = np.random.default_rng(0).integers(0, 4, size=(16, 256, env.n_robots))
        env.step(acts[0])

        def steps(env: TeamBattleEnv = env, acts: np.ndarray = acts) -> int:
            for k in range(3):
                env.step(acts[k])
            return 3

        out[name] = best(steps) * 1e3
    print(json.dumps(out))


def run_child(env: dict[str, str], flag: str = "--child") -> dict:
    """One child process; its record and its CPU seconds as the OS counted them (until exit)."""
    k0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, __file__, flag], env=env, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    k1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    rec = json.loads(out.stdout.strip().splitlines()[-1])
    rec["process_cpu_s"] = (k1.ru_utime + k1.ru_stime) - (k0.ru_utime + k0.ru_stime)
    rec["process_wall_s"] = wall
    return rec


MODES = {"cold": "empty numba cache, shipped kernels", "cold-compile": "empty numba cache, CONFRONT_PREBUILT_KERNELS=0",
         "warm": "numba cache of the cold-compile run"}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=3, help="runs of each mode (medians are printed)")
    p.add_argument("--runtime", type=int, default=4, help="pairs of run-time processes (shipped / compiled here)")
    p.add_argument("--top", type=int, default=15, help="compiled functions listed (of the last cold-compile run)")
    p.add_argument("--fresh-td", action="store_true", help="an empty CONFRONT_CACHE too (TD team pre-trained)")
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--runtime-child", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args()
    if a.child:
        child()
        return
    if a.runtime_child:
        runtime_child()
        return
    runs: dict[str, list[dict]] = {m: [] for m in MODES}
    tmp = tempfile.mkdtemp()
    try:
        for k in range(a.repeats):
            env = dict(os.environ, NUMBA_CACHE_DIR=str(Path(tmp) / f"shipped{k}"))
            if a.fresh_td:
                env["CONFRONT_CACHE"] = str(Path(tmp) / f"confront-shipped{k}")
            runs["cold"].append(run_child(env))
            env = dict(os.environ, NUMBA_CACHE_DIR=str(Path(tmp) / f"here{k}"), CONFRONT_PREBUILT_KERNELS="0")
            if a.fresh_td:
                env["CONFRONT_CACHE"] = str(Path(tmp) / f"confront-here{k}")
            runs["cold-compile"].append(run_child(env))
            runs["warm"].append(run_child(env))
        runtime = runtime_ab(a.runtime, Path(tmp) / "shipped0", Path(tmp) / f"here{a.repeats - 1}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    keys = ("cpu_s", "sys_s", "wall_s", "compile_cpu_s", "import_cpu_s", "build_cpu_s", "rollout_cpu_s",
            "process_cpu_s", "process_wall_s")
    med = {m: {k: statistics.median(r[k] for r in rs) for k in keys} for m, rs in runs.items()}
    print(f"confront demo start-up (tanks-demo: import, build the league, first rollout), median of {a.repeats}, "
          f"load {os.getloadavg()[0]:.1f}")
    print(f"{'mode':13s} {'CPU s':>6s} {'(sys)':>5s} {'wall s':>6s} {'compile':>7s} {'import':>6s} {'build':>6s} "
          f"{'rollout':>7s} {'process CPU':>11s}  numba cache")
    for m, r in med.items():
        print(f"{m:13s} {r['cpu_s']:6.1f} {r['sys_s']:5.1f} {r['wall_s']:6.1f} {r['compile_cpu_s']:7.1f} "
              f"{r['import_cpu_s']:6.1f} {r['build_cpu_s']:6.1f} {r['rollout_cpu_s']:7.1f} {r['process_cpu_s']:11.1f}"
              f"  {MODES[m]}")
    if runtime:
        print(f"\nrun time, median of {a.runtime} processes each, in turn (CPU per unit, one thread)")
        print(f"{'':24s} {'shipped':>8s} {'compiled here':>13s} {'ratio':>6s}")
        for k, r in runtime["median"].items():
            print(f"{k:24s} {r['shipped']:8.3f} {r['here']:13.3f} {r['shipped'] / r['here']:6.3f}")
    print("\ncompiled in the last cold-compile run (CPU s of each compile without the compiles nested in it)")
    print(f"{'function':52s} {'compiles':>8s} {'excl s':>7s} {'incl s':>7s}")
    top = runs["cold-compile"][-1]["functions"][: a.top]
    for f in top:
        print(f"{f['name']:52s} {f['compiles']:8d} {f['excl_cpu_s']:7.2f} {f['incl_cpu_s']:7.2f}")
    print(json.dumps({"repeats": a.repeats, "load": os.getloadavg()[0], "median": med,
                      **{f"{m}_cpu_s": [r["cpu_s"] for r in rs] for m, rs in runs.items()}, "runtime": runtime,
                      "functions": top}))


def runtime_ab(pairs: int, shipped: Path, here: Path) -> dict:
    """Run-time processes with the shipped kernels and with those compiled here, in turn (after one of each to
    fill the caches); medians of each measure."""
    if pairs <= 0:
        return {}
    envs = {"shipped": dict(os.environ, NUMBA_CACHE_DIR=str(shipped)),
            "here": dict(os.environ, NUMBA_CACHE_DIR=str(here), CONFRONT_PREBUILT_KERNELS="0")}
    for env in envs.values():
        run_child(env, "--runtime-child")
    recs: dict[str, list[dict]] = {k: [] for k in envs}
    for _ in range(pairs):
        for k, env in envs.items():
            recs[k].append(run_child(env, "--runtime-child"))
    keys = [k for k in recs["here"][0] if not k.startswith("process_")]
    med = {k: {m: statistics.median(r[k] for r in rs) for m, rs in recs.items()} for k in keys}
    return {"median": med, "runs": {m: [{k: r[k] for k in keys} for r in rs] for m, rs in recs.items()}}


if __name__ == "__main__":
    main()
