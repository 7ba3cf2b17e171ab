"""Throughput of the environments: Gymnasium step() calls/s, the vector env's and the SMDP team env's rates.

Usage: ``python benchmarks/env_throughput.py [--seconds 2] [--json] [--pool-only]``. ``gym`` and ``vector`` rows
are labelled with their view (``paper``: the paper's spaces; ``tank``: the tank view and head actions, T = 5;
random actions from the action space). Prints a table; with
``--json`` the last line is a JSON list of records (``env``, ``scenario``, ``batch``, ``turns_per_step``,
``steps_per_s`` (step() calls), ``env_steps_per_s`` (battles x steps), ``turns_per_s``, ``robot_turns_per_s``,
``steps_per_cpu_s`` (step() calls per second of the process' CPU time: with threads above the wall rate,
on a busy machine a steadier figure for single-threaded rows)).

``pool`` rows time ``PoolEnv.step`` alone (the PPO tanks' environment: tank view, tank actions, score
reward, T = 5) over the league of ``confront/train/configs/tanks-demo.toml`` (5 entries x 24 battles)
and ``tanks.toml`` (22 entries x 12), random joint tank actions; ``batch`` = agents (learning tanks),
``steps_per_s`` x batch = learner decisions per second. The caller-driven opponents run their Python
policies (dodge, strafe; a random-weight snapshot for ``self``), except the TD team: random paper moves
(training it would take minutes).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

from confront.arena import gym_env  # noqa: F401 - registers confront/Battle-v0
from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.vector_env import BattleVectorEnv

CPU_RATES: list[float] = []  # step() calls per second of this process' CPU time, one per _rate call


def _rate(step: Callable[[int], None], seconds: float) -> float:
    """step() calls per wall-clock second over about ``seconds`` (after a warm-up); the rate per CPU second
    (less sensitive to other processes on a busy machine) goes to CPU_RATES."""
    for i in range(20):
        step(i)
    n, t0, c0 = 0, time.perf_counter(), time.process_time()
    while True:
        for _ in range(10):
            step(n)
            n += 1
        dt = time.perf_counter() - t0
        if dt >= seconds:
            CPU_RATES.append(n / max(time.process_time() - c0, 1e-9))
            return n / dt


def bench_gym(scenario: str, opponents: str, turns: int, seconds: float, view: str = "paper") -> dict:
    env = gym.make("confront/Battle-v0", scenario=scenario, opponents=opponents, turns_per_step=turns,
                   disable_env_checker=True, view=view).unwrapped
    env.reset(seed=0)
    acts = [env.action_space.sample() for _ in range(64)]

    def step(i: int) -> None:
        _, _, term, trunc, _ = env.step(acts[i % 64])
        if term or trunc:
            env.reset()

    r = _rate(step, seconds)
    n = env.team_env.n_robots
    return {"env": f"gym/{view}", "scenario": scenario, "batch": 1, "turns_per_step": turns, "steps_per_s": r,
            "env_steps_per_s": r, "turns_per_s": r * turns, "robot_turns_per_s": r * turns * n}


def bench_vector(scenario: str, opponents: str, batch: int, turns: int, seconds: float, view: str = "paper") -> dict:
    env = BattleVectorEnv(batch, scenario, opponents, turns_per_step=turns, seed=0, view=view)
    env.reset(seed=0)
    acts = [env.action_space.sample() for _ in range(64)]

    def step(i: int) -> None:
        env.step(acts[i % 64])

    r = _rate(step, seconds)
    n = env._driver.env.n_robots
    return {"env": f"vector/{view}", "scenario": scenario, "batch": batch, "turns_per_step": turns, "steps_per_s": r,
            "env_steps_per_s": r * batch, "turns_per_s": r * batch * turns,
            "robot_turns_per_s": r * batch * turns * n}


def bench_team(scenario: str, opponents: str, batch: int, turns: int, seconds: float) -> dict:
    env = TeamBattleEnv(scenario, batch, seed=0, opponents=opponents, config=SMDPConfig(turns_per_step=turns))
    env.reset()
    acts = np.random.default_rng(0).integers(0, 4, size=(64, batch, env.n_robots))

    def step(i: int) -> None:
        env.step(acts[i % 64])

    r = _rate(step, seconds)
    n = env.n_robots
    return {"env": "team", "scenario": scenario, "batch": batch, "turns_per_step": turns, "steps_per_s": r,
            "env_steps_per_s": r * batch, "turns_per_s": r * batch * turns,
            "robot_turns_per_s": r * batch * turns * n}


def _league_pool(config: str):  # noqa: ANN202 - a PoolEnv
    """The PoolEnv of an experiment config's league (see the module docstring)."""
    from confront.arena.pool import PoolEntry, PoolEnv
    from confront.train import league
    from confront.train.ppo_model import smdp_tank_config, tank_space
    from confront.train.spec import load_experiment

    cfg = load_experiment(config)
    space = tank_space(cfg)
    snap = league.SnapshotPolicy(space.dims)
    rng = np.random.default_rng(0)
    sizes = [space.n_features, 64, 64, sum(space.dims)]
    snap.load({f"{w}{i}": (rng.normal(0, 0.1, (sizes[i + 1], sizes[i])) if w == "w" else np.zeros(sizes[i + 1]))
               for i in range(3) for w in "wb"})
    policies = {"td": league.random_policy, "random": league.random_policy, "dodge": league.dodge_policy,
                "strafe": league.strafe_policy(space), "self": snap}
    entries = []
    for e in cfg.league.opponents:
        scen, _, opp = e.partition(":")
        pol = policies.get(opp)
        entries.append(PoolEntry(e, scen, "td" if pol is not None else opp, cfg.league.battles, policy=pol,
                                 opponent_actions="paper" if opp in ("td", "random", "dodge") else "same"))
    return PoolEnv(entries, smdp_tank_config(cfg), seed=0)


