"""Which trainer trains a config, and the run it trains into: :func:`train_run` (``confront train``).

    config -> make_trainer (learner x backend) -> loop.run_trainer -> run folder, summary

    the paper's learners (dmnn, ssaq, random):  sim: paper_sim.SMDPTrainer   robocode: paper_engine.EngineTrainer
    ppo:                                        sim: ppo_sim.TankTrainer     robocode: ppo_engine.EngineTankTrainer
    ppo with a Ray address (--address):         sim: ppo_ray.RayTankTrainer (rollout workers as Ray actors)

Each backend's modules are imported only when its trainer is made.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from confront import checkpoint as ck
from confront.config import ConfigError
from confront.runs import Run
from confront.train.loop import Trainer, new_run, resume_run, run_trainer
from confront.train.spec import ExperimentConfig

__all__ = ["ENGINES", "make_trainer", "trainer_class", "train_run"]

ENGINES = ("sim", "robocode")


def make_trainer(cfg: ExperimentConfig, run: Run, engine: str = "sim", progress: bool = False,
                 cpu_constant_ms: float | None = None, address: str | None = None, workers: int = 1) -> Trainer:
    """The trainer of ``cfg``'s learner on ``engine`` (imports the backend it needs only); with ``address`` PPO's
    rollouts on ``workers`` Ray actors of that cluster (``ppo_ray``)."""
    if engine not in ENGINES:
        raise ConfigError(f"engine must be one of {ENGINES}, got {engine!r}")
    if address is not None:
        if engine != "sim" or cfg.learner.kind != "ppo":
            raise ConfigError("--address runs PPO's rollouts on Ray: it needs learner.kind = \"ppo\" and the "
                              "simulator (--engine sim)")
        from confront.train.ppo_ray import RayTankTrainer

        return RayTankTrainer(cfg, address, workers, progress=progress)
    if cfg.train.init and cfg.learner.kind != "ppo":
        raise ConfigError("train.init starts a PPO learner from a run's model; for the paper's learners use "
                          "transfer.source")
    if cfg.train.init and engine != "robocode":
        raise ConfigError("train.init (a PPO run to start from) is used in the engine only (--engine robocode)")
    return trainer_class(cfg.learner.kind, engine).from_config(cfg, run, progress, cpu_constant_ms)


def trainer_class(learner: str, engine: str) -> type[Trainer]:
    """The trainer of ``learner`` (``learner.kind``: ppo, or one of the paper's) on ``engine``."""
    if learner == "ppo":
        if engine == "robocode":
            from confront.train.ppo_engine import EngineTankTrainer

            return EngineTankTrainer
        from confront.train.ppo_sim import TankTrainer

        return TankTrainer
    if engine == "robocode":
        from confront.train.paper_engine import EngineTrainer

        return EngineTrainer
    from confront.train.paper_sim import SMDPTrainer

    return SMDPTrainer


def train_run(cfg: ExperimentConfig | None, out: str | Path | None, resume: bool = False, progress: bool = True,
              exist_ok: bool = False, engine: str = "sim", cpu_constant_ms: float | None = None,
              address: str | None = None, workers: int | None = None) -> dict[str, Any]:
    """Train ``cfg``'s learner on ``engine`` ("sim" or "robocode") into a run folder, or continue the run in
    ``out`` with ``resume`` (its own config); return the summary. ``address``: PPO's rollouts on ``workers`` Ray
    actors (default 1; a resumed run's own count)."""
    t_setup = time.time()
    if workers is not None and address is None:
        raise ConfigError("--workers is the number of Ray rollout workers: give --address too")
    if resume:
        run, cfg = resume_run(out)  # the run folder's lock held from here (runs.RunLock)
        try:
            workers = _resume_workers(run, address, workers)
        except BaseException:
            run.release()
            raise
    elif cfg is None:
        raise ValueError("train_run needs a config unless resuming")
    else:
        run = new_run(cfg, out, exist_ok)
    try:
        trainer = make_trainer(cfg, run, engine, progress=progress, cpu_constant_ms=cpu_constant_ms, address=address,
                               workers=workers or 1)
    except BaseException:
        run.discard_if_new()  # a failed start leaves no half-made run folder (and drops the lock)
        raise
    try:
        return run_trainer(cfg, run, trainer, resume, progress, setup_s=time.time() - t_setup)
    finally:
        try:
            trainer.close()
        finally:
            run.release()


def _resume_workers(run: Run, address: str | None, workers: int | None) -> int | None:
    """The rollout workers a resumed run continues with: its latest checkpoint's (``rollout_workers``; 0 for a
    local run); CheckpointError if ``address`` or ``workers`` do not fit it (checked before Ray is started)."""
    latest = ck.latest(run.checkpoints, notice=None)
    if latest is None:
        return workers
    try:
        held = json.loads((latest / "meta.json").read_text(encoding="utf-8")).get("rollout_workers", 0)
    except (OSError, ValueError, AttributeError):
        return workers  # run_trainer's check of the checkpoint names what is wrong
    if isinstance(held, bool) or not isinstance(held, int) or not 0 <= held <= 4096:
        raise ck.CheckpointError(f"{latest} has rollout_workers = {str(held)[:40]}: not a worker count")
    if held and address is None:
        raise ck.CheckpointError(f"{run.path} was trained on Ray with {held} rollout workers: resume it with "
                                 f"--address HOST:PORT|auto")
    if not held and address is not None:
        raise ck.CheckpointError(f"{run.path} was trained without --address: resume it without --address")
    if held and workers is not None and workers != held:
        raise ck.CheckpointError(f"{run.path} was trained with {held} rollout workers: resume it with --workers "
                                 f"{held} (or leave --workers out)")
    return held or workers
