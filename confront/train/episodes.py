"""The paper learners' episodes: a learning team against its opponents in the batched simulator (Algorithm 2).

Per SMDP step (T engine turns):

    observations (B, R) --learner.act--> our actions --+--> env.step --> rewards (B, R, T), next obs
                        --opponent.act-> their actions -+        |
    learner.learn(transitions of our living tanks)  <-----------+   (parameter sharing: one learner, all tanks)

B battles run side by side and share out the configured number of rounds; rounds are numbered in the
order they end (deterministic for a seed). :class:`Loop` holds everything that changes (arena arrays,
learner, opponent, RNG states, metrics so far) as data, so a checkpointed run resumes exactly. Also here: the
learner and model files of a config, the TD team (:func:`td_team`, a cached artefact),
:func:`record_round` (one greedy round as a replay) and :class:`SMDPTrainer`, the Loop as a trainer of the one
training loop (``train.py``, which also makes the run folders).
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import click
import numpy as np

from confront import checkpoint as ck
from confront.arena.scenarios import Scenario, get_scenario, load_scenario, scenario_names
from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.state import SCORE_PARTS
from confront.config import ConfigError, to_dict
from confront.engine.java_build import cache_root
from confront.experiments.spec import ExperimentConfig
from confront.learning.base import Learner, Transition
from confront.learning.factory import load_learner, make_learner, save_learner
from confront.learning.tabular import TabularQ
from confront.learning.transfer import TransferParams, TransferPolicy
from confront.runs import Run

__all__ = ["scenario_of", "smdp_config", "build_learner", "td_learner", "save_model", "load_model", "Side", "Loop",
           "SMDPTrainer", "with_transfer", "td_team", "run_rounds", "pooled_share", "record_round"]


# -- building blocks ---------------------------------------------------------------------------------------------

def scenario_of(name: str) -> Scenario:
    """A named scenario or a scenario TOML file (a ConfigError naming it when it is neither)."""
    try:
        return load_scenario(name) if name.endswith(".toml") else get_scenario(name)
    except (OSError, ValueError, TypeError, RecursionError) as exc:  # TOML and Unicode errors are ValueErrors
        raise ConfigError(f"scenario {name!r} cannot be used ({str(exc).splitlines()[0][:200]}): give one of "
                          f"{', '.join(scenario_names())} or a scenario .toml file") from None


def smdp_config(cfg: ExperimentConfig) -> SMDPConfig:
    from confront.arena.observe import ObservationConfig

    return SMDPConfig(turns_per_step=cfg.arena.decision_turns, fire_power_actions=cfg.arena.fire_power_actions,
                      observation=ObservationConfig(target=cfg.arena.target, sensing=cfg.arena.sensing))


def build_learner(cfg: ExperimentConfig, n_features: int, n_actions: int) -> Learner:
    """The learning team's learner from the config (shared by every tank: parameter sharing, §4.2)."""
    lc = cfg.learner
    common: dict[str, Any] = dict(n_actions=n_actions, gamma=lc.gamma, alpha=lc.alpha, rate=lc.learning_rate,
                                  backup=lc.backup, exploration="boltzmann", t_max=lc.t_max, t_min=lc.t_min, eta=lc.eta)
    if lc.kind == "ssaq":
        return make_learner("ssaq", n_states=320, **common)
    if lc.kind == "random":
        return make_learner("random", n_actions=n_actions)
    return make_learner("dmnn", n_inputs=n_features, observation="features", hidden=lc.hidden, awm=lc.awm,
                        momentum=lc.momentum, nn_rate=lc.nn_rate, output=lc.output, q_scale=lc.q_scale,
                        td_clip=lc.td_clip, init_seed=cfg.train.seed, **common)


def td_learner(cfg: ExperimentConfig, n_actions: int) -> Learner:
    """The TD team's learner: tabular one-step Q-learning, epsilon-greedy, fixed rate (paper §6.3)."""
    oc = cfg.opponent
    return make_learner("qlearning_egreedy", n_states=320, n_actions=n_actions, gamma=oc.gamma, alpha=oc.alpha,
                        exploit=oc.exploit)


