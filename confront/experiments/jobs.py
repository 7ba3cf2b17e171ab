"""Training jobs and what an experiment reports: the parts ``confront reproduce``, the baselines and the tank
comparison share.

:class:`Job` is one training run (an arm of an experiment at one seed, a run folder); :func:`run_jobs` runs a
list of them in worker processes, respecting dependencies (curriculum sources first), skipping finished ones
and resuming checkpointed ones. :class:`Claim` is one claim tested on the runs, :class:`Outcome` what an
experiment produced.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["VERDICTS", "Job", "Claim", "Outcome", "run_jobs", "slug"]

VERDICTS = {"holds": True, "partly": False, "no": False, "n/a": None}


@dataclass(frozen=True)
class Job:
    """One training run: an arm of an experiment at one seed."""

    experiment: str
    arm: str
    seed: int
    base: str
    overrides: tuple[str, ...]
    folder: Path
    after: tuple[Path, ...] = ()  # run folders that must be finished first (curriculum sources)


@dataclass
class Claim:
    """A claim of the paper, tested on our runs: our values, the tested effect with its 95% interval, p, the
    effect the seeds could detect (power 0.8) and a verdict (holds / partly / no / n/a) with its criterion.

    Given only ``holds``, the verdict is holds / no / n/a; given a verdict, ``holds`` follows from it."""

    text: str
    figure: str
    ours: str
    holds: bool | None = None
    detail: str = ""
    effect: str = ""
    p: str = ""
    mde: str = ""
    verdict: str = ""
    criterion: str = ""

    def __post_init__(self) -> None:
        if not self.verdict:
            self.verdict = {True: "holds", False: "no", None: "n/a"}[self.holds]
        if self.verdict not in VERDICTS:
            raise ValueError(f"bad value verdict={self.verdict!r}: must be one of {', '.join(VERDICTS)}")
        self.holds = VERDICTS[self.verdict]


@dataclass
class Outcome:
    """What an experiment produced."""

    name: str
    claims: list[Claim] = field(default_factory=list)
    figures: list[Path] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    seconds: float = 0.0  # wall time of this call
    run_seconds: float = 0.0  # summed wall time of the training runs (also those reused from an earlier call)
    runs: int = 0
    seeds: int = 0  # seeds actually run per arm
    note: str = ""  # how the claims were obtained when not from this call's runs


def _run_job(job: Job, rounds: int | None, engine: str = "sim") -> str:
    from confront.train.factory import train_run
    from confront.train.spec import load_experiment

    if (job.folder / "summary.json").exists():
        return "cached"
    if (job.folder / "checkpoints" / "LATEST").exists():  # a killed run continues (the engine's per battle)
        train_run(None, job.folder, resume=True, progress=False, engine=engine)
        return "resumed"
    extra = [f"train.seed={job.seed}", "train.replay=false"]
    if rounds is not None:
        extra.append(f"train.rounds={rounds}")
        extra.append(f"train.session_rounds={max(1, min(10, rounds // 2))}")
        if engine == "sim":  # the engine checkpoints after each battle (train.checkpoint_every rounds long)
            extra.append(f"train.checkpoint_every={max(1, rounds // 2)}")
    cfg = load_experiment(job.base, job.overrides + tuple(extra))
    train_run(cfg, job.folder, progress=False, exist_ok=True, engine=engine)
    return "trained"


def run_jobs(jobs: Sequence[Job], rounds: int | None, workers: int, engine: str = "sim") -> None:
    """Run jobs in worker processes, respecting ``after`` dependencies, with one progress bar.

    ``engine="robocode"`` trains every run live in the real engine, one at a time (two engines on two cores
    would skip turns)."""
    if engine == "robocode":
        workers = 1
    from tqdm import tqdm

    done: set[Path] = {j.folder for j in jobs if (j.folder / "summary.json").exists()}
    waiting = [j for j in jobs if j.folder not in done]
    start = time.time()
    with tqdm(total=len(jobs), initial=len(done), desc="runs", unit="run") as bar:
        if workers <= 1:
            while waiting:
                job = next(j for j in waiting if all(a in done for a in j.after))
                waiting.remove(job)
                _run_job(job, rounds, engine)
                done.add(job.folder)
                bar.set_postfix_str(f"{job.experiment}/{job.arm}/s{job.seed} {time.time() - start:.0f}s")
                bar.update(1)
            return
        with ProcessPoolExecutor(max_workers=workers) as pool:
            running: dict[Future[Any], Job] = {}
            while waiting or running:
                ready = [j for j in waiting if all(a in done for a in j.after)]
                for job in ready[: max(0, workers * 2 - len(running))]:
                    waiting.remove(job)
                    running[pool.submit(_run_job, job, rounds)] = job
                if not running:
                    raise RuntimeError("reproduce: jobs wait on runs that never finish (a dependency cycle)")
                fut = next(as_completed(running))
                job = running.pop(fut)
                fut.result()
                done.add(job.folder)
                bar.set_postfix_str(f"{job.experiment}/{job.arm}/s{job.seed} {time.time() - start:.0f}s")
                bar.update(1)


def slug(text: str) -> str:
    """A folder-safe name: lower case, every other character a dash."""
    return "".join(c if c.isalnum() else "-" for c in text.lower()).strip("-")
