"""Our PPO (``confront.learning.ppo``, one CleanRL-style file) against Stable-Baselines3's PPO and TorchRL's PPO
pieces on the same task: the same league (PoolEnv, tank view, tank actions as a MultiDiscrete space / per-head
categoricals, score-margin reward), the same network (two tanh layers of ``--hidden``), rollout, epochs and
minibatches, one torch thread each. The libraries: ``pip install -e '.[baselines]'`` (SB3) and ``pip install -e
'.[torchrl]'`` (TorchRL 0.14.1); ``--libraries`` picks the rows and their order.

Prints, per library: decisions/s end to end (env + inference + update), per wall second and per CPU-second of
the process (the machine is shared), and the greedy share per opponent after the same number of decisions; then
one JSON line. SB3 and TorchRL have no team critic and no per-agent activity mask here: dead tanks' steps are
trained on as zero-reward transitions (ours drops them). No assertions (figures go to docs/learning.md).
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from confront.experiments.tank_evaluate import evaluate_tanks
from confront.train.league import build_pool
from confront.train.ppo_sim import TankTrainer
from confront.train.spec import load_experiment

LEAGUE = ["1v1:SpinBot", "1v1:Walls", "1v1:Tracker", "1v1:RamFire", "4v4:SpinBot", "4v4:dodge"]


def _cfg(hidden: int, battles: int):  # noqa: ANN202 - an ExperimentConfig
    return load_experiment("tanks-demo", [f"league.opponents={json.dumps(LEAGUE)}", f"league.battles={battles}",
                                          f"ppo.hidden={hidden}"])


def ours(decisions: int, hidden: int, battles: int, rounds: int) -> dict[str, object]:
    trainer = TankTrainer(_cfg(hidden, battles))
    trainer.update()  # warm-up: compiles the kernels in this process (the SB3 run after reuses them)
    d0, t0, c0 = trainer.decisions, time.perf_counter(), time.process_time()
    while trainer.decisions - d0 < decisions:
        trainer.update()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    res = evaluate_tanks(trainer.cfg, trainer.ppo, rounds)
    return {"library": "confront.learning.ppo", "decisions": trainer.decisions - d0, "wall_s": wall, "cpu_s": cpu,
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
    pc = cfg.ppo
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
    t0, c0 = time.perf_counter(), time.process_time()
    from stable_baselines3.common.callbacks import BaseCallback

    class Budget(BaseCallback):
        def _on_step(self) -> bool:
            return env.decisions < decisions  # the same count as ours: steps of living tanks

    model.learn(total_timesteps=10 * decisions, callback=Budget())
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0

    class Greedy:
        def act(self, obs: np.ndarray, critic_in: object = None, explore: bool = True):  # noqa: ANN201
            a, _ = model.predict(obs, deterministic=True)
            return (np.ravel_multi_index(tuple(np.asarray(a).T), dims),)

        def actor_arrays(self) -> dict[str, np.ndarray]:
            return {}

    res = evaluate_tanks(cfg, Greedy(), rounds)  # type: ignore[arg-type]
    return {"library": "stable-baselines3 PPO", "decisions": env.decisions, "wall_s": wall, "cpu_s": cpu,
            "decisions_per_s": env.decisions / wall, "share": {k: v["share"] for k, v in res.items()}}


def torchrl(decisions: int, hidden: int, battles: int, rounds: int) -> dict[str, object]:
    """TorchRL's PPO pieces (``pip install -e '.[torchrl]'``): an ``EnvBase`` over the league (every agent one
    batch entry, the action heads one ``MultiCategorical`` spec), a ``ProbabilisticActor`` over a per-head
    categorical, a ``ValueOperator``, its ``Collector``, ``GAE``, ``ClipPPOLoss`` and a replay buffer sampling
    the rollout without replacement. Like the SB3 row: no team critic, dead tanks' steps are trained on."""
    import torch
    from tensordict import TensorDict
    from tensordict.nn import TensorDictModule
    from torch import nn
    from torch.distributions import Categorical, Distribution
    from torchrl.collectors import Collector
    from torchrl.data import Categorical as CategoricalSpec
    from torchrl.data import Composite, LazyTensorStorage, MultiCategorical, ReplayBuffer, Unbounded
    from torchrl.data.replay_buffers.samplers import SamplerWithoutReplacement
    from torchrl.envs import EnvBase
    from torchrl.envs.utils import ExplorationType, set_exploration_type
    from torchrl.modules import MLP, ProbabilisticActor, ValueOperator
    from torchrl.objectives import ClipPPOLoss
    from torchrl.objectives.value import GAE

    torch.set_num_threads(1)
    cfg = _cfg(hidden, battles)
    pool, _ = build_pool(cfg, cfg.train.seed)
    pc = cfg.ppo
    dims = pool.action_dims
    n = pool.n_agents
    torch.manual_seed(cfg.train.seed)

    class PoolTorchEnv(EnvBase):
        """Every league agent as one batch entry; the pool resets finished rounds itself, so ``_reset`` only
        hands back the current observations."""

        def __init__(self) -> None:
            super().__init__(batch_size=torch.Size([n]))
            self.observation_spec = Composite(observation=Unbounded((n, pool.n_features)), shape=(n,))
            self.action_spec = MultiCategorical(list(dims), shape=(n, len(dims)))
            self.reward_spec = Unbounded((n, 1))
            self.done_spec = Composite(done=CategoricalSpec(2, (n, 1), dtype=torch.bool),
                                       terminated=CategoricalSpec(2, (n, 1), dtype=torch.bool), shape=(n,))
            self.obs = torch.from_numpy(pool.reset())
            self.decisions = 0

        def _reset(self, td: TensorDict | None = None, **kwargs: object) -> TensorDict:
            done = torch.zeros(n, 1, dtype=torch.bool)
            return TensorDict(observation=self.obs, done=done, terminated=done.clone(), batch_size=self.batch_size)

        def _step(self, td: TensorDict) -> TensorDict:
            st = pool.step(np.ravel_multi_index(tuple(td["action"].numpy().T), dims))
            self.obs = torch.from_numpy(st.obs)
            self.decisions += int(st.active.sum())
            done = torch.from_numpy(st.done)[:, None]
            return TensorDict(observation=self.obs, done=done, terminated=done.clone(), batch_size=self.batch_size,
                              reward=torch.from_numpy((st.reward * pc.reward_scale).astype(np.float32))[:, None])

        def _set_seed(self, seed: int | None) -> None: ...

    class Heads(Distribution):
        """Independent categoricals over the action heads' logits (the MultiDiscrete of the other rows)."""

        arg_constraints: dict = {}

        def __init__(self, logits: torch.Tensor) -> None:
            self.heads = [Categorical(logits=z) for z in logits.split(list(dims), dim=-1)]
            super().__init__(logits.shape[:-1], validate_args=False)

        def sample(self, sample_shape: torch.Size = torch.Size()) -> torch.Tensor:  # noqa: B008
            return torch.stack([h.sample(sample_shape) for h in self.heads], dim=-1)

        def log_prob(self, a: torch.Tensor) -> torch.Tensor:
            return sum(h.log_prob(a[..., i]) for i, h in enumerate(self.heads))  # type: ignore[return-value]

        def entropy(self) -> torch.Tensor:
            return sum(h.entropy() for h in self.heads)  # type: ignore[return-value]

        @property
        def deterministic_sample(self) -> torch.Tensor:  # greedy: per-head argmax
            return torch.stack([h.logits.argmax(dim=-1) for h in self.heads], dim=-1)

    def mlp(n_out: int, gain: float) -> nn.Module:  # 128-128 tanh, orthogonal init (CleanRL's, SB3's, ours)
        net = MLP(in_features=pool.n_features, out_features=n_out, num_cells=[hidden, hidden],
                  activation_class=nn.Tanh)
        layers = [m for m in net if isinstance(m, nn.Linear)]
        for layer, g in zip(layers, (np.sqrt(2), np.sqrt(2), gain), strict=True):
            nn.init.orthogonal_(layer.weight, g)
            nn.init.zeros_(layer.bias)
        return net

    env = PoolTorchEnv()
    actor = ProbabilisticActor(TensorDictModule(mlp(sum(dims), 0.01), ["observation"], ["logits"]), ["logits"],
                               spec=env.action_spec, distribution_class=Heads, return_log_prob=True)
    critic = ValueOperator(mlp(1, 1.0), in_keys=["observation"])
    gae = GAE(gamma=pc.gamma, lmbda=pc.gae_lambda, value_network=critic)
    loss = ClipPPOLoss(actor, critic, clip_epsilon=pc.clip, entropy_coeff=pc.ent_coef, critic_coeff=pc.vf_coef,
                       loss_critic_type="l2", normalize_advantage=True, clip_value=pc.clip)
    opt = torch.optim.Adam(loss.parameters(), lr=pc.lr, eps=1e-5)
    batch = n * pc.rollout_steps
    buffer = ReplayBuffer(storage=LazyTensorStorage(batch), sampler=SamplerWithoutReplacement(),
                          batch_size=batch // pc.minibatches)
    collector = Collector(env, actor, frames_per_batch=batch, auto_register_policy_transforms=False)

    def update(data: TensorDict) -> None:
        with torch.no_grad():
            gae(data)
        for _ in range(pc.epochs):
            buffer.extend(data.reshape(-1))
            for _ in range(pc.minibatches):
                out = loss(buffer.sample())
                opt.zero_grad()
                (out["loss_objective"] + out["loss_critic"] + out["loss_entropy"]).backward()
                nn.utils.clip_grad_norm_(loss.parameters(), pc.max_grad_norm)
                opt.step()

    rollouts = iter(collector)
    update(next(rollouts))  # warm-up, untimed as ours: TorchRL sets itself up on the first rollout and update
    d0, t0, c0 = env.decisions, time.perf_counter(), time.process_time()
    for data in rollouts:
        update(data)
        if env.decisions - d0 >= decisions:
            break
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    collector.shutdown()

    class Greedy:
        @torch.no_grad()
        def act(self, obs: np.ndarray, critic_in: object = None, explore: bool = True):  # noqa: ANN201
            with set_exploration_type(ExplorationType.DETERMINISTIC):
                a = actor(TensorDict(observation=torch.from_numpy(obs), batch_size=[len(obs)]))["action"]
            return (np.ravel_multi_index(tuple(a.numpy().T), dims),)

        def actor_arrays(self) -> dict[str, np.ndarray]:
            return {}

    res = evaluate_tanks(cfg, Greedy(), rounds)  # type: ignore[arg-type]
    return {"library": "TorchRL PPO", "decisions": env.decisions - d0, "wall_s": wall, "cpu_s": cpu,
            "decisions_per_s": (env.decisions - d0) / wall, "share": {k: v["share"] for k, v in res.items()}}


ROWS = {"ours": ours, "sb3": sb3, "torchrl": torchrl}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--decisions", type=int, default=1_000_000)
    ap.add_argument("--hidden", type=int, default=128)
    ap.add_argument("--battles", type=int, default=16)
    ap.add_argument("--rounds", type=int, default=50, help="greedy evaluation rounds per opponent")
    ap.add_argument("--libraries", default="ours,sb3,torchrl", help="the rows, in this order (comma-separated)")
    args = ap.parse_args()
    pool, _ = build_pool(_cfg(args.hidden, args.battles), 0)  # warm-up: the simulator's kernels, for every row
    pool.reset()
    for _ in range(2):
        pool.step(np.zeros(pool.n_agents, dtype=np.int64))
    rows = []
    for name in args.libraries.split(","):
        rows.append(ROWS[name](args.decisions, args.hidden, args.battles, args.rounds))
        rows[-1]["load"] = os.getloadavg()[0]  # the 1-minute load average as the row ends
    print(f"{os.cpu_count()} cores; {args.decisions:,} decisions each")
    print("| library (load) | decisions/s | decisions/CPU-s | wall (s) | " + " | ".join(LEAGUE) + " |")
    print("|---|---:|---:|---:|" + "---:|" * len(LEAGUE))
    for r in rows:
        sh = r["share"]
        print(f"| {r['library']} ({r['load']:.1f}) | {r['decisions_per_s']:,.0f} | "  # type: ignore[index]
              f"{r['decisions'] / r['cpu_s']:,.0f} | {r['wall_s']:.0f} | "  # type: ignore[operator]
              + " | ".join(f"{sh[e]:.3f}" for e in LEAGUE) + " |")  # type: ignore[index]
    print(json.dumps({"bench": "ppo_libraries", "rows": rows}))

if __name__ == "__main__":
    main()