def _obs(learner: Learner, disc: np.ndarray, feats: np.ndarray) -> np.ndarray:
    return disc if learner.observation == "discrete" else feats


def save_model(folder: Path, learner: Learner, meta: dict[str, Any]) -> None:
    """``learner.npz`` (kind, parameters and state; no pickle) + ``model.json`` (the task it was trained on)."""
    folder.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=folder, prefix=".learner.", suffix=".npz")  # unique: writers may race
    os.close(fd)
    tmp = Path(name)
    try:
        save_learner(tmp, learner.current if isinstance(learner, TransferPolicy) else learner)
        os.replace(tmp, folder / "learner.npz")
    finally:
        tmp.unlink(missing_ok=True)
    info = {"format": "confront-model/1", "kind": learner.kind, "observation": learner.observation,
            "n_actions": learner.n_actions, **meta}
    ck.write_atomic(folder / "model.json", json.dumps(info, indent=1, sort_keys=True).encode())


def load_model(folder: str | Path) -> tuple[Learner, dict[str, Any]]:
    """Load a learner written by :func:`save_model` (a run folder, its ``model/``, or a model folder)."""
    p = Path(folder)
    if (p / "model").is_dir():
        p = p / "model"
    try:
        info = json.loads((p / "model.json").read_text(encoding="utf-8"))
    except (FileNotFoundError, NotADirectoryError):
        raise FileNotFoundError(f"no trained model in {folder} (expected model/model.json)") from None
    except (ValueError, OSError, RecursionError) as exc:  # JSON and Unicode errors are ValueErrors
        raise ck.CheckpointError(f"model {p} has a corrupt model.json ({str(exc)[:200]})") from None
    if not isinstance(info, dict) or info.get("format") != "confront-model/1":
        what = info.get("format") if isinstance(info, dict) else type(info).__name__
        raise ck.CheckpointError(f"{p} is not a confront model (format {what!r})")
    try:
        learner = load_learner(p / "learner.npz", frozen=False)
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile) as exc:
        raise ck.CheckpointError(f"model {p} cannot be read: {str(exc)[:200]}") from None
    return learner, info


# -- the loop ----------------------------------------------------------------------------------------------------

@dataclass
class Side:
    """Who drives which robots: the learner (team 0) and an optional learning opponent (the TD team)."""

    learner: Learner
    ours: np.ndarray  # (R,) bool
    opponent: Learner | None = None
    theirs: np.ndarray | None = None  # (R,) bool, robots the opponent learner drives
    opponent_learns: bool = False


def _round_row(end: Any, b: int, team: np.ndarray) -> dict[str, Any]:
    ours, theirs = team == 0, team != 0
    s = end.score[b]
    row: dict[str, Any] = {"battle": b, "turns": int(end.turns[b]), "decided": bool(end.decided[b])}
    total_o, total_t = float(s[ours].sum()), float(s[theirs].sum())
    row.update(score_ours=total_o, score_theirs=total_t,
               score_ratio=total_o / (total_o + total_t) if total_o + total_t > 0 else 0.5,
               defensive_ours=float(s[ours][:, :2].sum()), defensive_theirs=float(s[theirs][:, :2].sum()),
               won=bool(end.decided[b] and end.alive[b][ours].any()),
               alive_ours=int(end.alive[b][ours].sum()), alive_theirs=int(end.alive[b][theirs].sum()))
    for i, part in enumerate(SCORE_PARTS):
        row[f"{part}_ours"] = float(s[ours][:, i].sum())
        row[f"{part}_theirs"] = float(s[theirs][:, i].sum())
    return row


