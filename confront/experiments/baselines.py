"""Baselines beyond the paper (issue 6): every method ranked by score ratio against the same opponents.

Methods, all playing the paper's 4v4 scenario as team 0:

- ``DQN (SB3)`` and ``PPO (SB3)``: one Stable-Baselines3 model shared by the 4 tanks (parameter sharing):
  :class:`SharedTeamVecEnv` has one sub-environment per (battle, our tank) over a
  :class:`~confront.arena.smdp.TeamBattleEnv`; needs the extra ``confront[baselines]``;
- ``DMNN (FLM)``: the paper's method, trained by :func:`~confront.train.factory.train_run`;
- the scripted sample robots SpinBot, Walls, Tracker and RamFire as our team (no training);
- references that tell whether training helps: ``Random moves`` (``UniformPolicy``: each tank picks one of the
  four moves uniformly at random every SMDP step, same gun/radar controller) and ``DMNN (untrained)`` (the
  DMNN of the seed at its initialisation, greedy).

Trained methods learn against the TD team (the paper's opponent, ``train.td_team`` artefact of the seed)
for the same number of rounds; then every method plays ``eval_rounds`` greedy rounds against each opponent
(the TD team, acting greedily, and scripted SpinBot) on the same battle seeds. Per seed the score ratio is
pooled over those rounds; methods are ranked by the mean over seeds with a 95% bootstrap interval.

Output, ``<out>/baselines/``: ``runs/dmnn-flm/seed-k`` (ordinary run folders), ``eval/<method>/seed-k/
result.json`` (that method's evaluation rows; SB3 methods also ``policy.npz``, the network's parameters),
``results.csv`` (one row per method, seed and opponent), ``ranking.md``, ``figures/ranking.png``,
``config.json``. Finished (method, seed) pairs are not re-run.
"""

from __future__ import annotations

import json
import math
import re
import time
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np

from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.experiments.jobs import Claim, Job, Outcome, run_jobs, slug
from confront.learning.base import Learner, Transition
from confront.learning.uniform import UniformParams, UniformPolicy
from confront.stats import Interval, interval

try:  # the optional extra confront[baselines]
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv as _VecEnvBase

    HAVE_SB3 = True
except ImportError:  # the core install runs the scripted and paper methods only
    _VecEnvBase = object  # type: ignore[assignment,misc]
    HAVE_SB3 = False

__all__ = ["BaselinesConfig", "SharedTeamVecEnv", "SB3Policy", "baselines_outcome", "train_sb3",
           "sb3_activation", "sb3_exported_policy", "rank_table", "HAVE_SB3"]

SB3_METHODS = ("DQN", "PPO")
DMNN_METHOD = "DMNN (FLM)"
RANDOM_METHOD = "Random moves"
UNTRAINED_METHOD = "DMNN (untrained)"
REFERENCE_METHODS = (RANDOM_METHOD, UNTRAINED_METHOD)
CSV_COLUMNS = ("method", "seed", "opponent", "rounds", "score_ours", "score_theirs", "score_ratio",
               "train_rounds", "train_seconds")


