"""``confront reproduce``: the paper's experiments over seeds, with figures, statistics and a report.

Each experiment is a list of arms (config overrides on a packaged base config) run for every seed; runs
are ordinary run folders under ``<out>/<experiment>/runs/<arm>/seed-<k>``, so an interrupted reproduce
resumes where it stopped. Claims are tested on per-seed values of the last ``tail`` rounds (default 100)
with a one-sided permutation test and Hedges' g; a claim holds when p < 0.05 in the paper's direction.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import click
import numpy as np

from confront.experiments.plots import plot_curves
from confront.experiments.stats import hedges_g, interval, permutation_test
from confront.runs import Run

EXPERIMENTS = ("migration", "awm", "fuzzy", "transfer", "baselines")


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
    """A claim of the paper, tested on our runs."""

    text: str
    figure: str
    ours: str
    holds: bool | None
    detail: str = ""


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


def _run_job(job: Job, rounds: int | None, engine: str = "sim") -> str:
    from confront.experiments.spec import load_experiment
    from confront.experiments.train import train_run

    if (job.folder / "summary.json").exists():
        return "cached"
    if engine == "robocode":  # live in the real engine (no checkpoints there: an unfinished run restarts)
        import shutil

        from confront.experiments.train_engine import train_in_engine

        shutil.rmtree(job.folder, ignore_errors=True)
        extra = [f"train.seed={job.seed}"]
        if rounds is not None:
            extra += [f"train.rounds={rounds}", f"train.session_rounds={max(1, min(10, rounds // 2))}"]
        train_in_engine(load_experiment(job.base, job.overrides + tuple(extra)), job.folder, progress=False)
        return "trained"
    if (job.folder / "checkpoints" / "LATEST").exists():
        train_run(None, job.folder, resume=True, progress=False)
        return "resumed"
    extra = [f"train.seed={job.seed}", "train.replay=false"]
    if rounds is not None:
        extra.append(f"train.rounds={rounds}")
        extra.append(f"train.session_rounds={max(1, min(10, rounds // 2))}")
        extra.append(f"train.checkpoint_every={max(1, rounds // 2)}")
    cfg = load_experiment(job.base, job.overrides + tuple(extra))
    train_run(cfg, job.folder, progress=False, exist_ok=True)
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
            running = {}
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


def _session_matrix(folders: Sequence[Path], column: str) -> np.ndarray:
    rows = [Run(f).read_table("sessions") for f in folders]
    n = min(len(r) for r in rows)
    return np.array([[float(s[column]) for s in r[:n]] for r in rows])


def _tail_values(folders: Sequence[Path], column: str, tail: int) -> np.ndarray:
    """Per seed: the mean of ``column`` over the last ``tail`` rounds (ratios pooled as sums)."""
    out = []
    for f in folders:
        rows = Run(f).read_table("rounds")[-tail:]
        if column == "score_ratio":
            ours = sum(float(r["score_ours"]) for r in rows)
            theirs = sum(float(r["score_theirs"]) for r in rows)
            out.append(ours / (ours + theirs) if ours + theirs > 0 else 0.5)
        else:
            out.append(float(np.mean([float(r[column]) for r in rows])))
    return np.array(out)


def _fluctuation(folders: Sequence[Path]) -> np.ndarray:
    """Per seed: mean absolute first difference of the session score ratio (paper's Figure 11)."""
    m = _session_matrix(folders, "score_ratio")
    return np.abs(np.diff(m, axis=1)).mean(axis=1)


def compare(text: str, figure: str, a: np.ndarray, b: np.ndarray, name_a: str, name_b: str, rng: np.random.Generator,
            alternative: str = "greater", what: str = "score ratio") -> Claim:
    """Test "a > b" (or "a < b") on per-seed values."""
    p = permutation_test(a, b, rng, alternative=alternative)
    g = hedges_g(a, b)
    ia, ib = interval(a, rng), interval(b, rng)
    return Claim(text, figure, f"{name_a} {ia} vs {name_b} {ib} ({what}); p = {p:.3g}, g = {g:.2f}", p < 0.05,
                 detail=f"n = {a.size}/{b.size} seeds")


def level_claim(text: str, figure: str, values: np.ndarray, target: float, tol: float, rng: np.random.Generator,
                name: str) -> Claim:
    """Test "values stay near target": the 95% interval lies within target +- tol."""
    iv = interval(values, rng)
    holds = target - tol <= iv.lo and iv.hi <= target + tol
    return Claim(text, figure, f"{name} {iv}", holds, detail=f"holds if the interval lies in {target} +- {tol}")


# -- the experiments --------------------------------------------------------------------------------------------

def _arm_jobs(experiment: str, base: str, arms: dict[str, tuple[str, ...]], seeds: int, out: Path,
              prefix: tuple[str, ...] = ()) -> dict[str, list[Job]]:
    return {
        arm: [Job(experiment, arm, s, base, prefix + ov, out / experiment / "runs" / slug(arm) / f"seed-{s}")
              for s in range(seeds)]
        for arm, ov in arms.items()
    }


def slug(text: str) -> str:
    return "".join(c if c.isalnum() else "-" for c in text.lower()).strip("-")


def _session_figures(outcome: Outcome, fig_dir: Path, jobs: dict[str, list[Job]], title: str, stem: str,
                     defensive: bool = True) -> None:
    folders = {arm: [j.folder for j in js] for arm, js in jobs.items()}
    outcome.figures.append(plot_curves({a: _session_matrix(f, "score_ratio") for a, f in folders.items()},
                                       fig_dir / f"{stem}_score_ratio.png", ylabel="score ratio", title=title,
                                       hline=0.5))
    if defensive:
        outcome.figures.append(plot_curves({a: _session_matrix(f, "defensive_ours") for a, f in folders.items()},
                                           fig_dir / f"{stem}_defensive.png", ylabel="defensive score per session",
                                           title=title,
                                           dashed={a: _session_matrix(f, "defensive_theirs")
                                                   for a, f in folders.items()}))


RANDOM_ARM = "random moves"  # reference arm beyond the paper: uniform moves, same gun controller, never learns


def _beats_random(arm: str, folders: dict[str, list[Path]], tail: int, rng: np.random.Generator) -> Claim:
    """Beyond the paper: does the trained arm score more than a team that moves at random?"""
    return compare(f"beyond the paper: {arm} scores a higher ratio than random moves", "-",
                   _tail_values(folders[arm], "score_ratio", tail),
                   _tail_values(folders[RANDOM_ARM], "score_ratio", tail), arm, RANDOM_ARM, rng)


def awm(seeds: int, out: Path, rng: np.random.Generator, tail: int) -> tuple[list[Job], Callable[[], Outcome]]:
    jobs = _arm_jobs("awm", "awm", {"NN with AWM": ("learner.awm=true",),
                                    "NN without AWM": ("learner.awm=false",),
                                    RANDOM_ARM: ("learner.kind=\"random\"",)}, seeds, out)

    def analyse() -> Outcome:
        o = Outcome("awm")
        fig_dir = out / "awm" / "figures"
        _session_figures(o, fig_dir, jobs, "DMNN with vs without adaptive momentum (Fig. 10, 12)", "fig10_12")
        folders = {a: [j.folder for j in js] for a, js in jobs.items()}
        o.figures.append(plot_curves({a: np.diff(_session_matrix(f, "score_ratio"), axis=1)
                                      for a, f in folders.items()}, fig_dir / "fig11_fluctuation.png",
                                     ylabel="first difference of score ratio", title="Fluctuation (Fig. 11)",
                                     hline=0.0))
        w, wo = folders["NN with AWM"], folders["NN without AWM"]
        o.claims.append(compare("NN with AWM reaches a higher score ratio than NN without AWM", "Fig. 10",
                                _tail_values(w, "score_ratio", tail), _tail_values(wo, "score_ratio", tail),
                                "with", "without", rng))
        o.claims.append(compare("NN with AWM fluctuates less (smaller |first difference|)", "Fig. 11",
                                _fluctuation(w), _fluctuation(wo), "with", "without", rng, alternative="less",
                                what="mean |diff score ratio|"))
        o.claims.append(compare("NN with AWM has a higher defensive score", "Fig. 12",
                                _tail_values(w, "defensive_ours", tail), _tail_values(wo, "defensive_ours", tail),
                                "with", "without", rng, what="defensive score per round"))
        o.claims.append(_beats_random("NN with AWM", folders, tail, rng))
        return o

    return [j for js in jobs.values() for j in js], analyse


def fuzzy(seeds: int, out: Path, rng: np.random.Generator, tail: int) -> tuple[list[Job], Callable[[], Outcome]]:
    jobs = _arm_jobs("fuzzy", "fuzzy", {
        "FLM": ("learner.learning_rate=\"fuzzy\"",),
        "LM-0.2": ("learner.learning_rate=\"fixed\"", "learner.alpha=0.2"),
        "LM-0.95": ("learner.learning_rate=\"fixed\"", "learner.alpha=0.95"),
        RANDOM_ARM: ("learner.kind=\"random\"",),
    }, seeds, out)

    def analyse() -> Outcome:
        from confront.learning.fuzzy import plot_fuzzy

        o = Outcome("fuzzy")
        fig_dir = out / "fuzzy" / "figures"
        fig_dir.mkdir(parents=True, exist_ok=True)
        plot_fuzzy(fig_dir / "fig13_fuzzy_learning_rate.png")
        o.figures.append(fig_dir / "fig13_fuzzy_learning_rate.png")
        folders = {a: [j.folder for j in js] for a, js in jobs.items()}
        o.figures.append(plot_curves({a: _session_matrix(f, "score_ours") for a, f in folders.items()},
                                     fig_dir / "fig14_scores.png", ylabel="score per session",
                                     title="FLM vs LM-0.2 vs LM-0.95 against the TD team (Fig. 14)",
                                     dashed={a: _session_matrix(f, "score_theirs") for a, f in folders.items()}))
        _session_figures(o, fig_dir, jobs, "Score ratio against the TD team", "fig14", defensive=False)
        flm = _tail_values(folders["FLM"], "score_ratio", tail)
        o.claims.append(level_claim("FLM's score ratio stays around 0.8", "Fig. 14", flm, 0.8, 0.05, rng, "FLM"))
        for arm in ("LM-0.2", "LM-0.95"):
            other = _tail_values(folders[arm], "score_ratio", tail)
            o.claims.append(level_claim(f"{arm}'s score ratio stays around 0.7", "Fig. 14", other, 0.7, 0.05, rng,
                                        arm))
            o.claims.append(compare(f"FLM scores a higher ratio than {arm}", "Fig. 14", flm, other, "FLM", arm, rng))
        o.claims.append(_beats_random("FLM", folders, tail, rng))
        return o

    return [j for js in jobs.values() for j in js], analyse


def transfer(seeds: int, out: Path, rng: np.random.Generator, tail: int) -> tuple[list[Job], Callable[[], Outcome]]:
    root = out / "transfer" / "runs"
    source = [Job("transfer", "source 4v4", s, "transfer", ("arena.scenario=\"4v4\"",),
                  root / "source-4v4" / f"seed-{s}") for s in range(seeds)]
    jobs: dict[str, list[Job]] = {"LM with TF (4v6)": [], "LM without TF (4v6)": [], "LM with TF (4v10)": [],
                                  "LM without TF (4v10)": []}
    for s in range(seeds):
        mid = root / "with-tf-4v6" / f"seed-{s}"
        jobs["LM with TF (4v6)"].append(Job("transfer", "LM with TF (4v6)", s, "transfer",
                                            ("arena.scenario=\"4v6\"", f"transfer.source=\"{source[s].folder}\""),
                                            mid, after=(source[s].folder,)))
        jobs["LM without TF (4v6)"].append(Job("transfer", "LM without TF (4v6)", s, "transfer",
                                               ("arena.scenario=\"4v6\"",), root / "without-tf-4v6" / f"seed-{s}"))
        jobs["LM with TF (4v10)"].append(Job("transfer", "LM with TF (4v10)", s, "transfer",
                                             ("arena.scenario=\"4v10\"", f"transfer.source=\"{mid}\""),
                                             root / "with-tf-4v10" / f"seed-{s}", after=(mid,)))
        jobs["LM without TF (4v10)"].append(Job("transfer", "LM without TF (4v10)", s, "transfer",
                                                ("arena.scenario=\"4v10\"",), root / "without-tf-4v10" / f"seed-{s}"))

    def analyse() -> Outcome:
        o = Outcome("transfer")
        fig_dir = out / "transfer" / "figures"
        six = {k: v for k, v in jobs.items() if "4v6" in k}
        ten = {k: v for k, v in jobs.items() if "4v10" in k}
        _session_figures(o, fig_dir, six, "Curriculum transfer, 4 vs a TD team of 6 (Fig. 16, 17)", "fig16_17")
        _session_figures(o, fig_dir, ten, "Curriculum transfer, 4 vs a TD team of 10 (Fig. 18)", "fig18",
                         defensive=False)
        f = {k: [j.folder for j in v] for k, v in jobs.items()}
        o.claims.append(compare("With TF the score ratio is higher than without (4v6)", "Fig. 16",
                                _tail_values(f["LM with TF (4v6)"], "score_ratio", tail),
                                _tail_values(f["LM without TF (4v6)"], "score_ratio", tail), "with TF",
                                "without TF", rng))
        early = max(1, tail // 2)
        o.claims.append(compare("TF accelerates learning: higher score ratio early on (first rounds, 4v6)",
                                "Fig. 16", _head_values(f["LM with TF (4v6)"], early),
                                _head_values(f["LM without TF (4v6)"], early), "with TF", "without TF", rng))
        o.claims.append(compare("With TF the defensive score is higher (4v6)", "Fig. 17",
                                _tail_values(f["LM with TF (4v6)"], "defensive_ours", tail),
                                _tail_values(f["LM without TF (4v6)"], "defensive_ours", tail), "with TF",
                                "without TF", rng, what="defensive score per round"))
        o.claims.append(compare("With TF (curriculum 4v4 -> 4v6 -> 4v10) the score ratio is higher (4v10)",
                                "Fig. 18", _tail_values(f["LM with TF (4v10)"], "score_ratio", tail),
                                _tail_values(f["LM without TF (4v10)"], "score_ratio", tail), "with TF",
                                "without TF", rng))
        return o

    all_jobs = source + [j for js in jobs.values() for j in js]
    return all_jobs, analyse


def _head_values(folders: Sequence[Path], head: int) -> np.ndarray:
    out = []
    for f in folders:
        rows = Run(f).read_table("rounds")[:head]
        ours = sum(float(r["score_ours"]) for r in rows)
        theirs = sum(float(r["score_theirs"]) for r in rows)
        out.append(ours / (ours + theirs) if ours + theirs > 0 else 0.5)
    return np.array(out)


def migration_outcome(seeds: int, out: Path, episodes: int | None, workers: int = 1) -> Outcome:
    """§6.2: delegated to confront.learning.migration (no arena needed)."""
    from confront.learning import migration as mig

    o = Outcome("migration")
    start = time.time()
    kwargs: dict = {"seeds": seeds, "workers": workers}
    if episodes is not None:
        kwargs["episodes"] = episodes
    result = mig.run_migration(**kwargs)
    fig_dir = out / "migration" / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    o.figures.extend(Path(p) for p in mig.plot_migration(result, fig_dir))
    table = mig.convergence_table(result)
    o.tables.append(table)
    (out / "migration" / "convergence.md").write_text(table + "\n")
    for claim in mig.paper_claims(result):
        o.claims.append(Claim(claim["text"], "Fig. 9", claim["ours"], claim["holds"], claim.get("detail", "")))
    o.seconds = time.time() - start
    return o


# -- report ------------------------------------------------------------------------------------------------------

def write_report(out: Path, outcomes: Sequence[Outcome], seeds: int, rounds: int | None) -> Path:
    """``report.md`` and ``report.html`` in ``out``: claims table, figures (paths relative to ``out``), wall times."""
    lines = ["# confront: the paper's claims, re-run", "",
             f"Seeds per arm: {seeds}. Rounds per arm: {rounds or 'as in the paper (500)'}. "
             "Claims are tested on per-seed values of the last rounds (one-sided permutation test, p < 0.05; "
             "Hedges' g as effect size; 95% bootstrap intervals). Nothing was tuned to make a claim hold.", "",
             "| experiment | claim in the paper | paper's figure | our value [95% CI] | holds? |",
             "|---|---|---|---|---|"]
    for o in outcomes:
        for c in o.claims:
            mark = {True: "yes", False: "**no**", None: "n/a"}[c.holds]
            lines.append(f"| {o.name} | {c.text} | {c.figure} | {c.ours} | {mark} |")
    lines += ["", "## Wall time", "", "Runs already finished by an earlier call are reused, so this call's time can be "
              "short; the summed run time counts every run's own wall time (runs execute in parallel workers).", "",
              "| experiment | this call (s) | training runs | summed run time (s) |", "|---|---:|---:|---:|"]
    lines += [f"| {o.name} | {o.seconds:.0f} | {o.runs} | {o.run_seconds:.0f} |" for o in outcomes]
    for o in outcomes:
        lines += ["", f"## {o.name}", ""]
        lines += o.tables
        for fig in o.figures:
            rel = os.path.relpath(fig, out)
            lines.append(f"![{fig.stem}]({rel})")
    md = "\n".join(lines) + "\n"
    (out / "report.md").write_text(md)
    _write_html(out / "report.html", md)
    return out / "report.md"


def _write_html(path: Path, md: str) -> None:
    import html

    body = []
    in_table = False
    for line in md.splitlines():
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            if set("".join(cells)) <= set("-"):
                continue
            tag = "th" if not in_table else "td"
            if not in_table:
                body.append("<table>")
                in_table = True
            body.append("<tr>" + "".join(f"<{tag}>{html.escape(c).replace('**', '')}</{tag}>" for c in cells)
                        + "</tr>")
            continue
        if in_table:
            body.append("</table>")
            in_table = False
        if line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            body.append(f"<h{level}>{html.escape(line.lstrip('# '))}</h{level}>")
        elif line.startswith("!["):
            src = line[line.index("(") + 1: -1]
            body.append(f'<p><img src="{html.escape(src)}" style="max-width:720px"></p>')
        elif line:
            body.append(f"<p>{html.escape(line)}</p>")
    if in_table:
        body.append("</table>")
    style = ("body{font-family:sans-serif;max-width:1000px;margin:2em auto}table{border-collapse:collapse}"
             "td,th{border:1px solid #ccc;padding:4px 8px;font-size:13px}")
    path.write_text(f"<!doctype html><meta charset=utf-8><title>confront report</title><style>{style}</style>"
                    + "\n".join(body))


def reproduce(experiment: str, seeds: int | None = None, rounds: int | None = None, out: Path | None = None,
              workers: int | None = None, tail: int = 100, episodes: int | None = None, engine: str = "sim"
              ) -> list[Outcome]:
    """Run ``experiment`` (or ``all``) in the simulator or the real engine and write the report."""
    out = Path(out or ("results" if engine == "sim" else "results-robocode"))
    out.mkdir(parents=True, exist_ok=True)
    names = [e for e in EXPERIMENTS if e != "baselines"] if experiment == "all" else [experiment]
    workers = workers or os.cpu_count() or 1
    n_seeds = seeds or 10
    tail = min(tail, rounds // 2) if rounds else tail
    rng = np.random.default_rng(12345)
    outcomes = []
    builders = {"awm": awm, "fuzzy": fuzzy, "transfer": transfer}
    for name in names:
        click.echo(f"== {name}")
        start = time.time()
        if name == "migration":
            # the tabular task is cheap: 3 seeds per requested seed (30 for the default 10), never fewer than 2
            outcomes.append(migration_outcome(max(3 * n_seeds, 2), out, episodes, workers))
        elif name == "baselines":
            from confront.experiments.baselines import baselines_outcome

            outcomes.append(baselines_outcome(n_seeds, out, rounds, workers))
        else:
            jobs, analyse = builders[name](n_seeds, out, rng, tail)
            run_jobs(jobs, rounds, workers, engine)
            outcomes.append(analyse())
            outcomes[-1].runs = len(jobs)
            outcomes[-1].run_seconds = sum(json.loads((j.folder / "summary.json").read_text())["wall_time_s"]
                                           for j in jobs)
        outcomes[-1].seconds = time.time() - start
        click.echo(f"   {name}: {outcomes[-1].seconds:.0f} s")
        (out / name).mkdir(parents=True, exist_ok=True)
        (out / name / "claims.json").write_text(json.dumps([c.__dict__ for c in outcomes[-1].claims], indent=1))
    # `all` writes the report at the top; a single experiment writes <out>/<experiment>/report.md
    report = write_report(out if experiment == "all" else out / experiment, outcomes, n_seeds, rounds)
    click.echo(f"report: {report}")
    return outcomes


def reproduce_cli(experiment: str, seeds: int | None, rounds: int | None, engine: str, out: Path | None,
                  workers: int | None, overrides: tuple[str, ...]) -> None:
    if engine == "robocode" and experiment in ("baselines", "all"):
        raise click.UsageError("--engine robocode runs awm, fuzzy or transfer (hours at 500 rounds per run); "
                               "migration needs no engine and the SB3 baselines train in the simulator")
    if overrides:
        raise click.UsageError("reproduce takes no --set: edit a copy of the experiment's TOML instead")
    outcomes = reproduce(experiment, seeds=seeds, rounds=rounds, out=out, workers=workers, engine=engine)
    for o in outcomes:
        for c in o.claims:
            mark = {True: "holds", False: "does NOT hold", None: "n/a"}[c.holds]
            click.echo(f"[{o.name}] {c.text}: {mark} — {c.ours}")