class Loop:
    """The SMDP interaction loop over a TeamBattleEnv; state is data so it can be checkpointed."""

    def __init__(self, env: TeamBattleEnv, side: Side, seed: int, learning: bool = True) -> None:
        self.env, self.side = env, side
        self.learning = learning  # False: evaluate greedily, nothing learns
        self.team = env.team_ids()
        self.rngs = {name: np.random.default_rng([seed, i]) for i, name in enumerate(("act", "opp"))}
        self.rounds_done = 0
        self.decisions = 0
        self.rows: list[dict[str, Any]] = []
        self.disc, self.feats = env.reset()
        self.last_learn: dict[str, float] = {}

    # checkpoint state
    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays = {f"env.{k}": v for k, v in self.env.state_dict().items()}
        arrays.update({f"learner.{k}": v for k, v in self.side.learner.state_dict().items()})
        if self.side.opponent is not None:
            arrays.update({f"opponent.{k}": v for k, v in self.side.opponent.state_dict().items()})
        arrays["obs.discrete"], arrays["obs.features"] = self.disc, self.feats
        meta = {"rounds_done": self.rounds_done, "decisions": self.decisions, "rows": self.rows,
                "rngs": {k: ck.rng_state(g) for k, g in self.rngs.items()}}
        return arrays, meta

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        def sub(prefix: str) -> dict[str, np.ndarray]:
            return {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}

        try:
            self.env.load_state_dict(sub("env."))
            self.side.learner.load_state_dict(sub("learner."))
            if self.side.opponent is not None:
                self.side.opponent.load_state_dict(sub("opponent."))
            self.disc, self.feats = arrays["obs.discrete"], arrays["obs.features"]
            self.rounds_done, self.decisions = int(meta["rounds_done"]), int(meta["decisions"])
            self.rows = list(meta["rows"])
            self.rngs = {k: ck.rng_from_state(v) for k, v in meta["rngs"].items()}
        except (KeyError, ValueError, TypeError) as exc:
            raise ck.CheckpointError(f"checkpoint does not fit this run's config: {exc}") from None

    def step(self) -> list[dict[str, Any]]:
        """One SMDP step in every battle; returns the rows of the rounds that ended."""
        env, side = self.env, self.side
        b, r = env.n_battles, env.n_robots
        actions = np.zeros((b, r), dtype=np.int64)
        obs_ours = _obs(side.learner, self.disc, self.feats)[:, side.ours]
        flat = obs_ours.reshape((-1,) + obs_ours.shape[2:])
        actions[:, side.ours] = side.learner.act(flat, self.rngs["act"], explore=self.learning).reshape(b, -1)
        if side.opponent is not None and side.theirs is not None:
            obs_t = _obs(side.opponent, self.disc, self.feats)[:, side.theirs]
            their_a = side.opponent.act(obs_t.reshape((-1,) + obs_t.shape[2:]), self.rngs["opp"],
                                        explore=side.opponent_learns and self.learning)
            actions[:, side.theirs] = their_a.reshape(b, -1)
        res = env.step(actions)
        self.decisions += 1
        if self.learning:
            self._learn(side.learner, side.ours, res, actions)
        if self.learning and side.opponent is not None and side.opponent_learns and side.theirs is not None:
            self._learn(side.opponent, side.theirs, res, actions)
        ended: list[dict[str, Any]] = []
        if res.round_end is not None:
            for bi in np.flatnonzero(res.round_end.mask):
                row = _round_row(res.round_end, int(bi), self.team)
                self.rounds_done += 1
                row["round"] = self.rounds_done
                ended.append(row)
        self.disc, self.feats = res.discrete, res.features
        return ended

    def _learn(self, learner: Learner, robots: np.ndarray, res: Any, actions: np.ndarray) -> None:
        next_disc, next_feats = res.discrete, res.features
        if res.final_discrete is not None:
            ended = res.round_done[:, None]
            next_disc = np.where(ended, res.final_discrete, res.discrete)
            next_feats = np.where(ended[..., None], res.final_features, res.features)
        active = res.active[:, robots]
        if not active.any():
            return
        obs = _obs(learner, self.disc, self.feats)[:, robots][active]
        nxt = _obs(learner, next_disc, next_feats)[:, robots][active]
        batch = Transition(obs=obs, action=actions[:, robots][active], rewards=res.rewards[:, robots][active],
                           next_obs=nxt, done=res.terminated[:, robots][active])
        out = learner.learn(batch)
        if learner is self.side.learner:
            self.last_learn = out


