"""Our PPO (``confront.learning.ppo``, one CleanRL-style file) against Stable-Baselines3's PPO on the same task:
the same league (PoolEnv, tank view, tank actions as a MultiDiscrete space, score-margin reward), the same
network (two tanh layers of ``--hidden``), rollout, epochs and minibatches, one torch thread each.

Prints, per library: decisions/s end to end (env + inference + update) and the greedy share per opponent after
the same number of decisions; then one JSON line. SB3 has no team critic and no per-agent activity mask: dead
tanks' steps are trained on as zero-reward transitions (ours drops them). No assertions (figures go to
docs/learning.md).
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from confront.experiments.spec import load_experiment
from confront.experiments.tanks import TankTrainer, build_pool, evaluate_tanks, ppo_config

LEAGUE = ["1v1:SpinBot", "1v1:Walls", "1v1:Tracker", "1v1:RamFire", "4v4:SpinBot", "4v4:dodge"]


def _cfg(hidden: int, battles: int):  # noqa: ANN202 - an ExperimentConfig
    return load_experiment("tanks-demo", [f"league.opponents={json.dumps(LEAGUE)}", f"league.battles={battles}",
                                          f"ppo.hidden={hidden}"])


def ours(decisions: int, hidden: int, battles: int, rounds: int) -> dict[str, object]:
    trainer = TankTrainer(_cfg(hidden, battles))
    trainer.update()  # warm-up: compiles the kernels in this process (the SB3 run after reuses them)
    d0, t0 = trainer.decisions, time.perf_counter()
    while trainer.decisions - d0 < decisions:
        trainer.update()
    wall = time.perf_counter() - t0
    res = evaluate_tanks(trainer.cfg, trainer.ppo, rounds)
    return {"library": "confront.learning.ppo", "decisions": trainer.decisions - d0, "wall_s": wall,
            "decisions_per_s": (trainer.decisions - d0) / wall, "share": {k: v["share"] for k, v in res.items()}}


def sb3(decisions: int, hidden: int, battles: int, rounds: int) -> dict[str, object]:
    import torch
    from gymnasium import spaces
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import Logger
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv

    torch.set_num_threads(1)
    cfg = _cfg(hidden, battles)
    pool, _ = build_pool(cfg, cfg.train.seed)
    pc = ppo_config(cfg)
    dims = pool.action_dims

    class PoolVecEnv(VecEnv):
        """Every league agent as one SB3 sub-environment (a done agent's next observation is its next step's)."""

        def __init__(self) -> None:
            obs_space = spaces.Box(-np.inf, np.inf, (pool.n_features,), np.float32)
            super().__init__(pool.n_agents, obs_space, spaces.MultiDiscrete(list(dims)))
            self.obs = pool.reset()
            self.decisions = 0

        def reset(self) -> np.ndarray:
            return self.obs

        def step_async(self, actions: np.ndarray) -> None:
            self._joint = np.ravel_multi_index(tuple(np.asarray(actions).T), dims)

        def step_wait(self):  # noqa: ANN202
            st = pool.step(self._joint)
            self.obs = st.obs
            self.decisions += int(st.active.sum())
            return st.obs, (st.reward * pc.reward_scale).astype(np.float32), st.done, [{} for _ in range(self.num_envs)]

        def close(self) -> None: ...
        def get_attr(self, attr_name, indices=None): return [None] * self.num_envs  # noqa: ANN001, ANN201, E704
        def set_attr(self, attr_name, value, indices=None): ...  # noqa: ANN001, ANN201, E704
        def env_method(self, *a, indices=None, **k): return [None] * self.num_envs  # noqa: ANN002, ANN003, ANN001, ANN201, E704
        def env_is_wrapped(self, wrapper_class, indices=None): return [False] * self.num_envs  # noqa: ANN001, ANN201, E704

    env = PoolVecEnv()
    n_steps = pc.rollout_steps
    model = PPO("MlpPolicy", env, learning_rate=pc.lr, n_steps=n_steps,
                batch_size=env.num_envs * n_steps // pc.minibatches, n_epochs=pc.epochs, gamma=pc.gamma,
                gae_lambda=pc.gae_lambda, clip_range=pc.clip, clip_range_vf=pc.clip, ent_coef=pc.ent_coef,
                vf_coef=pc.vf_coef, max_grad_norm=pc.max_grad_norm, seed=cfg.train.seed, device="cpu",
                policy_kwargs={"net_arch": [hidden, hidden], "activation_fn": torch.nn.Tanh}, verbose=0)
    model.set_logger(Logger(folder=None, output_formats=[]))
    t0 = time.perf_counter()
    from stable_baselines3.common.callbacks import BaseCallback

    class Budget(BaseCallback):
        def _on_step(self) -> bool:
            return env.decisions < decisions  # the same count as ours: steps of living tanks

    model.learn(total_timesteps=10 * decisions, callback=Budget())
    wall = time.perf_counter() - t0

    class Greedy:
        def act(self, obs: np.ndarray, critic_in: object = None, explore: bool = True):  # noqa: ANN201
            a, _ = model.predict(obs, deterministic=True)
            return (np.ravel_multi_index(tuple(np.asarray(a).T), dims),)

        def actor_arrays(self) -> dict[str, np.ndarray]:
            return {}

    res = evaluate_tanks(cfg, Greedy(), rounds)  # type: ignore[arg-type]
    return {"library": "stable-baselines3 PPO", "decisions": env.decisions, "wall_s": wall,
            "decisions_per_s": env.decisions / wall, "share": {k: v["share"] for k, v in res.items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--decisions", type=int, default=1_000_000)
    ap.add_argument("--hidden", type=int, default=128)
    ap.add_argument("--battles", type=int, default=16)
    ap.add_argument("--rounds", type=int, default=50, help="greedy evaluation rounds per opponent")
    args = ap.parse_args()
    rows = [ours(args.decisions, args.hidden, args.battles, args.rounds),
            sb3(args.decisions, args.hidden, args.battles, args.rounds)]
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; {args.decisions:,} decisions each")
    print("| library | decisions/s | wall (s) | " + " | ".join(LEAGUE) + " |")
    print("|---|---:|---:|" + "---:|" * len(LEAGUE))
    for r in rows:
        sh = r["share"]
        print(f"| {r['library']} | {r['decisions_per_s']:,.0f} | {r['wall_s']:.0f} | "  # type: ignore[index]
              + " | ".join(f"{sh[e]:.3f}" for e in LEAGUE) + " |")  # type: ignore[index]
    print(json.dumps({"bench": "ppo_libraries", "load": os.getloadavg()[0], "rows": rows}))


if __name__ == "__main__":
    main()
