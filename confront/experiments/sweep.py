"""``confront sweep``: a grid of configs x seeds on Ray, resumable, aggregated into one table.

A grid file is TOML::

    experiment = "fuzzy"            # packaged experiment name or a TOML path (the base config)
    seeds = 3                       # seeds 0 .. seeds-1 for every grid point
    [set]                           # overrides applied to every trial
    "train.rounds" = 100
    [grid]                          # every combination of these values is one grid point
    "learner.learning_rate" = ["fuzzy", "fixed"]
    "learner.alpha" = [0.2, 0.95]

Each trial trains into ``<out>/trials/<point>-s<seed>/`` (a normal run folder). A trial whose
``summary.json`` exists is done and never re-run; one with a checkpoint resumes from it.
"""

from __future__ import annotations

import itertools
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import click
import numpy as np

from confront.config import ConfigError, load_toml, to_toml
from confront.stats import bootstrap_ci


@dataclass(frozen=True)
class Trial:
    """One grid point at one seed."""

    name: str
    point: str
    seed: int
    overrides: tuple[str, ...]


def _value_text(v: Any) -> str:
    return to_toml({"v": v}).split("=", 1)[1].strip()


def read_grid(path: str | Path, seeds: int | None = None) -> tuple[str, list[Trial]]:
    """Parse a grid file into the base experiment and its trials (validated before anything runs)."""
    from confront.train.spec import load_experiment

    data = load_toml(path)
    unknown = set(data) - {"experiment", "seeds", "set", "grid"}
    if unknown:
        raise ConfigError(f"unknown key {sorted(unknown)[0]!r} in grid file: allowed experiment, seeds, set, grid")
    base = data.get("experiment")
    if not isinstance(base, str):
        raise ConfigError("grid file needs experiment = \"<name or path>\"")
    n_seeds = seeds if seeds is not None else data.get("seeds", 3)
    if not isinstance(n_seeds, int) or n_seeds < 1:
        raise ConfigError(f"seeds = {n_seeds!r} must be an integer >= 1")
    fixed = tuple(f"{k}={_value_text(v)}" for k, v in data.get("set", {}).items())
    grid = data.get("grid", {})
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ConfigError(f"grid.{key} = {values!r} must be a non-empty list of values")
    keys = list(grid)
    trials = []
    for combo in itertools.product(*(grid[k] for k in keys)) if keys else [()]:
        point_overrides = tuple(f"{k}={_value_text(v)}" for k, v in zip(keys, combo, strict=True))
        point = ",".join(f"{k.split('.')[-1]}={v if isinstance(v, str) else _value_text(v)}"
                         for k, v in zip(keys, combo, strict=True)) or "base"
        load_experiment(base, fixed + point_overrides)  # fail fast on a bad grid value
        for seed in range(n_seeds):
            safe = "".join(c if c.isalnum() or c in "=.,-_" else "_" for c in point)
            trials.append(Trial(f"{safe}-s{seed}", point, seed, fixed + point_overrides + (f"train.seed={seed}",)))
    return base, trials


def run_trial(base: str, trial: Trial, out: Path) -> dict:
    """Train (or resume) one trial into ``out``; return its summary."""
    from confront.train.factory import train_run
    from confront.train.spec import load_experiment

    folder = out / "trials" / trial.name
    if (folder / "summary.json").exists():
        return json.loads((folder / "summary.json").read_text())
    if (folder / "checkpoints" / "LATEST").exists():
        return train_run(None, folder, resume=True, progress=False)
    cfg = load_experiment(base, trial.overrides)
    return train_run(cfg, folder, progress=False, exist_ok=True)


def run_sweep(grid: str | Path, out: str | Path, address: str | None = None, seeds: int | None = None,
              num_cpus: int | None = None) -> list[dict]:
    """Run every unfinished trial on Ray and write ``results.csv`` and ``results.md``; return the rows."""
    import ray

    base, trials = read_grid(grid, seeds)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "grid.toml").write_text(Path(grid).read_text())
    todo = [t for t in trials if not (out / "trials" / t.name / "summary.json").exists()]
    click.echo(f"sweep: {len(trials)} trials, {len(trials) - len(todo)} already done, {len(todo)} to run")
    if todo:
        if not ray.is_initialized():
            # a local cluster on a busy machine can take more than Ray's 60 s to register its raylet
            os.environ.setdefault("RAY_raylet_start_wait_time_s", "300")
            ray.init(address=address, num_cpus=num_cpus if address is None else None,
                     include_dashboard=False, log_to_driver=False)
        # one CPU a trial: its simulator and torch run one thread (CONFRONT_THREADS), so trials do not oversubscribe
        remote = ray.remote(num_cpus=1, runtime_env={"env_vars": {"CONFRONT_THREADS": "1"}})(run_trial)
        pending = {remote.remote(base, t, out): t for t in todo}
        from tqdm import tqdm

        start = time.time()
        with tqdm(total=len(todo), desc="sweep", unit="trial") as bar:
            while pending:
                ready, _ = ray.wait(list(pending), num_returns=1)
                trial = pending.pop(ready[0])
                ray.get(ready[0])
                bar.set_postfix_str(f"{trial.name} done, {time.time() - start:.0f}s")
                bar.update(1)
    return aggregate(out, trials)


def aggregate(out: Path, trials: list[Trial]) -> list[dict]:
    """One row per grid point: mean and 95% interval over seeds of the final score ratio."""
    rng = np.random.default_rng(0)
    by_point: dict[str, list[float]] = {}
    for t in trials:
        summary = json.loads((out / "trials" / t.name / "summary.json").read_text())
        by_point.setdefault(t.point, []).append(float(summary["final_score_ratio"]))
    rows: list[dict[str, Any]] = []
    for point, values in by_point.items():
        m, lo, hi = bootstrap_ci(np.array(values), rng)
        rows.append({"point": point, "seeds": len(values), "final_score_ratio": float(m), "ci_lo": float(lo),
                     "ci_hi": float(hi)})
    rows.sort(key=lambda r: -r["final_score_ratio"])
    lines = ["point,seeds,final_score_ratio,ci_lo,ci_hi"]
    lines += [f"\"{r['point']}\",{r['seeds']},{r['final_score_ratio']:.4f},{r['ci_lo']:.4f},{r['ci_hi']:.4f}"
              for r in rows]
    (out / "results.csv").write_text("\n".join(lines) + "\n")
    md = ["| grid point | seeds | final score ratio [95% CI] |", "|---|---|---|"]
    md += [f"| {r['point']} | {r['seeds']} | {r['final_score_ratio']:.3f} [{r['ci_lo']:.3f}, {r['ci_hi']:.3f}] |"
           for r in rows]
    (out / "results.md").write_text("\n".join(md) + "\n")
    return rows


def sweep_cli(grid: Path, out: Path, address: str | None, seeds: int | None) -> None:
    rows = run_sweep(grid, out, address=address, seeds=seeds)
    click.echo((out / "results.md").read_text())
    click.echo(f"{len(rows)} grid points; table in {out / 'results.csv'}")
