"""The one training loop: any :class:`Trainer` advanced round by round, and a run folder around it.

    Trainer.advance() until train.rounds (run_rounds) -> rows -> sessions, model, plots (run_trainer)

A :class:`Trainer` plays and learns in steps and holds all it changes as data. Four implement it, one per learner
and backend (``confront.train.factory`` picks one): ``paper_sim.SMDPTrainer``, ``paper_engine.EngineTrainer``,
``ppo_sim.TankTrainer`` and ``ppo_engine.EngineTankTrainer``. :func:`run_rounds` advances any of them (also the
TD team's pre-training); :func:`run_trainer` wraps it in a run folder, the same for all four: resume, progress bar,
TensorBoard scalars (``tb/``), checkpoints every ``train.checkpoint_every`` rounds, then the run's tables,
summary and figures.

Checkpoints hold everything that changes, so a simulator run killed at any time and resumed with ``--resume``
ends with exactly the metrics of an uninterrupted run (an engine run loses at most the battle that was running).
The run folder holds ``config.toml``, ``metrics/`` (rounds, sessions), ``model/``, ``plots/``, ``tb/``,
``checkpoints/`` and ``summary.json``. Rows are one per round (``score_ours``, ``score_theirs``, ``won``, ...);
here too what the summaries make of them: pooled shares, sessions, shares per opponent.
"""

from __future__ import annotations

import hashlib
import math
import signal
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

import click
import numpy as np

from confront import checkpoint as ck
from confront.config import load_toml, to_dict
from confront.runs import Interrupted, Run
from confront.train.spec import ExperimentConfig, config_from_dict

__all__ = ["Trainer", "RunFinished", "run_rounds", "run_trainer", "new_run", "resume_run",
           "pooled_share", "session_rows",
           "share_by_opponent", "share_windows", "print_summary"]


class Trainer(Protocol):
    """One learner on one battle backend, advanced step by step; its state is data (checkpoints)."""

    engine: str  # the backend, "sim" or "robocode" (checkpoints say which)
    desc: str  # progress-bar label
    bar_scalars: dict[str, str]  # scalar name -> progress-bar label
    final_window: int  # rounds the summary's final score ratio pools

    @classmethod
    def from_config(cls, cfg: ExperimentConfig, run: Run, progress: bool = False,
                    cpu_constant_ms: float | None = None) -> Trainer:
        """The trainer of ``cfg`` writing into ``run`` (``factory.make_trainer``); ``cpu_constant_ms``: the
        engine's CPU constant (the engine trainers' default if None)."""
        ...

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


# -- rows --------------------------------------------------------------------------------------------------------

def pooled_share(rows: list[dict[str, Any]]) -> float:
    """Our score over both sides' (pooled over ``rows``; 0.5 when nobody scored)."""
    o = sum(r["score_ours"] for r in rows)
    t = sum(r["score_theirs"] for r in rows)
    return o / (o + t) if o + t > 0 else 0.5


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


