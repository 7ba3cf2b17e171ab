"""The opponents the trainers' Python drives (the sample robots are the simulator's own, ``arena.bots``).

- The paper's TD team (§6.3): tabular one-step Q-learning, pre-trained once against a scripted robot and cached as
  an artefact (:func:`td_team`); the paper's learners fight it (``opponent.kind = "td"``), the PPO league plays it
  greedily (``td`` entries).
- The PPO league's others (``league.opponents``, ``SCENARIO:OPPONENT``): ``random`` (uniform paper moves),
  ``dodge`` (a hand-written stochastic dodge over the paper's state and moves), ``strafe`` (a hand-written strafer
  with the learners' own actions and gun), ``self`` (a snapshot of the policy, sampled from the last few); a
  scripted sample robot or a technique robot (``confront.arena.tech``; in 4v4 a team of four) otherwise.
  Opponents in the paper's moves play the paper's controller (no lead, power by distance), also in the engine
  (:func:`paper_move_robot`). Nothing in a tank's view names its opponent.

:func:`build_pool` makes the league a ``PoolEnv`` (all battles, one call per entry).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
import numpy as np

from confront import checkpoint as ck
from confront.arena.observe import N_DIST_BINS, N_HEADING_BINS, N_STATES, ObservationConfig
from confront.arena.pool import OpponentPolicy, PoolEntry, PoolEnv
from confront.arena.scenarios import get_scenario
from confront.arena.smdp import TeamBattleEnv
from confront.arena.tank import OWN_FEATURES, TankSpace
from confront.config import to_dict
from confront.engine.java_build import cache_root
from confront.learning.base import Learner
from confront.learning.factory import make_learner
from confront.learning.tabular import TabularQ
from confront.train.episodes import Loop, Side
from confront.train.loop import run_rounds
from confront.train.paper_model import load_model, save_model, smdp_config
from confront.train.ppo_model import smdp_tank_config, tank_space
from confront.train.spec import ExperimentConfig

if TYPE_CHECKING:
    from confront.engine.export import ExportedPolicy

__all__ = ["td_learner", "td_team", "td_policy", "random_policy", "dodge_policy", "strafe_policy", "SnapshotPolicy",
           "PAPER_MOVE_OPPONENTS", "paper_move_values", "paper_move_robot", "build_pool", "recent_shares",
           "pfsp_playing"]


# -- the paper's TD team -----------------------------------------------------------------------------------------

def td_learner(cfg: ExperimentConfig, n_actions: int) -> Learner:
    """The TD team's learner: tabular one-step Q-learning, epsilon-greedy, fixed rate (paper §6.3)."""
    oc = cfg.opponent
    return make_learner("qlearning_egreedy", n_states=320, n_actions=n_actions, gamma=oc.gamma, alpha=oc.alpha,
                        exploit=oc.exploit)


def td_team(cfg: ExperimentConfig, n_actions: int, progress: bool = False) -> tuple[Learner, Path]:
    """The opponent TD team: loaded from ``opponent.model`` or trained once and cached as a reusable artefact.

    Pre-training: the TD learner drives a 4-tank team against the scripted ``opponent.pretrain_against``
    robots for ``opponent.pretrain_rounds`` rounds. Its state model does not depend on team sizes, so the
    same artefact drives TD teams of 4, 6 or 10 tanks.
    """
    oc = cfg.opponent
    if oc.model:
        learner, _ = load_model(Path(oc.model))
        if not isinstance(learner, TabularQ):
            raise ck.CheckpointError(f"opponent.model {oc.model} is not a tabular TD model")
        return learner, Path(oc.model)
    key = json.dumps({"opponent": to_dict(oc), "decision_turns": cfg.arena.decision_turns,
                      "fire_power_actions": cfg.arena.fire_power_actions, "target": cfg.arena.target,
                      "sensing": cfg.arena.sensing, "seed": cfg.train.seed, "version": 2}, sort_keys=True)
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    cache = cache_root() / "td" / digest
    if (cache / "model.json").exists():
        try:
            learner, _ = load_model(cache)
            if not isinstance(learner, TabularQ):
                raise ck.CheckpointError(f"model {cache} is not a tabular TD model")
            return learner, cache
        except (ck.CheckpointError, FileNotFoundError) as exc:  # a corrupt cache entry is rebuilt below
            click.echo(f"note: the cached TD team cannot be used ({exc}); training it again", err=True)
    learner = td_learner(cfg, n_actions)
    if oc.pretrain_rounds > 0:
        env = TeamBattleEnv(get_scenario("4v4"), n_battles=8, seed=cfg.train.seed + 7919,
                            opponents=oc.pretrain_against, config=smdp_config(cfg))
        loop = Loop(env, Side(learner, ours=env.team_ids() == 0), seed=cfg.train.seed + 7919)
        run_rounds(loop, oc.pretrain_rounds, progress=progress, desc="TD team pre-training")
    save_model(cache, learner, {"trained_rounds": oc.pretrain_rounds, "against": oc.pretrain_against})
    return learner, cache