def bench_pool(config: str, seconds: float) -> dict:
    pool = _league_pool(config)
    pool.reset()
    acts = np.random.default_rng(0).integers(0, int(np.prod(pool.action_dims)), size=(64, pool.n_agents))

    def step(i: int) -> None:
        pool.step(acts[i % 64])

    r = _rate(step, seconds)
    turns = pool.envs[0].turns_per_step
    robots = sum(env.n_battles * env.n_robots for env in pool.envs)
    return {"env": "pool", "scenario": config, "batch": pool.n_agents, "turns_per_step": turns, "steps_per_s": r,
            "env_steps_per_s": r * sum(env.n_battles for env in pool.envs),
            "turns_per_s": r * turns * sum(env.n_battles for env in pool.envs),
            "robot_turns_per_s": r * turns * robots}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=2.0, help="measuring time per row")
    ap.add_argument("--json", action="store_true", help="print the records as JSON on the last line")
    ap.add_argument("--pool-only", action="store_true", help="only the PoolEnv rows (the PPO tanks' leagues)")
    args = ap.parse_args()
    s = args.seconds
    pools = [bench_pool("tanks-demo", s), bench_pool("tanks", s)]
    rows = [] if args.pool_only else [
        bench_gym("1v1", "SpinBot", 10, s),
        bench_gym("1v1", "SpinBot", 1, s),
        bench_gym("4v4", "SpinBot", 10, s),
        bench_vector("1v1", "SpinBot", 64, 10, s),
        bench_vector("1v1", "SpinBot", 256, 10, s),
        bench_gym("1v1", "SpinBot", 5, s, view="tank"),
        bench_vector("1v1", "SpinBot", 256, 5, s, view="tank"),
        bench_vector("4v4", "SpinBot", 64, 5, s, view="tank"),
        bench_team("4v4", "td", 1, 10, s),
        bench_team("4v4", "td", 64, 10, s),
        bench_team("4v4", "td", 256, 10, s),
        bench_team("4v4", "SpinBot", 256, 10, s),
        bench_team("4v10", "td", 256, 10, s),
    ]
    CPU_RATES[:] = CPU_RATES[2:] + CPU_RATES[:2]  # the pool rows were measured first
    rows += pools
    for r, cpu in zip(rows, CPU_RATES, strict=True):
        r["steps_per_cpu_s"] = cpu
    print(f"load average {os.getloadavg()[0]:.1f}; pool rows: batch = learning tanks, decisions/s = step()/s x batch")
    head = f"{'env':<13}{'scenario':<11}{'batch':>6}{'T':>4}{'step()/s':>12}{'env-steps/s':>14}{'turns/s':>13}" \
           f"{'robot-turns/s':>16}{'step()/cpu-s':>14}"
    print(head)
    print("-" * len(head))
    for r in rows:
        print(f"{r['env']:<13}{r['scenario']:<11}{r['batch']:>6}{r['turns_per_step']:>4}{r['steps_per_s']:>12,.0f}"
              f"{r['env_steps_per_s']:>14,.0f}{r['turns_per_s']:>13,.0f}{r['robot_turns_per_s']:>16,.0f}"
              f"{r['steps_per_cpu_s']:>14,.0f}")
    if args.json:
        print(json.dumps(rows))


if __name__ == "__main__":
    main()