def with_transfer(cfg: ExperimentConfig, learner: Learner) -> tuple[Learner, dict[str, Any]]:
    """Curriculum transfer (``transfer.source``): the learner wrapped to act from the source model with Eq. 34's
    epsilon (and started from its weights with ``init_from_source``); the learner itself when there is none."""
    tc = cfg.transfer
    if not tc.source:
        return learner, {}
    source, _ = load_model(tc.source)
    if (source.n_actions, source.observation) != (learner.n_actions, learner.observation):
        raise ck.CheckpointError(
            f"transfer.source {tc.source} has {source.n_actions} actions on {source.observation} observations; "
            f"this task needs {learner.n_actions} on {learner.observation} (Eq. 33)")
    if tc.init_from_source:
        learner.load_state_dict(source.state_dict())
    return TransferPolicy(learner, source, TransferParams(tc.epsilon0, tc.decay, 0, tc.floor)), \
        {"transfer_source": tc.source}


class SMDPTrainer:
    """The paper's learners in the simulator as a trainer of the one training loop (:func:`run_rounds`,
    ``train.train_run``): one SMDP step of every battle per ``advance``. :meth:`from_config` builds a config's
    (the learner vs scripted robots or the TD team, curriculum transfer as configured)."""

    engine = "sim"
    bar_scalars = {"temperature": "T"}
    final_window = 100

    def __init__(self, loop: Loop, desc: str, cfg: ExperimentConfig | None = None,
                 info: dict[str, Any] | None = None) -> None:
        self.loop, self.desc, self.cfg, self.info = loop, desc, cfg, info or {}

    @classmethod
    def from_config(cls, cfg: ExperimentConfig, progress: bool = False) -> SMDPTrainer:
        scenario = scenario_of(cfg.arena.scenario)
        env = TeamBattleEnv(scenario, n_battles=cfg.arena.battles, seed=cfg.train.seed, opponents=cfg.opponent.kind,
                            config=smdp_config(cfg))
        team = env.team_ids()
        learner = build_learner(cfg, env.n_features, env.n_actions)
        info: dict[str, Any] = {"scenario": scenario.name, "n_actions": env.n_actions, "n_features": env.n_features}
        side = Side(learner, ours=team == 0)
        if cfg.opponent.kind == "td":
            td, where = td_team(cfg, env.n_actions, progress=progress)
            side.opponent, side.theirs, side.opponent_learns = td, team != 0, cfg.opponent.learning
            info["td_model"] = str(where)
        side.learner, transfer_info = with_transfer(cfg, learner)
        info.update(transfer_info)
        return cls(Loop(env, side, seed=cfg.train.seed), f"{cfg.name} {scenario.name}", cfg, info)

    @property
    def rows(self) -> list[dict[str, Any]]:
        return self.loop.rows

    @property
    def rounds_done(self) -> int:
        return self.loop.rounds_done

    @property
    def decisions(self) -> int:
        return self.loop.decisions

    def advance(self, limit: int, tick: Any = None) -> dict[str, float]:
        """One SMDP step; rounds past ``limit`` are dropped (battles share out the rounds)."""
        loop = self.loop
        ended = loop.step()
        if not ended:
            return {}
        loop.rows.extend(ended)
        if len(loop.rows) > limit:
            del loop.rows[limit:]
            loop.rounds_done = limit
        return {k: v for k, v in loop.side.learner.diagnostics().items() if isinstance(v, int | float)}

    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        return self.loop.state()

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        self.loop.load(arrays, meta)

    def finish(self, run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]]) -> dict[str, Any]:
        from confront.experiments.plots import session_plots

        cfg, side = self.cfg, self.loop.side
        if cfg is None:
            raise ValueError("finish needs the trainer's config (SMDPTrainer.from_config)")
        save_model(run.path / "model", side.learner,
                   {"scenario": self.info["scenario"], "decision_turns": cfg.arena.decision_turns,
                    "fire_power_actions": cfg.arena.fire_power_actions, "target": cfg.arena.target})
        figures = session_plots(run.plots, sessions, cfg.name, cfg.train.session_rounds)
        replay = record_round(cfg, side, run.replays) if cfg.train.replay else None
        return {"scenario": self.info["scenario"], "learner": side.learner.diagnostics(),
                "figures": [str(f) for f in figures], "replay": replay, **self.info}

    def close(self) -> None:
        pass


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
        run_rounds(SMDPTrainer(loop, "TD team pre-training"), oc.pretrain_rounds, progress=progress)
    save_model(cache, learner, {"trained_rounds": oc.pretrain_rounds, "against": oc.pretrain_against})
    return learner, cache


