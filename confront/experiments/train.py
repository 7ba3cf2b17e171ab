"""Training one arm into a run folder: ``train_run`` for every learner (the paper's learners through
:class:`~confront.experiments.episodes.Loop`, PPO tanks through :mod:`confront.experiments.tanks`).

Checkpoints are taken every ``train.checkpoint_every`` rounds and hold everything that changes, so a run killed
at any time and resumed with ``--resume`` ends with exactly the metrics of an uninterrupted run. The run folder
holds ``config.toml``, ``metrics/`` (rounds, sessions), ``model/``, ``plots/``, ``replays/`` and ``summary.json``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import click
import numpy as np

from confront import checkpoint as ck
from confront.arena.smdp import TeamBattleEnv
from confront.config import load_toml, to_dict
from confront.experiments.episodes import (  # the building blocks, re-exported (train.py was their home)
    Loop,
    Side,
    build_learner,
    load_model,
    record_round,
    run_rounds,
    save_model,
    scenario_of,
    smdp_config,
    td_learner,
    td_team,
)
from confront.experiments.spec import ExperimentConfig, config_from_dict
from confront.learning.transfer import TransferParams, TransferPolicy
from confront.runs import Run

__all__ = ["train_run", "print_summary", "new_run", "resume_run", "session_rows",
           "Loop", "Side", "build_learner", "load_model", "record_round", "run_rounds", "save_model", "scenario_of",
           "smdp_config", "td_learner", "td_team"]


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

    run_rounds(loop, tc.rounds, progress, desc=f"{cfg.name} {info['scenario']}", on_rounds=on_rounds,
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