def share_by_opponent(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Pooled score share per opponent over ``rows``."""
    out: dict[str, list[float]] = {}
    for r in rows:
        o = out.setdefault(r["opponent"], [0.0, 0.0])
        o[0] += r["score_ours"]
        o[1] += r["score_theirs"]
    return {k: v[0] / (v[0] + v[1]) if v[0] + v[1] > 0 else 0.5 for k, v in out.items()}


def share_windows(rows: list[dict[str, Any]], size: int) -> list[tuple[int, float]]:
    """(rounds so far, pooled score share) per consecutive window of ``size`` rounds (a partial last one dropped;
    rows read back from a run's CSV tables too)."""
    out = []
    for end in range(size, len(rows) + 1, size):
        chunk = rows[end - size:end]
        o = sum(float(r["score_ours"]) for r in chunk)
        t = sum(float(r["score_theirs"]) for r in chunk)
        out.append((end, o / (o + t) if o + t > 0 else 0.5))
    return out


# -- the loop ----------------------------------------------------------------------------------------------------

def run_rounds(trainer: Any, rounds: int, progress: bool, desc: str | None = None, on_step: Any = None,
               window: int = 10) -> None:
    """The one training loop: ``trainer.advance`` until ``rounds`` rounds are done (any :class:`Trainer`), with a
    progress bar (the share of the last ``window`` rounds and the trainer's ``bar_scalars``); ``on_step(scalars)``
    after every step in which rounds ended."""
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


# -- run folders -------------------------------------------------------------------------------------------------

class RunFinished(FileExistsError):
    """``--resume`` of a run that ended (it has its summary.json): nothing is trained again."""


def resume_run(out: str | Path | None) -> tuple[Run, ExperimentConfig]:
    """An existing run folder, locked for this run, and the config it was started with (for ``--resume``);
    :class:`RunFinished` if it ended."""
    if out is None:
        raise ValueError("resume needs the run folder")
    path = Path(out)
    if not (path / "config.toml").exists():
        raise FileNotFoundError(f"{path} is not a run folder (no config.toml)")
    run = Run.open(path)
    try:
        if (path / "summary.json").exists():
            raise RunFinished(f"{path} is finished (it has its summary.json): nothing to resume; train longer in a "
                              "new run (confront train -c CONFIG --set train.rounds=N)")
        return run, config_from_dict(load_toml(path / "config.toml"))
    except BaseException:
        run.release()
        raise


def new_run(cfg: ExperimentConfig, out: str | Path | None, exist_ok: bool = False) -> Run:
    """A new run folder ``out`` (default ``runs/<name>-<time>``) holding the resolved config, locked for this
    run until :meth:`Run.release`."""
    from confront.runs import new_run_name

    return Run.create(Path(out) if out is not None else Path("runs") / new_run_name(cfg.name), to_dict(cfg),
                      exist_ok=exist_ok, lock=True)


def _config_digest(run: Run) -> str:
    """SHA-256 of the run's config.toml: a checkpoint records it, a resume compares it."""
    return hashlib.sha256((run.path / "config.toml").read_bytes()).hexdigest()


def _check_fits(fresh: tuple[dict[str, np.ndarray], dict[str, Any]], arrays: dict[str, np.ndarray],
                meta: dict[str, Any], where: Path) -> None:
    """A checkpoint's arrays and counters against what this config's trainer holds (``fresh``, its state before
    loading): every array both have of one shape and type, every counter a whole number >= 0 of the same kind,
    every other metadata value of the same type; CheckpointError naming the first that is not."""
    ref_arrays, ref_meta = fresh
    for k in sorted(set(ref_arrays) & set(arrays)):
        a, r = arrays[k], ref_arrays[k]
        if a.shape != r.shape or a.dtype.kind != r.dtype.kind:
            raise ck.CheckpointError(f"{where}: array {k} is {a.dtype.kind}{list(a.shape)}, this run's config makes "
                                     f"{r.dtype.kind}{list(r.shape)}")
    for k in sorted(set(ref_meta) & set(meta)):
        v, r = meta[k], ref_meta[k]
        if isinstance(r, bool) or isinstance(v, bool):
            ok = isinstance(r, bool) and isinstance(v, bool)
        elif isinstance(r, int):
            ok = isinstance(v, int) and v >= 0
        elif isinstance(r, float):
            ok = isinstance(v, int | float) and math.isfinite(v)
        else:
            ok = type(v) is type(r)
        if not ok:
            raise ck.CheckpointError(f"{where}: {k} = {str(v)[:40]} does not fit this run ({type(r).__name__})")


STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class _StopOnSignal:
    """Ctrl-C (or SIGTERM) during training sets :attr:`asked`; the loop saves after the step it is in and stops. A
    second Ctrl-C interrupts at once (KeyboardInterrupt). Outside the main thread nothing is installed."""

    def __init__(self) -> None:
        self.asked = False
        self._old: dict[int, Any] = {}

    def __enter__(self) -> _StopOnSignal:
        if threading.current_thread() is threading.main_thread():
            for sig in STOP_SIGNALS:
                self._old[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum: int, frame: Any) -> None:
        if self.asked:
            raise KeyboardInterrupt
        self.asked = True
        click.echo("\nstopping after this step (a checkpoint is saved; Ctrl-C again to stop at once)", err=True)

    def __exit__(self, *exc: object) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old)


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


def run_trainer(cfg: ExperimentConfig, run: Run, trainer: Trainer, resume: bool, progress: bool,
                setup_s: float) -> dict[str, Any]:
    """Train ``trainer`` to ``train.rounds`` rounds in ``run`` (from its latest checkpoint with ``resume``):
    checkpoints, TensorBoard scalars, the rounds and sessions tables, the trainer's own outputs and the summary,
    which it returns."""
    from torch.utils.tensorboard import SummaryWriter

    elapsed_before = 0.0
    digest = _config_digest(run)
    if resume and (latest := ck.latest(run.checkpoints)) is not None:
        arrays, meta = ck.load(latest)
        if meta.get("engine", "sim") != trainer.engine:
            raise ck.CheckpointError(f"{latest} was trained with --engine {meta.get('engine', 'sim')}: resume it "
                                     f"with that engine")
        if meta.get("config_sha256", digest) != digest:  # checkpoints of older versions carry no digest
            raise ck.CheckpointError(f"{run.path / 'config.toml'} was edited after {latest.name} was saved: put it "
                                     "back, or start a new run with the edited config (confront train -c FILE)")
        _check_fits(trainer.state(), arrays, meta, latest)
        trainer.load(arrays, meta)
        elapsed_before = float(meta.get("elapsed_s", 0.0))
        click.echo(f"resuming {run.path} from {latest.name} ({trainer.rounds_done} rounds done)", err=not progress)
    elif resume:
        click.echo(f"note: {run.path} has no checkpoint yet: training starts from round 0", err=True)
    tc = cfg.train
    total, every, window = tc.rounds, tc.checkpoint_every, min(tc.session_rounds, 200)
    start = time.time()
    next_ckpt = (trainer.rounds_done // every + 1) * every
    # a resumed run's scalars past its checkpoint were logged before the kill: TensorBoard drops them (purge_step)
    writer = SummaryWriter(str(run.path / "tb"), purge_step=trainer.decisions + 1 if resume else None)
    in_csv = 0  # rows in metrics/rounds.csv (rewritten whole at the first checkpoint, also after a resume)
    stop = _StopOnSignal()

    def save() -> str:
        nonlocal in_csv
        arrays, meta = trainer.state()
        meta.update(engine=trainer.engine, elapsed_s=elapsed_before + time.time() - start, config_sha256=digest)
        name = f"round-{trainer.rounds_done:06d}"
        ck.save(run.checkpoints, name, arrays, meta)
        in_csv = run.append_table("rounds", trainer.rows, in_csv)
        return name

    def on_step(scalars: dict[str, float]) -> None:
        nonlocal next_ckpt
        _log(writer, trainer, scalars, window)
        if next_ckpt <= trainer.rounds_done < total or (stop.asked and trainer.rounds_done < total):
            name = save()
            next_ckpt = (trainer.rounds_done // every + 1) * every
            if stop.asked:
                raise Interrupted(run.path, trainer.rounds_done, run.checkpoints / name)

    try:
        with stop:
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


# -- the terminal ------------------------------------------------------------------------------------------------

def print_summary(summary: dict[str, Any]) -> None:
    """The results table of a run, for the terminal."""
    if summary.get("learner") == "ppo":
        return _print_ppo_summary(summary)
    run = Run(Path(summary["run"]))
    sessions = run.read_table("sessions")
    where = " in Robocode" if summary.get("engine") == "robocode" else ""
    click.echo(f"\n{summary['name']}: {summary['rounds']} rounds of {summary['scenario']}{where} in "
               f"{summary['wall_time_s']:.1f} s ({summary['decisions']} decisions)")
    if sessions:
        click.echo("\n| session | score ours | score theirs | score ratio | defensive ours | win rate |")
        click.echo("|---:|---:|---:|---:|---:|---:|")
        for s in _some(sessions):
            click.echo(f"| {s['session']} | {s['score_ours']:.0f} | {s['score_theirs']:.0f} | "
                       f"{s['score_ratio']:.3f} | {s.get('defensive_ours', math.nan):.0f} | {s['win_rate']:.2f} |")
    click.echo(f"\nscore ratio over the last {summary['final_window_rounds']} rounds: "
               f"{summary['final_score_ratio']:.3f} (win rate {summary['win_rate_last']:.2f})")
    click.echo(f"run folder: {summary['run']}  (plots/, metrics/, model/, tb/, summary.json)")


def _print_ppo_summary(summary: dict[str, Any]) -> None:
    """The results table of a PPO run: sessions, then the share per opponent."""
    run = Run(Path(summary["run"]))
    sessions = run.read_table("sessions")
    click.echo(f"\n{summary['name']}: {summary['rounds']} rounds against the league in {summary['wall_time_s']:.1f} s "
               f"({summary['decisions']:,} decisions, {summary['decisions_per_s']:,.0f}/s)")
    if sessions:
        click.echo("\n| session | decisions | score ours | score theirs | score share | win rate |")
        click.echo("|---:|---:|---:|---:|---:|---:|")
        for s in _some(sessions):
            click.echo(f"| {s['session']} | {int(float(s['decisions'])):,} | {float(s['score_ours']):.0f} | "
                       f"{float(s['score_theirs']):.0f} | {float(s['score_ratio']):.3f} | {float(s['win_rate']):.2f} |")
    click.echo(f"\nscore share over the last {summary['final_window_rounds']} rounds, per opponent:")
    for name, v in sorted(summary["share_by_opponent_last"].items()):
        click.echo(f"  {name:<18} {v:.3f}")
    click.echo(f"all: {summary['final_score_ratio']:.3f} (first session {summary['first_session_ratio']:.3f}, "
               f"last {summary['last_session_ratio']:.3f})")
    click.echo(f"run folder: {summary['run']}  (plots/, metrics/, model/, tb/, summary.json)")


def _some(sessions: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """About ten sessions, evenly spaced, and the last."""
    step = max(1, len(sessions) // 10)
    return sessions[::step] + ([sessions[-1]] if (len(sessions) - 1) % step else [])