@dataclass(frozen=True)
class BaselinesConfig:
    """What is compared and how; SB3 hyperparameters are SB3's defaults except where noted."""

    base: str = "fuzzy"  # packaged experiment of the paper's FLM arm: 4v4 against the TD team
    overrides: tuple[str, ...] = ()  # extra ``key=value`` overrides on ``base`` (e.g. opponent.pretrain_rounds)
    eval_rounds: int = 100  # greedy evaluation rounds per method, seed and opponent
    eval_seed: int = 10_000  # evaluation battles use seed eval_seed + seed for every method
    opponents: tuple[str, ...] = ("td", "SpinBot")
    scripted: tuple[str, ...] = ("SpinBot", "Walls", "Tracker", "RamFire")
    sb3: tuple[str, ...] = SB3_METHODS
    references: tuple[str, ...] = REFERENCE_METHODS
    gamma: float = 0.9  # discount per SMDP step, as the paper's learners (Table 2)
    steps_per_round: int = 80  # SMDP steps a 4v4 round lasts, about (measured: ~75); sizes the SB3 schedules
    dqn_learning_rate: float = 5e-4
    dqn_exploration_fraction: float = 0.25  # of 2x the estimated budget: epsilon reaches its floor at ~half
    ppo_learning_rate: float = 3e-4
    ppo_n_steps: int = 128  # per sub-environment per update (32 sub-environments)
    ppo_batch_size: int = 256
    ppo_n_epochs: int = 4

    def __post_init__(self) -> None:
        if self.eval_rounds < 1:
            raise ValueError(f"eval_rounds must be >= 1, got {self.eval_rounds}")
        from confront.arena.bots import BOT_NAMES

        if not self.opponents:
            raise ValueError("opponents must name at least one opponent")
        for name in self.opponents:
            if name != "td" and name not in BOT_NAMES:
                raise ValueError(f"opponent {name!r} is neither 'td' nor one of {', '.join(BOT_NAMES)}")
        for name in self.scripted:
            if name not in BOT_NAMES:
                raise ValueError(f"scripted robot {name!r} is not one of {', '.join(BOT_NAMES)}")
        for name in self.references:
            if name not in REFERENCE_METHODS:
                raise ValueError(f"reference method {name!r} is not one of {', '.join(REFERENCE_METHODS)}")
        for name in self.sb3:
            if name not in SB3_METHODS:
                raise ValueError(f"sb3 method {name!r} is not one of {', '.join(SB3_METHODS)}")
        if not 0.0 <= self.gamma <= 1.0:
            raise ValueError(f"gamma must be in [0, 1], got {self.gamma}")
        if self.steps_per_round < 1:
            raise ValueError(f"steps_per_round must be >= 1, got {self.steps_per_round}")


# -- the SB3 adapter ---------------------------------------------------------------------------------------------

