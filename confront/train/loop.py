"""The one training loop: any learner over any battle backend, into a run folder.

    config -> Trainer (learner x backend) -> advance() until train.rounds -> rows -> sessions, model, plots

A :class:`Trainer` plays and learns in steps and holds all it changes as data. Four implement it:
:class:`~confront.experiments.episodes.SMDPTrainer` (the paper's learners in the simulator),
:class:`~confront.experiments.tanks.TankTrainer` (PPO tanks in the simulator's league),
:class:`~confront.experiments.train_engine.EngineTrainer` (the paper's learners live in Robocode, one battle
per step) and :class:`~confront.experiments.tanks_engine.EngineTankTrainer` (PPO tanks in Robocode, one battle
and one update per step). One loop advances them all, :func:`~confront.experiments.episodes.run_rounds` (also
the TD team's pre-training); :func:`train_run` wraps it in a run folder, the same for all four: resume, progress bar,
TensorBoard scalars (``tb/``), checkpoints every ``train.checkpoint_every`` rounds, then the run's tables,
summary and figures.

Checkpoints hold everything that changes, so a simulator run killed at any time and resumed with ``--resume``
ends with exactly the metrics of an uninterrupted run (an engine run loses at most the battle that was running).
The run folder holds ``config.toml``, ``metrics/`` (rounds, sessions), ``model/``, ``plots/``, ``tb/``,
``checkpoints/`` and ``summary.json``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

import click
import numpy as np

from confront import checkpoint as ck
from confront.config import ConfigError, load_toml, to_dict
from confront.experiments.episodes import (  # the building blocks, re-exported (train.py was their home)
    Loop,
    Side,
    SMDPTrainer,
    build_learner,
    load_model,
    pooled_share,
    record_round,
    run_rounds,
    save_model,
    scenario_of,
    smdp_config,
    td_learner,
    td_team,
)
from confront.experiments.spec import ExperimentConfig, config_from_dict
from confront.runs import Run

__all__ = ["Trainer", "SMDPTrainer", "make_trainer", "train_run", "print_summary", "new_run", "resume_run",
           "session_rows", "Loop", "Side", "build_learner", "load_model", "record_round", "run_rounds", "save_model",
           "scenario_of", "smdp_config", "td_learner", "td_team"]

ENGINES = ("sim", "robocode")


class Trainer(Protocol):
    """One learner on one battle backend, advanced step by step; its state is data (checkpoints)."""

    engine: str  # the backend, "sim" or "robocode" (checkpoints say which)
    desc: str  # progress-bar label
    bar_scalars: dict[str, str]  # scalar name -> progress-bar label
    final_window: int  # rounds the summary's final score ratio pools

    @property
    def rows(self) -> list[dict[str, Any]]:
        """One per round, in the order rounds ended."""
        ...

    @property
    def decisions(self) -> int: ...

    @property
    def rounds_done(self) -> int: ...

    def advance(self, limit: int, tick: Callable[[int], None]) -> dict[str, float]:
        """Play (and learn) one step towards ``limit`` rounds; ``tick(rounds)`` reports rounds done within a long
        step. Returns the step's scalars (TensorBoard)."""
        ...

    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]: ...

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None: ...

    def finish(self, run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]]) -> dict[str, Any]:
        """Write the model and the trainer's own tables and figures; return its summary keys."""
        ...

    def close(self) -> None: ...


def make_trainer(cfg: ExperimentConfig, run: Run, engine: str = "sim", progress: bool = False,
                 cpu_constant_ms: float | None = None) -> Trainer:
    """The trainer of ``cfg``'s learner on ``engine`` (imports the backend it needs only)."""
    if engine not in ENGINES:
        raise ConfigError(f"engine must be one of {ENGINES}, got {engine!r}")
    if cfg.train.init and cfg.learner.kind != "ppo":
        raise ConfigError("train.init starts a PPO learner from a run's model; for the paper's learners use "
                          "transfer.source")
    if cfg.learner.kind == "ppo":
        if engine == "robocode":
            from confront.experiments.tanks_engine import EngineTankTrainer

            return EngineTankTrainer(cfg, run, progress=progress, cpu_constant_ms=cpu_constant_ms)
        if cfg.train.init:
            raise ConfigError("train.init (a PPO run to start from) is used in the engine only (--engine robocode)")
        from confront.experiments.tanks import TankTrainer

        return TankTrainer(cfg, progress=progress)
    if engine == "robocode":
        from confront.experiments.train_engine import EngineTrainer

        return EngineTrainer(cfg, run, progress=progress, cpu_constant_ms=cpu_constant_ms)
    return SMDPTrainer.from_config(cfg, progress=progress)


