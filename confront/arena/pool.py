"""An opponent pool: several :class:`~confront.arena.smdp.TeamBattleEnv` batches stepped as one set of agents.

``PoolEnv(entries, config, seed)``: one env per :class:`PoolEntry` (a scenario, its opponents, how many
battles). Team 0's learning tanks of every battle of every entry are the pool's agents, in a fixed order
(entry, battle, robot): ``N = sum(battles * team-0 size)``. Observations are the learners' feature vectors
(the tank view has one length for every scenario, so 1v1 and 4v4 battles share a policy).

``step(actions (N,) ints)`` steps every env once (T turns) and returns a :class:`PoolStep`: next observations
(N, F) float32 (after auto-reset, a new round's first), per-step rewards (N,) (the sum of the step's per-turn
rewards), ``done`` (N,) (the tank died or its round ended: nothing to bootstrap), ``active`` (N,) (it was
alive at the start of the step: the transition counts), and the rounds that ended (entry, score ours/theirs).
``step(actions, playing)`` with ``playing`` (entries,) bools steps only those entries: the others' battles wait
where they are (their agents' observations unchanged, reward 0, not done, not active), e.g. for prioritised
sampling of the entries a learner still loses to.

Opponents driven by the caller (``"td"`` in a scenario's opponents: a TD team, random moves, a dodge, a
snapshot of the policy) get their actions from the entry's ``policy(discrete (n,), features (n, F), rng)``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .core import run_parallel
from .smdp import LEARNER, SMDPConfig, StepResult, TeamBattleEnv, call_kernel, kernel_pool

__all__ = ["PoolEntry", "PoolEnv", "PoolStep", "OpponentPolicy"]

OpponentPolicy = Callable[[np.ndarray, np.ndarray, np.random.Generator], np.ndarray]


@dataclass
class PoolEntry:
    """One kind of battle in the pool: ``name`` labels its metrics (e.g. ``1v1/SpinBot``)."""

    name: str
    scenario: str
    opponents: str  # a sample or technique robot's name for every opponent, or "td" (caller-driven: ``policy``)
    battles: int
    policy: OpponentPolicy | None = None
    opponent_actions: str = "same"  # the caller-driven opponents' action space: "same" or "paper"

    def __post_init__(self) -> None:
        if self.battles < 1:
            raise ValueError(f"pool entry {self.name!r}: battles must be >= 1, got {self.battles}")
        if (self.opponents == LEARNER) != (self.policy is not None):
            raise ValueError(f"pool entry {self.name!r}: caller-driven opponents ('td') need a policy, "
                             "scripted ones none")


@dataclass
class PoolStep:
    """What :meth:`PoolEnv.step` returns (see the module docstring)."""

    obs: np.ndarray  # (N, F) float32
    reward: np.ndarray  # (N,) float64
    done: np.ndarray  # (N,) bool
    active: np.ndarray  # (N,) bool
    rounds: list[dict[str, float | str | bool]] = field(default_factory=list)


class PoolEnv:
    """Every entry's battles in one agent set; see the module docstring."""

    def __init__(self, entries: list[PoolEntry], config: SMDPConfig, seed: int = 0) -> None:
        if not entries:
            raise ValueError("the pool needs at least one entry")
        names = [e.name for e in entries]
        if len(set(names)) != len(names):
            raise ValueError(f"pool entry names must be unique, got {names}")
        self.entries = entries
        self.envs = [TeamBattleEnv(e.scenario, n_battles=e.battles, seed=seed * 1000 + k, opponents=e.opponents,
                                   config=config, opponent_actions=e.opponent_actions)  # type: ignore[arg-type]
                     for k, e in enumerate(entries)]
        for env in self.envs:  # only the caller-driven robots' views are read (a scripted bot's is not), and
            env.view_robots = env.learner.copy()  # the paper observations only of the opponents' policies
            env.paper_robots = env.learner & ((env.team_ids() != 0) | (config.tank is None))
        self.ours = [env.team_ids() == 0 for env in self.envs]
        self.theirs = [env.learner & (env.team_ids() != 0) for env in self.envs]
        sizes = [env.n_battles * int(o.sum()) for env, o in zip(self.envs, self.ours, strict=True)]
        self.bounds = np.concatenate([[0], np.cumsum(sizes)])
        self.n_agents = int(self.bounds[-1])
        self.n_features = self.envs[0].n_features
        if any(env.n_features != self.n_features for env in self.envs):
            raise ValueError("pool entries must share one observation length (use the tank view)")
        self.n_actions = self.envs[0].n_actions
        self.action_dims = self.envs[0].action_dims
        # agent -> its team (entry, battle): a team critic pools over these groups
        groups, entry_of, g0 = [], [], 0
        for k, (env, o) in enumerate(zip(self.envs, self.ours, strict=True)):
            groups.append(g0 + np.repeat(np.arange(env.n_battles), int(o.sum())))
            entry_of.append(np.full(env.n_battles * int(o.sum()), k))
            g0 += env.n_battles
        self.group = np.concatenate(groups)
        self.n_groups = g0
        self.entry_of = np.concatenate(entry_of)
        self.rng = np.random.default_rng([seed, 17])
        self._disc: list[np.ndarray] = []
        self._feats: list[np.ndarray] = []

    def reset(self) -> np.ndarray:
        """New battles in every env: the agents' first observations (N, F)."""
        self._disc, self._feats = [], []
        for env in self.envs:
            d, f = env.reset()
            self._disc.append(d)
            self._feats.append(f)
        return self._gather(self._feats)

    def _gather(self, feats: list[np.ndarray]) -> np.ndarray:
        return np.concatenate([f[:, o].reshape(-1, f.shape[-1]) for f, o in zip(feats, self.ours, strict=True)])

    def step(self, actions: np.ndarray, playing: np.ndarray | None = None) -> PoolStep:
        """Every env (or the ``playing`` entries' only) one SMDP step with the agents' ``actions`` (N,).

        The entries' compiled kernels run together, largest first, on this thread and the pool's others."""
        a = np.asarray(actions, dtype=np.int64)
        if a.shape != (self.n_agents,):
            raise ValueError(f"actions must have shape ({self.n_agents},), got {a.shape}")
        play = np.ones(len(self.envs), dtype=bool) if playing is None else np.asarray(playing, dtype=bool)
        if play.shape != (len(self.envs),):
            raise ValueError(f"playing must have shape ({len(self.envs)},), got {play.shape}")
        on = [int(k) for k in np.flatnonzero(play)]
        full_actions = []
        for k in on:
            entry, env = self.entries[k], self.envs[k]
            ours, theirs = self.ours[k], self.theirs[k]
            full = np.zeros((env.n_battles, env.n_robots), dtype=np.int64)
            full[:, ours] = a[self.bounds[k]:self.bounds[k + 1]].reshape(env.n_battles, -1)
            if entry.policy is not None:
                d, f = self._disc[k][:, theirs], self._feats[k][:, theirs]
                full[:, theirs] = np.asarray(entry.policy(d.reshape(-1), f.reshape(-1, f.shape[-1]), self.rng),
                                             dtype=np.int64).reshape(env.n_battles, -1)
            full_actions.append(full)
        envs = [self.envs[k] for k in on]
        if any(env.recording is not None for env in envs):
            stepped = [env.step(full) for env, full in zip(envs, full_actions, strict=True)]
        else:
            stepped = self._step_together(envs, full_actions)
        results: list[StepResult | None] = [None] * len(self.envs)
        for j, done_step in zip(on, stepped, strict=True):
            results[j] = done_step
        obs, rew, done, active = [], [], [], []
        rounds: list[dict[str, float | str | bool]] = []
        for k, (entry, res) in enumerate(zip(self.entries, results, strict=True)):
            ours = self.ours[k]
            if res is None:  # waiting: as it was, no transition
                f = self._feats[k]
                n = int(self.bounds[k + 1] - self.bounds[k])
                obs.append(f[:, ours].reshape(-1, f.shape[-1]))
                rew.append(np.zeros(n))
                done.append(np.zeros(n, dtype=bool))
                active.append(np.zeros(n, dtype=bool))
                continue
            self._disc[k], self._feats[k] = res.discrete, res.features
            obs.append(res.features[:, ours].reshape(-1, res.features.shape[-1]))
            rew.append(res.rewards[:, ours].sum(axis=2).reshape(-1))
            done.append(res.terminated[:, ours].reshape(-1))
            active.append(res.active[:, ours].reshape(-1))
            if res.round_end is not None:
                end = res.round_end
                for b in np.flatnonzero(end.mask):
                    s = end.score[b].sum(axis=1)
                    o, t = float(s[ours].sum()), float(s[~ours].sum())
                    rounds.append({"opponent": entry.name, "battle": int(b), "score_ours": o, "score_theirs": t,
                                   "share": o / (o + t) if o + t > 0 else 0.5, "turns": int(end.turns[b]),
                                   "won": bool(end.decided[b] and end.alive[b][ours].any())})
        return PoolStep(np.concatenate(obs), np.concatenate(rew), np.concatenate(done), np.concatenate(active),
                        rounds)

    @staticmethod
    def _step_together(envs: list[TeamBattleEnv], full_actions: list[np.ndarray]) -> list[StepResult]:
        """The envs' steps (what ``env.step`` does) with all the kernels run together, largest first."""
        begun = [env.begin_step(full) for env, full in zip(envs, full_actions, strict=True)]
        workers = kernel_pool()._max_workers
        whole = len(envs) >= 2 * workers  # enough entries to balance the threads: one call per entry
        calls: list[tuple[int, tuple[Any, ...]]] = []
        for k, (env, (rewards, _, obs)) in enumerate(zip(envs, begun, strict=True)):
            calls.extend((k, c) for c in env.kernel_calls(0, env.turns_per_step, rewards, obs, whole=whole))
        calls.sort(key=lambda kc: -(kc[1][1] - kc[1][0]) * envs[kc[0]].n_robots)  # largest first
        run_parallel(kernel_pool(), call_kernel, [(envs[k].kernel(c), c) for k, c in calls], workers)
        return [env.finish_step(rewards, active, obs)
                for env, (rewards, active, obs) in zip(envs, begun, strict=True)]

    def state_dict(self) -> dict[str, np.ndarray]:
        """Every env's state and the last observations (data only)."""
        d: dict[str, np.ndarray] = {}
        for k, env in enumerate(self.envs):
            d.update({f"env{k}.{n}": v for n, v in env.state_dict().items()})
            d[f"obs{k}.discrete"], d[f"obs{k}.features"] = self._disc[k], self._feats[k]
        return d

    def load_state_dict(self, d: dict[str, np.ndarray]) -> np.ndarray:
        """Restore :meth:`state_dict`; returns the agents' current observations."""
        self._disc, self._feats = [], []
        for k, env in enumerate(self.envs):
            p = f"env{k}."
            env.load_state_dict({n[len(p):]: v for n, v in d.items() if n.startswith(p)})
            self._disc.append(np.asarray(d[f"obs{k}.discrete"]))
            self._feats.append(np.asarray(d[f"obs{k}.features"]))
        return self._gather(self._feats)
