"""End-to-end training throughput of the recommended learner (PPO tanks against the league): agent-decisions
per second with the env, inference and updates all counted, and where the time goes. Prints a table, then
one JSON line. No assertions (figures go to docs/learning.md).

``--workers 0,1,2 [--address ray://HOST:PORT|auto]``: the scale-out rows instead, the config's league with 0
(the local path), 1 and 2 Ray rollout workers (``confront.train.ppo_ray``; without --address a local Ray of this
machine's CPUs), each with its peak resident memory: the driver's (``getrusage``, its children's included) and
each worker's own, summed."""

from __future__ import annotations

import argparse
import json
import os
import resource
import time
from collections.abc import Callable
from typing import Any

from confront.train.ppo_sim import TankTrainer
from confront.train.spec import load_experiment


def measure(opponents: list[str] | None, battles: int, updates: int, config: str = "tanks", overlap: bool = True,
            threads: int = 2, precision: str | None = None, workers: int = 0,
            address: str | None = None) -> dict[str, float | int | str]:
    """Run ``updates`` PPO updates after two warm-up ones (kernels compile; the first has no update before it);
    figures over the timed ones. ``opponents`` None: the config's own league (battles, focus) as it trains.
    ``workers`` > 0: the rollouts on that many Ray actors (``address``: the cluster, Ray already up if None)."""
    ov = [f"ppo.overlap={str(overlap).lower()}", f"ppo.threads={threads}"]
    if precision is not None:
        ov.append(f"ppo.precision={precision}")
    if opponents is not None:
        ov += [f"league.opponents={json.dumps(opponents)}", f"league.battles={battles}", "league.focus=[]"]
    cfg = load_experiment(config, ov)
    trainer: Any
    if workers:
        from confront.train.ppo_ray import RayTankTrainer

        trainer = RayTankTrainer(cfg, address or "auto", workers)
        agents = trainer.n_agents
    else:
        trainer = TankTrainer(cfg)
        agents = trainer.pool.n_agents
    try:
        trainer.update()  # warm-up: numba kernels, torch
        trainer.update()
        d0, t0, c0 = trainer.decisions, time.perf_counter(), time.process_time()
        env = upd = 0.0
        for _ in range(updates):
            row = trainer.update()
            env += row["env_fraction"]
            upd += row["update_wait_fraction"]
        wall = time.perf_counter() - t0
        n = trainer.decisions - d0
        worker_rss = 0
        if workers:
            import ray

            worker_rss = sum(ray.get([w.peak_rss_bytes.remote() for w in trainer.workers]))
    finally:
        trainer.close()
    league = ",".join(opponents) if opponents is not None else f"its own ({len(cfg.league.opponents)} entries)"
    return {"config": config, "overlap": overlap, "threads": threads, "precision": cfg.ppo.precision, "league": league,
            "agents": agents, "workers": workers,
            "decisions": n,
            "decisions_per_s": n / wall, "decisions_per_cpu_s": n / (time.process_time() - c0),
            "env_fraction": env / updates, "update_wait_fraction": upd / updates, "wall_s": wall,
            "driver_peak_rss_mib": _peak_rss() / 2**20, "workers_peak_rss_mib": worker_rss / 2**20}


def _peak_rss() -> int:
    """Peak resident bytes of this process and of its children that ended (Linux: ru_maxrss in KiB)."""
    return sum(resource.getrusage(who).ru_maxrss for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)) * 1024


def scale_out(args: argparse.Namespace) -> None:
    """The rows of --workers: one config, 0 / 1 / 2 ... rollout workers."""
    counts = [int(w) for w in args.workers.split(",")]
    if any(counts) and args.address is None:
        import ray

        ray.init(num_cpus=os.cpu_count(), include_dashboard=False, log_to_driver=False)
    rows = [measure(None, 0, args.updates, args.config, overlap=args.overlap, threads=args.threads,
                    precision=args.precision, workers=w, address=args.address) for w in counts]
    print_table(rows, 1, {
        "config": lambda r: r["config"], "rollout workers": lambda r: r["workers"] or "local",
        "agents": lambda r: r["agents"], "decisions/s": lambda r: f"{r['decisions_per_s']:,.0f}",
        "env (slowest worker)": lambda r: f"{r['env_fraction']:.0%}",
        "update (or waiting for it)": lambda r: f"{r['update_wait_fraction']:.0%}",
        "peak RSS driver": lambda r: f"{r['driver_peak_rss_mib']:,.0f} MiB",
        "peak RSS workers": lambda r: f"{r['workers_peak_rss_mib']:,.0f} MiB"})
    print(json.dumps({"bench": "train-scale-out", "load": os.getloadavg()[0], "rows": rows}))


def print_table(rows: list[dict[str, Any]], text_columns: int, columns: dict[str, Callable[[dict[str, Any]], Any]]
                ) -> None:
    """The load average, then a Markdown table: one column per ``columns`` entry (its header, the cell of a row),
    the first ``text_columns`` left-aligned."""
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * text_columns + "---:|" * (len(columns) - text_columns))
    for r in rows:
        print("| " + " | ".join(str(cell(r)) for cell in columns.values()) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--updates", type=int, default=20, help="timed updates per row (5 swung by 20-30%%)")
    ap.add_argument("--battles", type=int, default=16)
    ap.add_argument("--threads", type=int, default=2, help="ppo.threads (the update's torch threads)")
    ap.add_argument("--precision", choices=("fp32", "bf16"), help="ppo.precision (default: each config's own)")
    ap.add_argument("--no-overlap", action="store_true", help="only the sequential schedule (the default one)")
    ap.add_argument("--workers", metavar="N,N,...", help="scale-out rows instead: these rollout worker counts "
                    "(0: the local path), e.g. 0,1,2")
    ap.add_argument("--address", help="with --workers: the Ray cluster (ray://HOST:PORT or auto; default a local Ray)")
    ap.add_argument("--config", default="tanks", help="with --workers: the config whose league trains")
    ap.add_argument("--overlap", action="store_true", help="with --workers: ppo.overlap (workers act one update "
                    "behind while the driver updates)")
    args = ap.parse_args()
    if args.workers is not None:
        return scale_out(args)
    league = ["1v1:SpinBot", "1v1:Walls", "1v1:Tracker", "1v1:RamFire", "1v1:Crazy"]
    teams = ["4v4:SpinBot", "4v4:Walls", "4v4:dodge", "4v4:self"]
    rows = []
    kw = {"threads": args.threads, "precision": args.precision}
    # collect, then update (the default); or the update beside the next rollout
    for overlap in (False,) if args.no_overlap else (False, True):
        rows += [measure(None, 0, args.updates, overlap=overlap, **kw),
                 measure(None, 0, args.updates, "tanks-demo", overlap=overlap, **kw),
                 measure(league, args.battles * 2, args.updates, overlap=overlap, **kw),
                 measure(teams, args.battles, args.updates, overlap=overlap, **kw)]
    print_table(rows, 4, {
        "config": lambda r: r["config"], "overlap": lambda r: r["overlap"], "precision": lambda r: r["precision"],
        "league": lambda r: r["league"], "agents": lambda r: r["agents"],
        "decisions/s": lambda r: f"{r['decisions_per_s']:,.0f}",
        "decisions/CPU-s": lambda r: f"{r['decisions_per_cpu_s']:,.0f}", "env": lambda r: f"{r['env_fraction']:.0%}",
        "update (or waiting for it)": lambda r: f"{r['update_wait_fraction']:.0%}"})
    print(json.dumps({"bench": "train", "load": os.getloadavg()[0], "rows": rows}))


if __name__ == "__main__":
    main()