# -- run folders -------------------------------------------------------------------------------------------------

def session_rows(rows: list[dict[str, Any]], size: int) -> list[dict[str, Any]]:
    """Aggregate round rows into sessions of ``size`` rounds (paper: 10); the score ratio pools the sums. Score
    parts the rows carry are summed; ``decisions`` and ``wall_s`` are the session's last round's."""
    out: list[dict[str, Any]] = []
    summed = [k for k in ("defensive_ours", "defensive_theirs", "bullet_damage_ours", "bullet_damage_theirs")
              if rows and k in rows[0]]
    last = [k for k in ("decisions", "wall_s") if rows and k in rows[0]]
    for start in range(0, len(rows) - size + 1, size):
        chunk = rows[start:start + size]
        ratio = pooled_share(chunk)
        out.append({
            "session": len(out) + 1, "rounds": len(chunk), "score_ours": sum(r["score_ours"] for r in chunk),
            "score_theirs": sum(r["score_theirs"] for r in chunk),
            "score_ratio": ratio,
            "fluctuation": ratio - out[-1]["score_ratio"] if out else 0.0,  # Fig. 11: first difference
            "win_rate": sum(r["won"] for r in chunk) / len(chunk),
            **{k: sum(r[k] for r in chunk) for k in summed}, **{k: chunk[-1][k] for k in last},
        })
    return out


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


def _log(writer: Any, trainer: Trainer, scalars: dict[str, float], window: int) -> None:
    """TensorBoard scalars at the trainer's decision count: score share (overall, per opponent) and the step's."""
    step = trainer.decisions
    recent = trainer.rows[-window:]
    writer.add_scalar("share/all", pooled_share(recent), step)
    for name in sorted({r["opponent"] for r in recent if "opponent" in r}):
        writer.add_scalar(f"share/{name}", pooled_share([r for r in recent if r.get("opponent") == name]), step)
    for k, v in scalars.items():
        if isinstance(v, int | float) and math.isfinite(v):
            writer.add_scalar(f"train/{k}", v, step)


def train_run(cfg: ExperimentConfig | None, out: str | Path | None, resume: bool = False, progress: bool = True,
              exist_ok: bool = False, engine: str = "sim", cpu_constant_ms: float | None = None) -> dict[str, Any]:
    """Train ``cfg``'s learner on ``engine`` ("sim" or "robocode") into a run folder, or continue the run in
    ``out`` with ``resume`` (its own config); return the summary."""
    t_setup = time.time()
    if resume:
        run, cfg = resume_run(out)
    elif cfg is None:
        raise ValueError("train_run needs a config unless resuming")
    else:
        run = new_run(cfg, out, exist_ok)
    try:
        trainer = make_trainer(cfg, run, engine, progress=progress, cpu_constant_ms=cpu_constant_ms)
    except Exception:
        run.discard_if_new()  # a failed start leaves no half-made run folder
        raise
    try:
        return _train(cfg, run, trainer, resume, progress, setup_s=time.time() - t_setup)
    finally:
        trainer.close()