class SharedTeamVecEnv(_VecEnvBase):
    """SB3 ``VecEnv`` over a TeamBattleEnv: one sub-environment per (battle, tank of team 0).

    Sub-environment ``k = b * n_ours + j`` is tank ``j`` of team 0 in battle ``b``. Observation: the
    features vector (with ``config.tank``: the tank view, actions as ``MultiDiscrete`` head indices,
    ``gym_env.make_spaces``); reward: the config's (Eq. 35 or the score margin) summed over the SMDP step's
    turns; done: the tank is dead or its round
    is over (``info["terminal_observation"]`` holds the last observation, ``"TimeLimit.truncated"`` marks
    a living tank whose round hit the turn limit). A tank dead at the start of a step is *padding* (it waits
    for its round to end): reward 0, done, ``info["padding"] = True``. The TD team, if any, acts greedily.
    """

    def __init__(self, scenario: Any, n_battles: int, seed: int, opponents: str = "td",
                 td: Learner | None = None, config: SMDPConfig | None = None) -> None:
        if not HAVE_SB3:
            raise ImportError("SharedTeamVecEnv needs stable-baselines3: pip install 'confront[baselines]'")
        from gymnasium import spaces

        from confront.arena.gym_env import make_spaces

        self.env = TeamBattleEnv(scenario, n_battles=n_battles, seed=seed, opponents=opponents, config=config)
        team = self.env.team_ids()
        self.ours = np.flatnonzero(team == 0)
        self.theirs = np.flatnonzero((team != 0) & self.env.learner)
        if self.theirs.size and td is None:
            raise ValueError("opponents='td' needs the TD team's learner: pass td=")
        self.td = td
        self.seed_value = seed
        self.rng = np.random.default_rng([seed, 1])  # the TD team's ties
        self.render_mode = None
        self.rounds_done = 0
        self.live_steps = 0
        self.padding_steps = 0
        self._actions: np.ndarray | None = None
        self._disc = np.zeros((n_battles, self.env.n_robots), dtype=np.int64)
        self._feats = np.zeros((n_battles, self.env.n_robots, self.env.n_features), dtype=np.float32)
        obs_space, act_space = make_spaces(self.env.config)
        n = n_battles * self.ours.size
        if self.env.config.tank is None:  # the paper's Dict: SB3 sees its features
            obs_space = cast(spaces.Dict, obs_space)["features"]
        super().__init__(n, obs_space, act_space)

    def _flat(self, feats: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(feats[:, self.ours].reshape(self.num_envs, -1), dtype=np.float32)

    def reset(self) -> np.ndarray:
        """New battles in every sub-environment; the features of our tanks, (N, F)."""
        seed = next((s for s in self._seeds if s is not None), None)
        self._disc, self._feats = self.env.reset(seed=seed)
        self._reset_seeds()
        return self._flat(self._feats)

    def step_async(self, actions: np.ndarray) -> None:
        """Remember our tanks' actions: (N,) ints, or (N, heads) with the tank view."""
        from confront.arena.gym_env import action_indices

        self._actions = action_indices(self.env.config, actions, self.num_envs)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        """One SMDP step of every battle: (obs, rewards, dones, infos) per sub-environment."""
        if self._actions is None:
            raise RuntimeError("step_wait called before step_async")
        b = self.env.n_battles
        full = np.zeros((b, self.env.n_robots), dtype=np.int64)
        full[:, self.ours] = self._actions.reshape(b, self.ours.size)
        if self.td is not None and self.theirs.size:
            obs_t = self._disc[:, self.theirs].reshape(-1)
            full[:, self.theirs] = self.td.act(obs_t, self.rng, explore=False).reshape(b, -1)
        res = self.env.step(full)
        self._actions = None
        rewards = res.rewards[:, self.ours].sum(axis=2).reshape(-1).astype(np.float32)  # summed over T
        active = res.active[:, self.ours]
        dones = (res.terminated[:, self.ours] | ~active).reshape(-1)
        terminal = res.features
        alive_end = np.zeros_like(active)
        if res.round_end is not None:
            self.rounds_done += int(res.round_end.mask.sum())
            alive_end = res.round_end.alive[:, self.ours] & res.round_end.mask[:, None]
            if res.final_features is not None:
                terminal = np.where(res.round_done[:, None, None], res.final_features, res.features)
        truncated = (res.truncated[:, None] & alive_end & active).reshape(-1)
        term_flat = self._flat(terminal)
        padding = (~active).reshape(-1)
        self.padding_steps += int(padding.sum())
        self.live_steps += int(active.sum())
        infos: list[dict[str, Any]] = []
        for k in range(self.num_envs):
            info: dict[str, Any] = {}
            if dones[k]:
                info["terminal_observation"] = term_flat[k]
                info["TimeLimit.truncated"] = bool(truncated[k])
                info["padding"] = bool(padding[k])
            infos.append(info)
        self._disc, self._feats = res.discrete, res.features
        return self._flat(res.features), rewards, dones, infos

    def close(self) -> None:
        """Nothing to release."""

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        """The adapter's attribute, once per selected sub-environment."""
        return [getattr(self, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        """Set an attribute on the adapter (shared by every sub-environment)."""
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any) -> list[Any]:
        """Call a method of the adapter once per selected sub-environment."""
        return [getattr(self, method_name)(*args, **kwargs) for _ in self._indices(indices)]

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        """No sub-environment is wrapped."""
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)


class SB3Policy(Learner):
    """A trained SB3 model behind the Learner interface, for greedy evaluation (it does not learn here)."""

    kind = "sb3"
    observation = "features"

    def __init__(self, model: Any, n_actions: int) -> None:
        self.model = model
        self.n_actions = n_actions
        self.params = None

    def act(self, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
        """The model's greedy (deterministic) actions; ``explore`` samples from the policy instead."""
        a, _ = self.model.predict(np.asarray(obs, dtype=np.float32), deterministic=not explore)
        return np.asarray(a, dtype=np.int64).reshape(-1)

    def learn(self, batch: Transition) -> dict[str, float]:
        """Not supported: SB3 models learn through :class:`SharedTeamVecEnv`."""
        raise TypeError("SB3Policy is for evaluation: train the model with train_sb3")

    def diagnostics(self) -> dict[str, float]:
        """Nothing to report."""
        return {}

    def state_dict(self) -> dict[str, np.ndarray]:
        """The policy network's parameters as arrays (data only, no pickle)."""
        return {k: v.detach().cpu().numpy() for k, v in self.model.policy.state_dict().items()}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        """Load parameters written by :meth:`state_dict`."""
        import torch

        own = self.model.policy.state_dict()
        missing = set(own) - set(state)
        if missing:
            raise ValueError(f"state_dict misses key {sorted(missing)[0]!r}")
        self.model.policy.load_state_dict({k: torch.as_tensor(state[k]) for k in own})


SB3_ACTIVATIONS = {"Tanh": "tanh", "ReLU": "relu"}  # torch activations of an SB3 MLP -> ExportedPolicy's names


def sb3_activation(model: Any) -> str:
    """ExportedPolicy's name of the activation of an SB3 actor-critic model's MLP (``policy.activation_fn``)."""
    name = model.policy.activation_fn.__name__
    if name not in SB3_ACTIVATIONS:
        raise ValueError(f"SB3 activation {name} has no exported twin; known: {', '.join(SB3_ACTIVATIONS)}")
    return SB3_ACTIVATIONS[name]


def sb3_exported_policy(state: Mapping[str, np.ndarray], activation: str, observation: Any, step_turns: int
                        ) -> Any:
    """An SB3 PPO policy network (:meth:`SB3Policy.state_dict`) as the engine's greedy MLP (an ExportedPolicy on
    the features): the actor's layers ``mlp_extractor.policy_net.<i>``, each followed by ``activation``, then
    ``action_net`` (the logits); the first maximum is SB3's deterministic action."""
    from confront.engine.export import ExportedPolicy

    idx = sorted(int(m.group(1)) for k in state if (m := re.fullmatch(r"mlp_extractor\.policy_net\.(\d+)\.weight", k)))
    names = [f"mlp_extractor.policy_net.{i}" for i in idx] + ["action_net"]
    missing = [f"{n}.{p}" for n in names for p in ("weight", "bias") if f"{n}.{p}" not in state]
    if missing:
        raise ValueError(f"not an SB3 actor-critic policy: {', '.join(missing)} missing")
    return ExportedPolicy("mlp", weights=tuple(np.asarray(state[f"{n}.weight"], np.float64) for n in names),
                          biases=tuple(np.asarray(state[f"{n}.bias"], np.float64) for n in names),
                          hidden_activation=activation, output_activation="linear", observation=observation,
                          step_turns=step_turns)


# -- one (method, seed) ------------------------------------------------------------------------------------------

def baseline_experiment(cfg: BaselinesConfig, seed: int, rounds: int) -> Any:
    """The baselines' experiment (the paper's 4v4 against the TD team) at ``seed`` for ``rounds`` rounds."""
    from confront.train.spec import load_experiment

    return load_experiment(cfg.base, cfg.overrides + (f"train.seed={seed}", f"train.rounds={rounds}",
                                                      f"train.session_rounds={max(1, min(10, rounds // 2))}"))


def pooled_ratio(rows: Sequence[dict[str, Any]], flip: bool = False) -> tuple[float, float, float]:
    """(ours, theirs, ratio) summed over rounds; ``flip`` swaps the sides (scripted robots played as team 1)."""
    o = float(sum(r["score_ours"] for r in rows))
    t = float(sum(r["score_theirs"] for r in rows))
    if flip:
        o, t = t, o
    return o, t, o / (o + t) if o + t > 0 else 0.5


def _evaluate(cfg: BaselinesConfig, exp: Any, seed: int, td_path: Path, policy: Learner | None = None,
              scripted: str = "") -> list[dict[str, Any]]:
    """Score rows of one method (a policy, or a scripted robot as our team) against every opponent."""
    from confront.experiments.evaluate import sim_bot_battle, sim_evaluate
    from confront.train.paper_model import load_model

    if (policy is None) == (not scripted):
        raise ValueError("evaluate either a policy or a scripted robot")
    out = []
    for opp in cfg.opponents:
        eval_seed = cfg.eval_seed + seed
        if policy is not None:
            o, t, r = pooled_ratio(sim_evaluate(exp, policy, opp, cfg.eval_rounds, eval_seed, str(td_path)))
        elif opp == "td":  # the TD team plays as team 0 (TeamBattleEnv's learning side), the robot as team 1
            td, _ = load_model(td_path)
            o, t, r = pooled_ratio(sim_evaluate(exp, td, scripted, cfg.eval_rounds, eval_seed), flip=True)
        else:
            res = sim_bot_battle(exp.arena.scenario, [scripted, opp], cfg.eval_rounds, eval_seed, n_battles=16)
            o = sum(c.total for c in res.contestants if c.name.endswith("team 0"))
            t = sum(c.total for c in res.contestants if not c.name.endswith("team 0"))
            r = o / (o + t) if o + t > 0 else 0.5
        out.append({"opponent": opp, "rounds": cfg.eval_rounds, "score_ours": o, "score_theirs": t,
                    "score_ratio": r})
    return out


def train_sb3(algo: str, cfg: BaselinesConfig, seed: int, rounds: int) -> tuple[Any, dict[str, Any]]:
    """Train a parameter-shared DQN or PPO against the seed's TD team for ``rounds`` rounds."""
    import torch
    from stable_baselines3 import DQN, PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.logger import Logger

    from confront.train.league import td_team
    from confront.train.paper_model import scenario_of, smdp_config

    if algo not in SB3_METHODS:
        raise ValueError(f"algo must be one of {', '.join(SB3_METHODS)}, got {algo!r}")
    torch.set_num_threads(1)
    exp = baseline_experiment(cfg, seed, rounds)
    smdp = smdp_config(exp)
    td, td_path = td_team(exp, smdp.n_actions)
    env = SharedTeamVecEnv(scenario_of(exp.arena.scenario), exp.arena.battles, seed, "td", td, smdp)

    class StopAfterRounds(BaseCallback):
        """Stop learning once the battles have played the round budget."""

        def _on_step(self) -> bool:
            return env.rounds_done < rounds

    # schedules need a length: twice the estimated budget; the callback stops at the round budget
    budget = 2 * math.ceil(rounds / exp.arena.battles) * cfg.steps_per_round * env.num_envs
    if algo == "DQN":
        model: Any = DQN("MlpPolicy", env, learning_rate=cfg.dqn_learning_rate, gamma=cfg.gamma,
                         exploration_fraction=cfg.dqn_exploration_fraction, learning_starts=1000, train_freq=1,
                         gradient_steps=1, target_update_interval=2000, seed=seed, device="cpu", verbose=0)
    else:
        model = PPO("MlpPolicy", env, learning_rate=cfg.ppo_learning_rate, gamma=cfg.gamma, n_steps=cfg.ppo_n_steps,
                    batch_size=cfg.ppo_batch_size, n_epochs=cfg.ppo_n_epochs, seed=seed, device="cpu", verbose=0)
    # SB3's default logger makes an empty folder in the system temp dir per model: log nowhere instead
    model.set_logger(Logger(folder=None, output_formats=[]))
    start = time.time()
    model.learn(total_timesteps=budget, callback=StopAfterRounds())
    info = {"train_rounds": env.rounds_done, "train_seconds": time.time() - start, "td_model": str(td_path),
            "padding_fraction": env.padding_steps / max(1, env.padding_steps + env.live_steps),
            "timesteps": int(model.num_timesteps)}
    return model, info


def _method_job(method: str, cfg: BaselinesConfig, seed: int, rounds: int, folder: Path,
                dmnn_folder: Path | None) -> list[dict[str, Any]]:
    """Train (if needed) and evaluate one method at one seed; cached in ``folder/result.json``."""

    from confront import checkpoint as ck
    from confront.train.league import td_team
    from confront.train.paper_model import load_model

    done = folder / "result.json"
    if done.exists():
        return json.loads(done.read_text())
    exp = baseline_experiment(cfg, seed, rounds)
    extra: dict[str, Any] = {"train_rounds": 0, "train_seconds": 0.0}
    policy: Learner | None = None
    scripted = ""
    if method in SB3_METHODS:
        model, info = train_sb3(method, cfg, seed, rounds)
        policy = SB3Policy(model, int(model.action_space.n))
        td_path = Path(info.pop("td_model"))
        extra.update(info)
        folder.mkdir(parents=True, exist_ok=True)
        ck.write_npz(folder / "policy.npz", policy.state_dict())
    elif method == DMNN_METHOD:
        if dmnn_folder is None:
            raise ValueError("the DMNN method needs its run folder")
        summary = json.loads((dmnn_folder / "summary.json").read_text())
        policy, _ = load_model(dmnn_folder)
        td_path = Path(summary["td_model"])
        extra.update(train_rounds=int(summary["rounds"]), train_seconds=float(summary["wall_time_s"]))
    else:
        from confront.train.paper_model import build_learner, smdp_config

        smdp = smdp_config(exp)
        _, td_path = td_team(exp, smdp.n_actions)
        if method == RANDOM_METHOD:
            policy = UniformPolicy(UniformParams(n_actions=smdp.n_actions))
        elif method == UNTRAINED_METHOD:
            policy = build_learner(exp, smdp.observation.n_features, smdp.n_actions)
        else:
            scripted = method
    rows = [{"method": method, "seed": seed, **r, **extra}
            for r in _evaluate(cfg, exp, seed, td_path, policy, scripted)]
    folder.mkdir(parents=True, exist_ok=True)
    ck.write_atomic(done, json.dumps(rows, indent=1).encode())
    return rows


# -- ranking, table, figure --------------------------------------------------------------------------------------

def rank_table(rows: Sequence[dict[str, Any]], opponents: Sequence[str], rng: np.random.Generator,
               skipped: dict[str, str] | None = None) -> tuple[str, dict[str, dict[str, Interval]]]:
    """Markdown ranking (by the first opponent's mean score ratio) and the intervals per method and opponent."""
    methods = list(dict.fromkeys(r["method"] for r in rows))
    stats: dict[str, dict[str, Interval]] = {}
    for m in methods:
        stats[m] = {}
        for opp in opponents:
            v = np.array([r["score_ratio"] for r in rows if r["method"] == m and r["opponent"] == opp])
            if v.size:
                stats[m][opp] = interval(v, rng)
    first = opponents[0]
    order = sorted(methods, key=lambda m: -stats[m][first].mean if first in stats[m] else 1.0)
    label = {"td": "TD team"}
    head = "| rank | method | " + " | ".join(f"vs {label.get(o, o)} [95% CI]" for o in opponents) + " | seeds |"
    lines = [head, "|---:|---|" + "---:|" * len(opponents) + "---:|"]
    for i, m in enumerate(order, 1):
        cells = [str(stats[m][o]) if o in stats[m] else "" for o in opponents]
        n = len({r["seed"] for r in rows if r["method"] == m})
        lines.append(f"| {i} | {m} | " + " | ".join(cells) + f" | {n} |")
    for m, why in (skipped or {}).items():
        lines.append(f"| - | {m} | skipped: {why} |" + " |" * len(opponents))
    return "\n".join(lines), stats


def plot_ranking(stats: dict[str, dict[str, Interval]], opponents: Sequence[str], path: Path) -> Path:
    """Grouped bars: mean score ratio per method and opponent, whiskers = 95% bootstrap interval."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from confront.plots import COLORS

    methods = sorted(stats, key=lambda m: -stats[m][opponents[0]].mean if opponents[0] in stats[m] else 1.0)
    x = np.arange(len(methods))
    width = 0.8 / len(opponents)
    fig, ax = plt.subplots(figsize=(8, 4), dpi=110)
    for k, opp in enumerate(opponents):
        iv = [stats[m].get(opp, Interval(np.nan, np.nan, np.nan)) for m in methods]
        mean = np.array([v.mean for v in iv])
        err = np.array([[v.mean - v.lo for v in iv], [v.hi - v.mean for v in iv]])
        ax.bar(x + (k - (len(opponents) - 1) / 2) * width, mean, width, yerr=err, capsize=3,
               color=COLORS[k % len(COLORS)], label=f"vs {'TD team' if opp == 'td' else opp}")
    ax.axhline(0.5, color="k", lw=0.8, ls=":")
    ax.set_xticks(x, methods, rotation=20, ha="right")
    ax.set_ylim(0, 1)
    ax.set_ylabel("score ratio (greedy evaluation)")
    ax.set_title("Baselines: score ratio with 95% bootstrap intervals over seeds")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path


def _write_csv(path: Path, rows: Sequence[dict[str, Any]]) -> None:
    import csv

    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_COLUMNS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


# -- the experiment ----------------------------------------------------------------------------------------------

def baselines_outcome(n_seeds: int, out: Path, rounds: int | None, workers: int,
                      config: BaselinesConfig | None = None) -> Outcome:
    """Train and evaluate every method over ``n_seeds`` seeds; write ``out/baselines/``; return the Outcome."""
    if n_seeds < 1:
        raise ValueError(f"n_seeds must be >= 1, got {n_seeds}")
    cfg = config or BaselinesConfig()
    rounds = rounds or 500
    root = Path(out) / "baselines"
    runs = root / "runs"
    start = time.time()
    # 1. the paper's method, as the paper's arms are trained (this also builds each seed's TD team)
    dmnn = [Job("baselines", DMNN_METHOD, s, cfg.base, cfg.overrides + ("learner.learning_rate=\"fuzzy\"",),
                runs / slug(DMNN_METHOD) / f"seed-{s}") for s in range(n_seeds)]
    run_jobs(dmnn, rounds, workers)
    # 2. SB3 methods (trained here) and scripted robots, evaluated on the same seeds
    skipped: dict[str, str] = {}
    methods: list[str] = [DMNN_METHOD]
    if HAVE_SB3:
        methods += list(cfg.sb3)
    else:
        skipped.update({f"{m} (SB3)": "stable_baselines3/torch not installed (pip install 'confront[baselines]')"
                        for m in cfg.sb3})
    methods += list(cfg.references) + list(cfg.scripted)
    tasks = [(m, s) for m in methods for s in range(n_seeds)]

    args = [(m, cfg, s, rounds, root / "eval" / slug(m) / f"seed-{s}", dmnn[s].folder) for m, s in tasks]
    if workers <= 1:
        results = [_method_job(*a) for a in args]
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            results = list(pool.map(_method_job, *zip(*args, strict=True)))
    rows = [dict(r, method=f"{r['method']} (SB3)" if r["method"] in SB3_METHODS else r["method"])
            for res in results for r in res]
    _write_csv(root / "results.csv", rows)
    rng = np.random.default_rng(12345)
    table, stats = rank_table(rows, cfg.opponents, rng, skipped)
    fig = plot_ranking(stats, cfg.opponents, root / "figures" / "ranking.png")
    intro = (f"Ranking by score ratio against the {'TD team' if cfg.opponents[0] == 'td' else cfg.opponents[0]} "
             f"(4v4, {n_seeds} seeds; trained methods: {rounds} training rounds against the TD team each; "
             f"every method: {cfg.eval_rounds} greedy evaluation rounds per opponent, pooled per seed).")
    (root / "ranking.md").write_text(intro + "\n\n" + table + "\n")
    (root / "config.json").write_text(json.dumps({**asdict(cfg), "seeds": n_seeds, "rounds": rounds}, indent=1))
    first = cfg.opponents[0]
    order = sorted((m for m in stats if first in stats[m]), key=lambda m: -stats[m][first].mean)
    claim = Claim(f"beyond the paper: ranking by score ratio vs {'the TD team' if first == 'td' else first}", "-",
                  "; ".join(f"{i}. {m} {stats[m][first]}" for i, m in enumerate(order, 1)), None,
                  detail=f"n = {n_seeds} seeds")
    return Outcome("baselines", claims=[claim], figures=[fig], tables=[intro, "", table, ""],
                   seconds=time.time() - start)