def pooled_share(rows: list[dict[str, Any]]) -> float:
    """Our score over both sides' (pooled over ``rows``; 0.5 when nobody scored)."""
    o = sum(r["score_ours"] for r in rows)
    t = sum(r["score_theirs"] for r in rows)
    return o / (o + t) if o + t > 0 else 0.5


def run_rounds(trainer: Any, rounds: int, progress: bool, desc: str | None = None, on_step: Any = None,
               window: int = 10) -> None:
    """The one training loop: ``trainer.advance`` until ``rounds`` rounds are done (any trainer of
    ``train.Trainer``), with a progress bar (the share of the last ``window`` rounds and the trainer's
    ``bar_scalars``); ``on_step(scalars)`` after every step in which rounds ended."""
    from tqdm import tqdm

    bar = tqdm(total=rounds, initial=min(trainer.rounds_done, rounds), desc=desc or trainer.desc, unit="round",
               disable=not progress, dynamic_ncols=True)

    def tick(done: int) -> None:
        bar.update(min(done, rounds) - bar.n)

    try:
        while trainer.rounds_done < rounds:
            before = trainer.rounds_done
            scalars = trainer.advance(rounds, tick)
            if trainer.rounds_done == before:
                continue
            tick(trainer.rounds_done)
            bar.set_postfix(share=f"{pooled_share(trainer.rows[-window:]):.3f}", refresh=False,
                            **{label: f"{scalars[k]:,.0f}" if abs(scalars[k]) >= 100 else f"{scalars[k]:.3f}"
                               for k, label in trainer.bar_scalars.items() if k in scalars})
            if on_step is not None:
                on_step(scalars)
    finally:
        bar.close()


def record_round(cfg: ExperimentConfig, side: Side, out_dir: Path, seed: int | None = None) -> str | None:
    """One greedy round of the trained team in a single fresh battle, as replay JSON + GIF + HTML."""
    from confront.arena import replay as rp

    env = TeamBattleEnv(scenario_of(cfg.arena.scenario), n_battles=1,
                        seed=cfg.train.seed + 1000 if seed is None else seed,
                        opponents="td" if side.opponent is not None else cfg.opponent.kind,
                        config=smdp_config(cfg))
    loop = Loop(env, Side(side.learner, side.ours, side.opponent, side.theirs), seed=cfg.train.seed, learning=False)
    env.start_recording(0)
    while loop.rounds_done < 1:
        loop.step()
    replay = env.stop_recording()
    if replay is None:
        return None
    out_dir.mkdir(parents=True, exist_ok=True)
    path = replay.save(out_dir / "last_round.replay.json.gz")
    rp.write_gif(replay, out_dir / "last_round.gif")
    rp.write_html(replay, out_dir / "last_round.html", title=f"confront: {cfg.name}")
    return str(path)
