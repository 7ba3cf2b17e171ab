"""CPU time of one PPO update per sample, by network width, epochs x minibatches and precision: the update's share of
the learner's budget (docs/learning.md, "Epochs and minibatches"). A rollout of 32 steps x 640 agents of
random tank views and actions (the league's sizes), on one torch thread and on two (``ppo.threads``, the default);
prints a table, then one JSON line."""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from confront.arena.tank import TankSpace
from confront.learning.ppo import PPO, Rollout
from confront.learning.ppo_config import PPOConfig

SETTINGS = ((128, 4, 4, "fp32"), (128, 4, 4, "bf16"), (128, 2, 2, "fp32"), (128, 2, 2, "bf16"), (64, 2, 4, "fp32"),
            (128, 1, 2, "fp32"))


def measure(hidden: int, epochs: int, minibatches: int, precision: str, steps: int, agents: int, repeats: int,
            threads: int) -> dict[str, float | str]:
    """Median CPU and wall time per sample of ``repeats`` updates after a warm-up one."""
    space = TankSpace()
    rng = np.random.default_rng(0)
    ppo = PPO(space.n_features, space.dims, PPOConfig(hidden=hidden, epochs=epochs, minibatches=minibatches,
                                                        rollout_steps=steps, threads=threads,
                                                        precision=precision), seed=0)
    obs = rng.standard_normal((steps, agents, space.n_features)).astype(np.float32)
    heads = np.stack([rng.integers(0, d, (steps, agents)) for d in space.dims], axis=2)
    ro = Rollout(obs, np.concatenate([obs, obs], axis=2), heads, np.full((steps, agents), -5.0, np.float32),
                 np.zeros((steps, agents), np.float32), rng.standard_normal((steps, agents)),
                 np.zeros((steps, agents), bool), np.ones((steps, agents), bool), np.zeros(agents, np.float32))
    ppo.update(ro)
    cpu, wall = [], []
    for _ in range(repeats):
        c, w = time.process_time(), time.perf_counter()
        ppo.update(ro)
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    n = steps * agents
    return {"hidden": hidden, "epochs": epochs, "minibatches": minibatches, "precision": precision, "threads": threads,
            "cpu_us_per_sample": float(np.median(cpu)) / n * 1e6,
            "wall_us_per_sample": float(np.median(wall)) / n * 1e6}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--steps", type=int, default=32)
    ap.add_argument("--agents", type=int, default=640)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    rows = [measure(h, e, m, p, args.steps, args.agents, args.repeats, t) for h, e, m, p in SETTINGS for t in (1, 2)]
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print("| hidden | epochs x minibatches | precision | threads | CPU us / sample | wall us / sample |\n"
          "|---:|---|---|---:|---:|---:|")
    for r in rows:
        print(f"| {r['hidden']} | {r['epochs']} x {r['minibatches']} | {r['precision']} | {r['threads']} | "
              f"{r['cpu_us_per_sample']:.1f} | {r['wall_us_per_sample']:.1f} |")
    print(json.dumps({"bench": "ppo_update", "load": os.getloadavg()[0], "rows": rows}))


if __name__ == "__main__":
    main()