def td_policy(cfg: ExperimentConfig, progress: bool = False) -> OpponentPolicy:
    """The paper's TD team in the league, greedy (random ties)."""
    learner = td_team(cfg, 4, progress=progress)[0]

    def act(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return learner.act(disc, rng, explore=False)

    return act


# -- the league's others -----------------------------------------------------------------------------------------------

def random_policy(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Uniform random paper moves."""
    return rng.integers(0, 4, size=len(disc))


def dodge_policy(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The hand-written stochastic dodge over the paper's own state and moves (§6.1): with the target ahead or
    behind (rel bins 0, 2) turn 45 deg either way at random, with it at a side (bins 1, 3) drive forward or
    backward at random; the paper's gun controller (no lead)."""
    rel = disc // (N_HEADING_BINS * N_DIST_BINS)
    side = (rel == 1) | (rel == 3)
    return np.where(side, rng.integers(0, 2, len(disc)), 2 + rng.integers(0, 2, len(disc)))


PAPER_MOVE_OPPONENTS = ("td", "random", "dodge")  # opponents in the paper's moves, playable in the engine


def paper_move_values(cfg: ExperimentConfig, opp: str, progress: bool = False) -> np.ndarray:
    """(320, 4) move values of a paper-move opponent whose maxima are the moves it draws from, uniformly: the TD
    team's Q table (greedy, random ties), zeros for ``random``, and for ``dodge`` 1 on the two moves of
    :func:`dodge_policy` in each state."""
    if opp == "td":
        return np.asarray(td_team(cfg, 4, progress=progress)[0].state_dict()["q"], dtype=np.float64)
    rel = np.arange(N_STATES) // (N_HEADING_BINS * N_DIST_BINS)
    q = np.zeros((N_STATES, 4))
    if opp == "dodge":
        side = (rel == 1) | (rel == 3)
        q[side, :2] = 1.0
        q[~side, 2:] = 1.0
    elif opp != "random":
        raise ValueError(f"{opp!r} is not one of the paper-move opponents {PAPER_MOVE_OPPONENTS}")
    return q


def paper_move_robot(cfg: ExperimentConfig, opp: str) -> ExportedPolicy:  # the engine import kept lazy
    """A paper-move opponent as the exported ``confront.PolicyBot`` plays it in the engine: its move values with
    random ties, the league's decision interval, the paper's controller and scan memory, as in the simulator."""
    from confront.engine.export import ExportedPolicy

    return ExportedPolicy("qtable", q=paper_move_values(cfg, opp), observation=ObservationConfig(),
                          step_turns=cfg.tank.decision_turns, ties="random")


def strafe_policy(space: TankSpace) -> OpponentPolicy:
    """A hand-written stochastic strafer in the tank actions, with the learners' own gun: the body perpendicular
    to the nearest known enemy, full distance on in the direction it moves (reversed with probability 0.2 each
    step), fire power 1 with the last lead of ``space.leads``."""
    turns = np.radians(np.asarray(space.turns_deg))
    dists = np.asarray(space.distances)
    powers = np.asarray(space.fire_powers)
    far = int(np.argmax(dists)), int(np.argmin(dists))
    fire = int(np.argmin(np.abs(powers - 1.0)))
    side = int(np.argmin(np.abs(np.abs(turns) - np.pi / 2)))  # the angle nearest 90 deg (turn_mode "target")

    def act(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        o = OWN_FEATURES
        if space.turn_mode == "target":
            t = np.full(len(disc), side)
        else:
            rel = np.arctan2(feats[:, o + 1], feats[:, o + 2])  # bearing of slot 0 from the heading
            cand = (np.stack([rel + np.pi / 2, rel - np.pi / 2]) + np.pi) % (2 * np.pi) - np.pi
            want = np.where(np.abs(cand[0]) < np.abs(cand[1]), cand[0], cand[1])  # the smaller perpendicular turn
            t = np.argmin(np.abs(turns[None, :] - want[:, None]), axis=1)
        ahead = np.where(rng.random(len(disc)) < 0.8, feats[:, 6] >= 0, feats[:, 6] < 0)  # keep going, or reverse
        d = np.where(ahead, far[0], far[1])
        f = np.where(feats[:, o] > 0, fire, int(np.argmin(powers)))
        zero = np.zeros_like(d)
        return np.ravel_multi_index((d, t, f, zero, np.full_like(d, len(space.leads) - 1)), space.dims)

    return act


class SnapshotPolicy:
    """A frozen copy of the actor (NumPy), sampling its actions: the self-play opponent."""

    def __init__(self, dims: tuple[int, ...]) -> None:
        self.dims = dims
        self.layers: list[tuple[np.ndarray, np.ndarray]] = []

    def load(self, arrays: dict[str, np.ndarray]) -> None:
        """Set the weights from ``PPO.actor_arrays()``."""
        n = sum(1 for k in arrays if k.startswith("w"))
        self.layers = [(np.asarray(arrays[f"w{i}"]), np.asarray(arrays[f"b{i}"])) for i in range(n)]

    def __call__(self, disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        h = feats.astype(np.float64)
        for i, (w, b) in enumerate(self.layers):
            h = h @ w.T + b
            if i < len(self.layers) - 1:
                h = np.tanh(h)
        out = np.zeros(len(h), dtype=np.int64)
        start = 0
        for d in self.dims:
            z = h[:, start:start + d]
            p = np.exp(z - z.max(axis=1, keepdims=True))
            p /= p.sum(axis=1, keepdims=True)
            pick = (rng.random(len(z))[:, None] > np.cumsum(p, axis=1)).sum(axis=1)
            out = out * d + np.minimum(pick, d - 1)
            start += d
        return out



def build_pool(cfg: ExperimentConfig, seed: int, battles: int | None = None, progress: bool = False,
               part: dict[str, int] | None = None, td: OpponentPolicy | None = None
               ) -> tuple[PoolEnv, SnapshotPolicy]:
    """The league as a PoolEnv; the self-play snapshot policy its ``self`` entries share. ``part``: only these
    entries, with these battles (a Ray rollout worker's share, ``ppo_ray``; default every entry, ``battles`` or
    its ``league.battles_of``); ``td``: the TD team's policy (default :func:`td_policy`, from its cache)."""
    space = tank_space(cfg)
    snap = SnapshotPolicy(space.dims)
    entries = []
    for e in cfg.league.opponents if part is None else [e for e in cfg.league.opponents if e in part]:
        scen, _, opp = e.partition(":")
        n = part[e] if part is not None else battles or cfg.league.battles_of(e)
        if opp == "td":
            if td is None:
                td = td_policy(cfg, progress)
            entries.append(PoolEntry(e, scen, "td", n, policy=td, opponent_actions="paper"))
        elif opp == "random":
            entries.append(PoolEntry(e, scen, "td", n, policy=random_policy, opponent_actions="paper"))
        elif opp == "dodge":
            entries.append(PoolEntry(e, scen, "td", n, policy=dodge_policy, opponent_actions="paper"))
        elif opp == "strafe":
            entries.append(PoolEntry(e, scen, "td", n, policy=strafe_policy(space)))
        elif opp == "self":
            entries.append(PoolEntry(e, scen, "td", n, policy=snap))
        else:
            entries.append(PoolEntry(e, scen, opp, n))
    return PoolEnv(entries, smdp_tank_config(cfg), seed=seed), snap


# -- prioritised sampling ----------------------------------------------------------------------------------------

def recent_shares(rows: list[dict[str, Any]], names: list[str], window: int) -> np.ndarray:
    """Each entry's mean share over its last ``window`` rounds in ``rows`` (0.5 before its first)."""
    out = np.full(len(names), 0.5)
    index = {n: k for k, n in enumerate(names)}
    seen: list[list[float]] = [[] for _ in names]
    for r in reversed(rows):
        k = index.get(str(r["opponent"]))
        if k is not None and len(seen[k]) < window:
            seen[k].append(float(r["share"]))
        if all(len(v) >= window for v in seen):
            break
    for k, v in enumerate(seen):
        if v:
            out[k] = float(np.mean(v))
    return out


def pfsp_playing(shares: np.ndarray, rng: np.random.Generator, fraction: float, floor: float, power: float
                 ) -> np.ndarray:
    """Which entries play the next rollout (bools): entry e with probability p_e = clip(fraction * E * w_e / sum w,
    floor, 1), w_e = (1 - share_e)^power (prioritised fictitious self-play's f_hard, Vinyals et al. 2019; all won:
    p_e = fraction); when none is drawn, one plays, drawn by p."""
    w = (1.0 - np.clip(shares, 0.0, 1.0)) ** power
    p = np.clip(fraction * len(w) * w / w.sum(), floor, 1.0) if w.sum() > 0 else np.full(len(w), fraction)
    play = rng.random(len(w)) < p
    if not play.any():
        play[int(rng.choice(len(p), p=p / p.sum()))] = True
    return play