def _train(cfg: ExperimentConfig, run: Run, trainer: Trainer, resume: bool, progress: bool,
           setup_s: float) -> dict[str, Any]:
    from torch.utils.tensorboard import SummaryWriter

    elapsed_before = 0.0
    if resume and (latest := ck.latest(run.checkpoints)) is not None:
        arrays, meta = ck.load(latest)
        if meta.get("engine", "sim") != trainer.engine:
            raise ck.CheckpointError(f"{latest} was trained with --engine {meta.get('engine', 'sim')}: resume it "
                                     f"with that engine")
        trainer.load(arrays, meta)
        elapsed_before = float(meta.get("elapsed_s", 0.0))
        if progress:
            click.echo(f"resuming {run.path} from {latest.name} ({trainer.rounds_done} rounds done)")
    tc = cfg.train
    total, every, window = tc.rounds, tc.checkpoint_every, min(tc.session_rounds, 200)
    start = time.time()
    next_ckpt = (trainer.rounds_done // every + 1) * every
    writer = SummaryWriter(str(run.path / "tb"))
    in_csv = 0  # rows in metrics/rounds.csv (rewritten whole at the first checkpoint, also after a resume)

    def on_step(scalars: dict[str, float]) -> None:
        nonlocal next_ckpt, in_csv
        _log(writer, trainer, scalars, window)
        if next_ckpt <= trainer.rounds_done < total:
            arrays, meta = trainer.state()
            meta.update(engine=trainer.engine, elapsed_s=elapsed_before + time.time() - start)
            ck.save(run.checkpoints, f"round-{trainer.rounds_done:06d}", arrays, meta)
            in_csv = run.append_table("rounds", trainer.rows, in_csv)
            next_ckpt = (trainer.rounds_done // every + 1) * every

    try:
        run_rounds(trainer, total, progress, on_step=on_step, window=window)
    finally:
        writer.close()
    rows = trainer.rows
    sessions = session_rows(rows, tc.session_rounds)
    run.write_table("rounds", rows)
    run.write_table("sessions", sessions)
    tail = rows[-min(trainer.final_window, len(rows)):]
    summary: dict[str, Any] = {
        "name": cfg.name, "run": str(run.path), "engine": trainer.engine, "rounds": len(rows),
        "sessions": len(sessions), "decisions": trainer.decisions,
        "final_score_ratio": pooled_share(tail), "final_window_rounds": len(tail),
        "first_session_ratio": sessions[0]["score_ratio"] if sessions else math.nan,
        "last_session_ratio": sessions[-1]["score_ratio"] if sessions else math.nan,
        "win_rate_last": sum(r["won"] for r in tail) / max(1, len(tail)),
        "score_ours": sum(r["score_ours"] for r in rows), "score_theirs": sum(r["score_theirs"] for r in rows),
        "wall_time_s": elapsed_before + time.time() - start, "setup_s": setup_s,
    }
    summary.update(trainer.finish(run, rows, sessions))
    run.write_summary(summary)
    return summary


def print_summary(summary: dict[str, Any]) -> None:
    """The results table of a run, for the terminal."""
    if summary.get("learner") == "ppo":
        from confront.experiments.tanks import print_tank_summary

        return print_tank_summary(summary)
    run = Run(Path(summary["run"]))
    sessions = run.read_table("sessions")
    where = " in Robocode" if summary.get("engine") == "robocode" else ""
    click.echo(f"\n{summary['name']}: {summary['rounds']} rounds of {summary['scenario']}{where} in "
               f"{summary['wall_time_s']:.1f} s ({summary['decisions']} decisions)")
    if sessions:
        click.echo("\n| session | score ours | score theirs | score ratio | defensive ours | win rate |")
        click.echo("|---:|---:|---:|---:|---:|---:|")
        step = max(1, len(sessions) // 10)
        for s in sessions[::step] + ([sessions[-1]] if (len(sessions) - 1) % step else []):
            click.echo(f"| {s['session']} | {s['score_ours']:.0f} | {s['score_theirs']:.0f} | "
                       f"{s['score_ratio']:.3f} | {s.get('defensive_ours', math.nan):.0f} | {s['win_rate']:.2f} |")
    click.echo(f"\nscore ratio over the last {summary['final_window_rounds']} rounds: "
               f"{summary['final_score_ratio']:.3f} (win rate {summary['win_rate_last']:.2f})")
    click.echo(f"run folder: {summary['run']}  (plots/, metrics/, model/, tb/, summary.json)")
