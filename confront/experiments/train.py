"""Training one arm: the learning team against its opponents in the batched simulator (paper Algorithm 2).

The whole loop is in this file. Per SMDP step (T engine turns):

    observations (B, R) --learner.act--> our actions --+--> env.step --> rewards (B, R, T), next obs
                        --opponent.act-> their actions -+        |
    learner.learn(transitions of our living tanks)  <-----------+   (parameter sharing: one learner, all tanks)

B battles run side by side and share out the configured number of rounds; rounds are numbered in the
order they end (deterministic for a seed). Checkpoints are taken every ``train.checkpoint_every`` rounds
and hold everything that changes (arena arrays, learner, opponent, RNG states, metrics so far), so a run
killed at any time and resumed with ``--resume`` ends with exactly the metrics of an uninterrupted run.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import time
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
from confront.config import ConfigError, load_toml, to_dict
from confront.engine.java_build import cache_root
from confront.experiments.spec import ExperimentConfig, config_from_dict
from confront.learning.base import Learner, Transition
from confront.learning.factory import load_learner, make_learner, save_learner
from confront.learning.tabular import TabularQ
from confront.learning.transfer import TransferParams, TransferPolicy
from confront.runs import Run

__all__ = ["train_run", "print_summary", "build_learner", "load_model", "save_model", "scenario_of", "td_team",
           "new_run", "resume_run"]


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
    common = dict(n_actions=n_actions, gamma=lc.gamma, alpha=lc.alpha, rate=lc.learning_rate, backup=lc.backup,
                  exploration="boltzmann", t_max=lc.t_max, t_min=lc.t_min, eta=lc.eta)
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
        _run(loop, oc.pretrain_rounds, progress=progress, desc="TD team pre-training")
    save_model(cache, learner, {"trained_rounds": oc.pretrain_rounds, "against": oc.pretrain_against})
    return learner, cache


def _run(loop: Loop, rounds: int, progress: bool, desc: str, on_rounds: Any = None, session: int = 10) -> None:
    from tqdm import tqdm

    bar = tqdm(total=rounds, initial=min(loop.rounds_done, rounds), desc=desc, unit="round", disable=not progress,
               dynamic_ncols=True, leave=True)
    try:
        while loop.rounds_done < rounds:
            ended = loop.step()
            if not ended:
                continue
            loop.rows.extend(ended)
            if len(loop.rows) > rounds:
                del loop.rows[rounds:]
                loop.rounds_done = rounds
            bar.update(min(loop.rounds_done, rounds) - bar.n)
            recent = loop.rows[-session:]
            o = sum(r["score_ours"] for r in recent)
            t = sum(r["score_theirs"] for r in recent)
            diag = loop.side.learner.diagnostics()
            bar.set_postfix(score_ratio=f"{o / (o + t) if o + t else 0.5:.3f}",
                            T=f"{diag.get('temperature', 0):.3f}", refresh=False)
            if on_rounds is not None:
                on_rounds(loop)
    finally:
        bar.close()


# -- run folders -------------------------------------------------------------------------------------------------

def session_rows(rows: list[dict[str, Any]], size: int) -> list[dict[str, Any]]:
    """Aggregate round rows into sessions of ``size`` rounds (paper: 10); the score ratio pools the sums."""
    out: list[dict[str, Any]] = []
    for start in range(0, len(rows) - size + 1, size):
        chunk = rows[start:start + size]
        o = sum(r["score_ours"] for r in chunk)
        t = sum(r["score_theirs"] for r in chunk)
        ratio = o / (o + t) if o + t > 0 else 0.5
        out.append({
            "session": len(out) + 1, "rounds": len(chunk), "score_ours": o, "score_theirs": t,
            "score_ratio": ratio,
            "fluctuation": ratio - out[-1]["score_ratio"] if out else 0.0,  # Fig. 11: first difference
            "defensive_ours": sum(r["defensive_ours"] for r in chunk),
            "defensive_theirs": sum(r["defensive_theirs"] for r in chunk),
            "win_rate": sum(r["won"] for r in chunk) / len(chunk),
            "bullet_damage_ours": sum(r["bullet_damage_ours"] for r in chunk),
            "bullet_damage_theirs": sum(r["bullet_damage_theirs"] for r in chunk),
        })
    return out


def _setup(cfg: ExperimentConfig, progress: bool) -> tuple[Loop, dict[str, Any]]:
    scenario = scenario_of(cfg.arena.scenario)
    smdp = smdp_config(cfg)
    opponents = "td" if cfg.opponent.kind == "td" else cfg.opponent.kind
    env = TeamBattleEnv(scenario, n_battles=cfg.arena.battles, seed=cfg.train.seed, opponents=opponents,
                        config=smdp)
    team = env.team_ids()
    learner = build_learner(cfg, env.n_features, env.n_actions)
    info: dict[str, Any] = {"scenario": scenario.name, "n_actions": env.n_actions, "n_features": env.n_features}
    side = Side(learner, ours=team == 0)
    if cfg.opponent.kind == "td":
        td, where = td_team(cfg, env.n_actions, progress=progress)
        side.opponent, side.theirs, side.opponent_learns = td, team != 0, cfg.opponent.learning
        info["td_model"] = str(where)
    if cfg.transfer.source:
        source, _ = load_model(cfg.transfer.source)
        if (source.n_actions, source.observation) != (learner.n_actions, learner.observation):
            raise ck.CheckpointError(
                f"transfer.source {cfg.transfer.source} has {source.n_actions} actions on {source.observation} "
                f"observations; this task needs {learner.n_actions} on {learner.observation} (Eq. 33)")
        if cfg.transfer.init_from_source:
            learner.load_state_dict(source.state_dict())
        tc = cfg.transfer
        side.learner = TransferPolicy(learner, source, TransferParams(tc.epsilon0, tc.decay, 0, tc.floor))
        info["transfer_source"] = cfg.transfer.source
    return Loop(env, side, seed=cfg.train.seed), info


def resume_run(out: str | Path | None) -> tuple[Run, ExperimentConfig]:
    """An existing run folder and the config it was started with (for ``--resume``)."""
    if out is None:
        raise ValueError("resume needs the run folder")
    run = Run(Path(out))
    if not (run.path / "config.toml").exists():
        raise FileNotFoundError(f"{run.path} is not a run folder (no config.toml)")
    return run, config_from_dict(load_toml(run.path / "config.toml"))


def new_run(cfg: ExperimentConfig, out: str | Path | None, exist_ok: bool = False) -> Run:
    """A new run folder ``out`` (default ``runs/<name>-<time>``) holding the resolved config."""
    from confront.runs import new_run_name

    return Run.create(Path(out) if out is not None else Path("runs") / new_run_name(cfg.name), to_dict(cfg),
                      exist_ok=exist_ok)


def train_run(cfg: ExperimentConfig | None, out: str | Path | None, resume: bool = False, progress: bool = True,
              exist_ok: bool = False) -> dict[str, Any]:
    """Train one arm into a run folder (or continue it with ``resume``); return its summary."""
    start = time.time()
    if resume:
        run, cfg = resume_run(out)
    elif cfg is None:
        raise ValueError("train_run needs a config unless resuming")
    else:
        run = new_run(cfg, out, exist_ok)
    if cfg.learner.kind == "ppo":  # the recommended learner: its own rollout loop over the league (tanks.py)
        from confront.experiments.tanks import TankTrainer, train_tanks

        try:
            trainer = TankTrainer(cfg, progress=progress)
        except Exception:
            run.discard_if_new()  # a failed start leaves no half-made run folder
            raise
        return train_tanks(cfg, run, resume=resume, progress=progress, trainer=trainer)
    try:
        loop, info = _setup(cfg, progress)
    except Exception:
        run.discard_if_new()  # a failed start leaves no half-made run folder
        raise
    elapsed_before = 0.0
    if resume:
        latest = ck.latest(run.checkpoints)
        if latest is not None:
            arrays, meta = ck.load(latest)
            if meta.get("engine") == "robocode":
                raise ck.CheckpointError(f"{latest} was trained in the real engine: resume it with --engine robocode")
            loop.load(arrays, meta)
            elapsed_before = float(meta.get("elapsed_s", 0.0))
            if progress:
                click.echo(f"resuming {run.path} from {latest.name} ({loop.rounds_done} rounds done)")
    tc = cfg.train
    next_ckpt = [(loop.rounds_done // tc.checkpoint_every + 1) * tc.checkpoint_every]

    def on_rounds(lp: Loop) -> None:
        if lp.rounds_done >= next_ckpt[0] and lp.rounds_done < tc.rounds:
            arrays, meta = lp.state()
            meta["elapsed_s"] = elapsed_before + time.time() - start
            ck.save(run.checkpoints, f"round-{lp.rounds_done:06d}", arrays, meta)
            run.write_table("rounds", lp.rows)
            next_ckpt[0] = (lp.rounds_done // tc.checkpoint_every + 1) * tc.checkpoint_every

    _run(loop, tc.rounds, progress, desc=f"{cfg.name} {info['scenario']}", on_rounds=on_rounds,
         session=tc.session_rounds)
    rows = loop.rows[: tc.rounds]
    sessions = session_rows(rows, tc.session_rounds)
    run.write_table("rounds", rows)
    run.write_table("sessions", sessions)
    save_model(run.path / "model", loop.side.learner,
               {"scenario": info["scenario"], "decision_turns": cfg.arena.decision_turns,
                "fire_power_actions": cfg.arena.fire_power_actions, "target": cfg.arena.target})
    figures = _plots(run, rows, sessions, cfg)
    replay = _replay(run, cfg, loop.side) if cfg.train.replay else None
    tail = rows[-min(100, len(rows)):]
    o, t = sum(r["score_ours"] for r in tail), sum(r["score_theirs"] for r in tail)
    summary = {
        "name": cfg.name, "run": str(run.path), "scenario": info["scenario"], "rounds": len(rows),
        "sessions": len(sessions), "decisions": loop.decisions,
        "final_score_ratio": o / (o + t) if o + t else 0.5, "final_window_rounds": len(tail),
        "win_rate_last": sum(r["won"] for r in tail) / max(1, len(tail)),
        "score_ours": sum(r["score_ours"] for r in rows), "score_theirs": sum(r["score_theirs"] for r in rows),
        "learner": loop.side.learner.diagnostics(), "wall_time_s": elapsed_before + time.time() - start,
        "figures": [str(f) for f in figures], "replay": replay, **info,
    }
    run.write_summary(summary)
    return summary


def _plots(run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]], cfg: ExperimentConfig) -> list[Path]:
    from confront.experiments.plots import plot_curves

    if not sessions:
        return []
    ratio = np.array([s["score_ratio"] for s in sessions])
    figs = [plot_curves({cfg.name: ratio}, run.plots / "score_ratio.png", ylabel="score ratio",
                        title=f"{cfg.name}: score ratio per session of {cfg.train.session_rounds} rounds", hline=0.5),
            plot_curves({"ours": np.array([s["score_ours"] for s in sessions]),
                         "theirs": np.array([s["score_theirs"] for s in sessions])},
                        run.plots / "scores.png", ylabel="score per session", title=f"{cfg.name}: scores"),
            plot_curves({"ours": np.array([s["defensive_ours"] for s in sessions]),
                         "theirs": np.array([s["defensive_theirs"] for s in sessions])},
                        run.plots / "defensive.png", ylabel="defensive score per session",
                        title=f"{cfg.name}: defensive score (survival + last-survivor bonus)")]
    return figs


def _replay(run: Run, cfg: ExperimentConfig, side: Side) -> str | None:
    """Record one greedy round of the trained team in a fresh battle: replay JSON, GIF and HTML."""
    try:
        from confront.experiments.evaluate import record_round
    except ImportError:
        return None
    return record_round(cfg, side, run.replays)


def print_summary(summary: dict[str, Any]) -> None:
    """The results table of a run, for the terminal."""
    if summary.get("learner") == "ppo":
        from confront.experiments.tanks import print_tank_summary

        return print_tank_summary(summary)
    run = Run(Path(summary["run"]))
    sessions = run.read_table("sessions")
    click.echo(f"\n{summary['name']}: {summary['rounds']} rounds of {summary['scenario']} in "
               f"{summary['wall_time_s']:.1f} s ({summary['decisions']} decisions)")
    if sessions:
        click.echo("\n| session | score ours | score theirs | score ratio | defensive ours | win rate |")
        click.echo("|---:|---:|---:|---:|---:|---:|")
        step = max(1, len(sessions) // 10)
        for s in sessions[::step] + ([sessions[-1]] if (len(sessions) - 1) % step else []):
            click.echo(f"| {s['session']} | {s['score_ours']:.0f} | {s['score_theirs']:.0f} | "
                       f"{s['score_ratio']:.3f} | {s['defensive_ours']:.0f} | {s['win_rate']:.2f} |")
    click.echo(f"\nscore ratio over the last {summary['final_window_rounds']} rounds: "
               f"{summary['final_score_ratio']:.3f} (win rate {summary['win_rate_last']:.2f})")
    click.echo(f"run folder: {summary['run']}  (plots/, metrics/, model/, summary.json)")
