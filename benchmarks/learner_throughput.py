"""Decisions plus updates per second of the learners (1 agent, and 4 agents x 256 battles), and the cost of
the fuzzy learning rate per element. Prints a table; no assertions."""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices: threads only add overhead

import numpy as np  # noqa: E402

from confront.learning import Transition, make_learner  # noqa: E402
from confront.learning.fuzzy import paper_learning_rate  # noqa: E402


def bench(kind: str, rows: int, seconds: float, sojourn: int, **params) -> tuple[float, float, float, int]:
    """Agent-updates (act + learn on ``rows`` agents per call) per wall second and per CPU second of this
    process (the latter is robust to other load on the machine), wall microseconds per call, calls."""
    rng = np.random.default_rng(0)
    lr = make_learner(kind, rng=np.random.default_rng(1), **params) if kind == "dmnn" else make_learner(
        kind, **params)
    n_pool = 64
    if lr.observation == "discrete":
        n_states = lr.params.n_inputs if kind == "dmnn" else lr.params.n_states
        pool = [rng.integers(0, n_states, rows) for _ in range(n_pool)]
    else:
        pool = [rng.uniform(-1, 1, (rows, lr.params.n_inputs)) for _ in range(n_pool)]
    rewards = [rng.standard_t(3, (rows, sojourn)) * 5 for _ in range(n_pool)]  # heavy-tailed, like Eq. 35
    done = [rng.random(rows) < 0.01 for _ in range(n_pool)]
    calls = 0
    c0 = time.process_time()
    t0 = time.perf_counter()
    while True:
        for _ in range(20):
            i = calls % n_pool
            obs = pool[i]
            a = lr.act(obs, rng)
            lr.learn(Transition(obs, a, rewards[i], pool[(i + 1) % n_pool], done[i]))
            calls += 1
        elapsed = time.perf_counter() - t0
        if elapsed >= seconds:
            break
    cpu = time.process_time() - c0
    return rows * calls / elapsed, rows * calls / cpu, 1e6 * elapsed / calls, calls


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=2.0, help="time per configuration")
    ap.add_argument("--sojourn", type=int, default=4, help="turns per SMDP step (reward columns)")
    args = ap.parse_args()
    configs = [
        ("ssaq", "SSAQ (tabular, paper backup)", {}),
        ("ssaq", "SSAQ + fuzzy rate", {"rate": "fuzzy"}),
        ("qlearning_egreedy", "TD team (tabular, e-greedy)", {}),
        ("dmnn", "DMNN 8-32-4, AWM", {"hidden": (32,)}),
        ("dmnn", "DMNN 8-32-4, AWM, fuzzy rate", {"hidden": (32,), "rate": "fuzzy"}),
        ("dmnn", "DMNN 8-32-4, AWM, float32", {"hidden": (32,), "dtype": "float32"}),
        ("dmnn", "DMNN 8-64-64-4, AWM", {"hidden": (64, 64)}),
        ("dmnn", "DMNN 8-64-64-4, AWM, float32", {"hidden": (64, 64), "dtype": "float32"}),
        ("dmnn", "DMNN 320(one-hot)-32-4", {"hidden": (32,), "observation": "discrete", "n_inputs": 320}),
    ]
    print(f"threads: OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}, load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"{'learner':<32} {'agents':>7} {'updates/wall-s':>15} {'updates/cpu-s':>14} {'us/call':>9} {'calls':>6}")
    for kind, name, params in configs:
        for rows, label in ((1, "1"), (1024, "4x256")):
            rate, cpu_rate, us, calls = bench(kind, rows, args.seconds, args.sojourn, **params)
            print(f"{name:<32} {label:>7} {rate:>15,.0f} {cpu_rate:>14,.0f} {us:>9.1f} {calls:>6}")
    x = np.random.default_rng(0).uniform(-40, 40, 1024)
    paper_learning_rate(x)
    n = 2000
    t0 = time.perf_counter()
    for _ in range(n):
        paper_learning_rate(x)
    ns = 1e9 * (time.perf_counter() - t0) / (n * x.size)
    print(f"fuzzy learning rate, batch of 1024: {ns:.1f} ns per element")


if __name__ == "__main__":
    main()
