"""``confront reproduce``: the paper's experiments over seeds, with figures, statistics and a report.

Each experiment is a list of arms (config overrides on a packaged base config) run for every seed; runs
are ordinary run folders under ``<out>/<experiment>/runs/<arm>/seed-<k>``, so an interrupted reproduce
resumes where it stopped. Claims are tested on per-seed values of the last ``tail`` rounds (default 100).
Arms of one seed are paired: they share the seed's TD team, its first-round start positions and the
opponent's random stream, so arms are compared by a paired permutation test (sign flips of the per-seed
differences), the mean difference with its BCa 95% interval and the difference the seeds could detect (power
0.8). Every claim gets one of three verdicts, holds / partly / no, with the criterion that decided it.
"""

from __future__ import annotations

import json
import os
import re
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import click
import numpy as np
from scipy import stats

from confront.experiments.jobs import Claim, Job, Outcome, run_jobs, slug
from confront.plots import plot_curves
from confront.runs import Run
from confront.stats import interval, mde_t, paired_comparison, paired_permutation_test

EXPERIMENTS = ("migration", "awm", "fuzzy", "transfer", "baselines")
MIGRATION_SEEDS = 1000  # the tabular task runs all seeds side by side in seconds
ALPHA = 0.05


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


def _fmt(x: float) -> str:
    return f"{x:.3g}" if abs(x) < 1000 else f"{x:.0f}"


def compare(text: str, figure: str, a: np.ndarray, b: np.ndarray, name_a: str, name_b: str, rng: np.random.Generator,
            alternative: str = "greater", what: str = "score ratio", paper_diff: float | None = None) -> Claim:
    """Test "a > b" (or "a < b") on per-seed values of two arms run on the same seeds (paired)."""
    res = paired_comparison(a, b, rng, alternative=alternative)
    d = res.diff
    sign = 1.0 if alternative == "greater" else -1.0
    right = res.p < ALPHA
    short = paper_diff is not None and sign * (d.hi if sign > 0 else d.lo) < sign * paper_diff
    verdict = ("partly" if short else "holds") if right else "no" if res.n > 1 else "n/a"  # n/a: one seed, no test
    crit = f"holds if a paired permutation test finds {name_a} {'>' if sign > 0 else '<'} {name_b} at p < {ALPHA}"
    if paper_diff is not None:
        crit += f" and the 95% CI reaches the paper's difference ({paper_diff:+.2g}); partly if only the direction"
    crit += "; no otherwise"
    ia, ib = interval(a, rng), interval(b, rng)
    return Claim(text, figure, f"{name_a} {ia} vs {name_b} {ib} ({what}; {res.n} seeds, paired)",
                 effect=f"{name_a} - {name_b} {_fmt(d.mean)} [{_fmt(d.lo)}, {_fmt(d.hi)}] (d_z {res.dz:.2f})",
                 p=f"{res.p:.3g}", mde=f"{_fmt(res.mde)}", verdict=verdict, criterion=crit,
                 detail=f"n = {res.n} seeds, paired")


def _level_verdict(lo: float, hi: float, target: float, tol: float) -> str:
    if target - tol <= lo and hi <= target + tol:
        return "holds"
    return "partly" if lo <= target + tol and hi >= target - tol else "no"


def _level_criterion(target: float, tol: float) -> str:
    return (f"holds if the 95% CI lies within {target} +- {tol}; partly if it overlaps that band (the paper's level "
            "not excluded, not shown); no if it lies outside")


def level_claim(text: str, figure: str, values: np.ndarray, target: float, tol: float, rng: np.random.Generator,
                name: str) -> Claim:
    """Test "values stay near target": the 95% interval of the mean against target +- tol."""
    v = np.asarray(values, float)
    iv = interval(v, rng)
    p = paired_permutation_test(v, np.full_like(v, target), rng, alternative="two-sided")
    mde = mde_t(float(v.std(ddof=1)) / np.sqrt(v.size), v.size - 1, two_sided=True) if v.size > 1 else float("nan")
    return Claim(text, figure, f"{name} {iv} ({v.size} seeds)",
                 effect=f"mean - {target} {_fmt(iv.mean - target)} [{_fmt(iv.lo - target)}, {_fmt(iv.hi - target)}]",
                 p=f"{p:.3g} (mean = {target}, sign flips)", mde=f"{_fmt(mde)}",
                 verdict=_level_verdict(iv.lo, iv.hi, target, tol), criterion=_level_criterion(target, tol),
                 detail=f"n = {v.size} seeds")


# -- the experiments --------------------------------------------------------------------------------------------

def _arm_jobs(experiment: str, base: str, arms: dict[str, tuple[str, ...]], seeds: int, out: Path,
              prefix: tuple[str, ...] = ()) -> dict[str, list[Job]]:
    return {
        arm: [Job(experiment, arm, s, base, prefix + ov, out / experiment / "runs" / slug(arm) / f"seed-{s}")
              for s in range(seeds)]
        for arm, ov in arms.items()
    }


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


PAPER_FLM_GAIN = 0.1  # §6.3: FLM's score ratio near 0.8, the fixed rates' near 0.7
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
            o.claims.append(compare(f"FLM scores a higher ratio than {arm}", "Fig. 14", flm, other, "FLM", arm, rng,
                                    paper_diff=PAPER_FLM_GAIN))
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


def migration_outcome(seeds: int, out: Path, episodes: int | None) -> Outcome:
    """§6.2: delegated to confront.experiments.migration (no arena needed); all seeds side by side."""
    from confront.experiments import migration as mig

    o = Outcome("migration", seeds=seeds)
    start = time.time()
    kwargs: dict = {"seeds": seeds}
    if episodes is not None:
        kwargs["episodes"] = episodes
    result = mig.run_migration(**kwargs)
    fig_dir = out / "migration" / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    o.figures.extend(Path(p) for p in mig.plot_migration(result, fig_dir))
    settings = result.settings
    intro = (f"{result.seeds} seeds (seeds {settings['seed']} .. {settings['seed'] + result.seeds - 1}), "
             f"{settings['episodes']} episodes, {settings['layers']} layers; every method reads the same uniform "
             "draws per move (common random numbers). Convergence episode: median [interquartile range].")
    tables = [intro, "", mig.convergence_table(result), "", mig.paired_table(result), ""]
    o.tables.extend(tables)
    (out / "migration" / "convergence.md").write_text("\n".join(tables))
    for c in mig.paper_claims(result):
        o.claims.append(Claim(c["text"], "Fig. 9", c["ours"], effect=c["effect"], p=c["p"], mde=c["mde"],
                              verdict=c["verdict"], criterion=c["criterion"], detail=f"n = {result.seeds} seeds"))
    o.seconds = time.time() - start
    return o


def baseline_claims(csv_path: Path, rng: np.random.Generator, opponent: str = "td") -> list[Claim]:
    """Beyond the paper, from the baselines' per-seed results: does each trained method beat random moves, and
    does training beat the untrained DMNN? Paired by seed (every method plays the same evaluation battles)."""
    import csv

    with open(csv_path, newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["opponent"] == opponent]
    by: dict[str, dict[int, float]] = {}
    for r in rows:
        by.setdefault(r["method"], {})[int(r["seed"])] = float(r["score_ratio"])
    pairs = [(m, "Random moves") for m in ("DMNN (FLM)", "DQN (SB3)", "PPO (SB3)")]
    pairs.append(("DMNN (FLM)", "DMNN (untrained)"))
    label = "the TD team" if opponent == "td" else opponent
    out = []
    for a, b in pairs:
        if a not in by or b not in by:
            continue
        seeds = sorted(set(by[a]) & set(by[b]))
        va, vb = np.array([by[a][k] for k in seeds]), np.array([by[b][k] for k in seeds])
        out.append(compare(f"beyond the paper: {a} scores a higher ratio than {b} (vs {label})", "-", va, vb, a, b,
                           rng))
    return out


# -- restating committed claims without re-running the battles ---------------------------------------------------

_NUM = r"(-?[\d.]+(?:e-?\d+)?)"
_COMPARE = re.compile(rf"^(.+?) {_NUM} \[{_NUM}, {_NUM}\] vs (.+?) {_NUM} \[{_NUM}, {_NUM}\] \((.*)\); "
                      rf"p = {_NUM}, g = {_NUM}$")
_LEVEL = re.compile(rf"^(.+?) {_NUM} \[{_NUM}, {_NUM}\]$")
_BAND = re.compile(rf"lies in {_NUM} \+- {_NUM}")


def restate_claim(c: dict, seeds: int) -> Claim:
    """A claim from a claims.json written before paired tests, given three verdicts and a detectable effect from
    its own numbers: the arms' means and 95% bootstrap intervals (standard error = interval width / 3.92)
    and the unpaired permutation p of that run. Claims already in the new form are returned as they are."""
    keys = ("text", "figure", "ours", "holds", "detail", "effect", "p", "mde", "verdict", "criterion")
    if c.get("verdict") and c.get("criterion"):
        return Claim(**{k: c[k] for k in keys if k in c})
    text, fig, ours = c["text"], c["figure"], c["ours"]
    note = "; restated from the committed summary (per-seed values not committed): unpaired, normal approximation"
    m = _COMPARE.match(ours)
    if m:
        a, ma, la, ha, b, mb, lb, hb, what, p, _g = m.groups()
        ma, la, ha, mb, lb, hb, pv = map(float, (ma, la, ha, mb, lb, hb, p))
        se = float(np.hypot((ha - la) / 3.92, (hb - lb) / 3.92))
        sign = -1.0 if ("less" in text or "fluctuates" in text) else 1.0
        d = ma - mb
        lo, hi = d - 1.96 * se, d + 1.96 * se
        paper = PAPER_FLM_GAIN if text.startswith("FLM scores a higher ratio than LM") else None
        short = paper is not None and (hi if sign > 0 else -lo) < paper
        verdict = ("partly" if short else "holds") if pv < ALPHA else "no"
        crit = f"holds if {a} {'>' if sign > 0 else '<'} {b} at p < {ALPHA}"
        if paper is not None:
            crit += f" and the 95% CI reaches the paper's difference ({paper:+.2g}); partly if only the direction"
        return Claim(text, fig, ours, effect=f"{a} - {b} {_fmt(d)} [{_fmt(lo)}, {_fmt(hi)}]", p=f"{pv:.3g}",
                     mde=_fmt(mde_t(se, 2 * seeds - 2)), verdict=verdict, criterion=crit + "; no otherwise" + note,
                     detail=c.get("detail", ""))
    m, band = _LEVEL.match(ours), _BAND.search(c.get("detail", ""))
    if m and band:
        mean, lo, hi = (float(v) for v in m.groups()[1:])
        target, tol = map(float, band.groups())
        se = (hi - lo) / 3.92
        p = 2 * stats.t.sf(abs(mean - target) / se, seeds - 1) if se > 0 else float("nan")
        return Claim(text, fig, ours, effect=f"mean - {target} {_fmt(mean - target)} [{_fmt(lo - target)}, "
                     f"{_fmt(hi - target)}]", p=f"{p:.3g} (t, mean = {target})",
                     mde=_fmt(mde_t(se, seeds - 1, two_sided=True)), verdict=_level_verdict(lo, hi, target, tol),
                     criterion=_level_criterion(target, tol) + note, detail=f"n = {seeds} seeds")
    return Claim(text, fig, ours, c.get("holds"), detail=c.get("detail", ""))


def restated_outcome(name: str, out: Path, seeds: int) -> Outcome:
    """An experiment's claims from its committed ``claims.json`` (and the baselines' ``results.csv``), not re-run."""
    claims = json.loads((out / name / "claims.json").read_text())
    o = Outcome(name, seeds=seeds, note="not re-run: claims restated from the committed results")
    if name == "baselines":
        o.claims = [restate_claim(c, seeds) for c in claims if "ranking" in c["text"]]
        csv_path = out / "baselines" / "results.csv"
        if csv_path.exists():
            o.claims += baseline_claims(csv_path, np.random.default_rng(12345))
            o.note = "not re-run: paired tests recomputed from the committed per-seed results.csv"
    else:
        o.claims = [restate_claim(c, seeds) for c in claims]
    o.figures = sorted((out / name / "figures").glob("*.png"))
    return o


# -- report ------------------------------------------------------------------------------------------------------

def _cell(text: str) -> str:
    return text.replace("|", "\\|")  # a "|" inside a cell would split it


def write_report(out: Path, outcomes: Sequence[Outcome], seeds: int, rounds: int | None) -> Path:
    """``report.md`` and ``report.html`` in ``out``: claims table, figures (paths relative to ``out``), wall times."""
    ran = ", ".join(f"{o.name} {o.seeds}" for o in outcomes)
    lines = ["# confront: the paper's claims, re-run", "",
             f"Seeds actually run per arm: {ran}. Rounds per arm: {rounds or 'as in the paper (500)'}. "
             "Battle claims are tested on per-seed values of the last rounds; arms of one seed are paired (same TD "
             "team, same first-round start positions, same opponent random stream): paired permutation test (sign "
             "flips, exact up to 14 seeds), mean difference with its BCa 95% interval, and the difference the seeds "
             f"detect with power 0.8 at p < {ALPHA} (paired t approximation). Migration: paired sign tests on the "
             "convergence episode over seeds with common random numbers; 'detectable' is then a share of seeds. "
             "Verdicts: holds / partly (direction right, magnitude or a named part not) / no, each with its "
             "criterion. Nothing was tuned to make a claim hold.", ""]
    lines += [f"- {o.name}: {o.note}" for o in outcomes if o.note]
    lines += ["", "| experiment | claim in the paper | paper's figure | ours [95% CI] | effect [95% CI] | p | "
              "detectable (power 0.8) | verdict | criterion |", "|---|---|---|---|---|---|---|---|---|"]
    for o in outcomes:
        for c in o.claims:
            mark = c.verdict if c.verdict in ("holds", "n/a") else f"**{c.verdict}**"
            cells = [o.name, c.text, c.figure, c.ours, c.effect or "-", c.p or "-", c.mde or "-", mark,
                     c.criterion or c.detail or "-"]
            lines.append("| " + " | ".join(_cell(x) for x in cells) + " |")
    lines += ["", "## Wall time", "", "Runs already finished by an earlier call are reused, so this call's time can be "
              "short; the summed run time counts every run's own wall time (runs execute in parallel workers).", "",
              "| experiment | seeds | this call (s) | training runs | summed run time (s) |",
              "|---|---:|---:|---:|---:|"]
    lines += [f"| {o.name} | {o.seeds} | {'not re-run' if o.note else f'{o.seconds:.0f}'} | {o.runs} | "
              f"{o.run_seconds:.0f} |" for o in outcomes]
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


def _save_claims(out: Path, o: Outcome) -> None:
    (out / o.name).mkdir(parents=True, exist_ok=True)
    (out / o.name / "claims.json").write_text(json.dumps([c.__dict__ for c in o.claims], indent=1))


def reproduce(experiment: str, seeds: int | None = None, rounds: int | None = None, out: Path | None = None,
              workers: int | None = None, tail: int = 100, episodes: int | None = None, engine: str = "sim"
              ) -> list[Outcome]:
    """Run ``experiment`` (or ``all``) in the simulator or the real engine and write the report.

    ``seeds``: seeds per arm (default 10); migration runs ``seeds`` when it is the experiment asked for, else
    1000 (all side by side in seconds)."""
    if seeds is not None and (isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1):
        raise ValueError(f"bad value seeds={seeds!r}: must be a whole number >= 1")
    for key, value in (("rounds", rounds), ("workers", workers)):  # checked before the output folder is made
        if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
            raise ValueError(f"bad value {key}={value!r}: must be a whole number >= 1")
    out = Path(out or ("results" if engine == "sim" else "results-robocode"))
    out.mkdir(parents=True, exist_ok=True)
    names = [e for e in EXPERIMENTS if e != "baselines"] if experiment == "all" else [experiment]
    workers = workers or os.cpu_count() or 1
    n_seeds = 10 if seeds is None else seeds
    tail = min(tail, rounds // 2) if rounds else tail
    rng = np.random.default_rng(12345)
    outcomes = []
    builders = {"awm": awm, "fuzzy": fuzzy, "transfer": transfer}
    for name in names:
        click.echo(f"== {name}")
        start = time.time()
        if name == "migration":
            mig_seeds = seeds if experiment == "migration" and seeds is not None else MIGRATION_SEEDS
            outcomes.append(migration_outcome(mig_seeds, out, episodes))
        elif name == "baselines":
            from confront.experiments.baselines import baselines_outcome

            outcomes.append(baselines_outcome(n_seeds, out, rounds, workers))
            outcomes[-1].claims += baseline_claims(out / "baselines" / "results.csv", rng)
            outcomes[-1].seeds = n_seeds
        else:
            jobs, analyse = builders[name](n_seeds, out, rng, tail)
            run_jobs(jobs, rounds, workers, engine)
            outcomes.append(analyse())
            outcomes[-1].runs = len(jobs)
            outcomes[-1].seeds = n_seeds
            outcomes[-1].run_seconds = sum(json.loads((j.folder / "summary.json").read_text())["wall_time_s"]
                                           for j in jobs)
        outcomes[-1].seconds = time.time() - start
        click.echo(f"   {name}: {outcomes[-1].seconds:.0f} s")
        _save_claims(out, outcomes[-1])
    # `all` writes the report at the top; a single experiment writes <out>/<experiment>/report.md
    report = write_report(out if experiment == "all" else out / experiment, outcomes, n_seeds, rounds)
    click.echo(f"report: {report}")
    return outcomes


def restate(out: Path, battle_seeds: int = 10, migration_seeds: int = MIGRATION_SEEDS, rounds: int | None = None
            ) -> list[Outcome]:
    """Re-run the migration experiment and restate the battle experiments' committed claims (no training):
    the report of ``out`` (and of ``out/baselines``) regenerated with the current statistics."""
    out = Path(out)
    outcomes = [migration_outcome(migration_seeds, out, None)]
    _save_claims(out, outcomes[0])
    for name in ("awm", "fuzzy", "transfer"):
        if (out / name / "claims.json").exists():
            outcomes.append(restated_outcome(name, out, battle_seeds))
            _save_claims(out, outcomes[-1])
    if (out / "baselines" / "claims.json").exists():
        csv_path = out / "baselines" / "results.csv"
        seeds = len({r.split(",")[1] for r in csv_path.read_text().splitlines()[1:]}) if csv_path.exists() else 0
        base = restated_outcome("baselines", out, seeds)
        ranking = out / "baselines" / "ranking.md"
        if ranking.exists():
            base.tables = [ranking.read_text()]
        _save_claims(out, base)
        write_report(out / "baselines", [base], seeds, rounds)
        outcomes.append(base)
    write_report(out, outcomes, battle_seeds, rounds)
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
        click.echo(f"[{o.name}] {o.seeds} seeds")
        for c in o.claims:
            click.echo(f"[{o.name}] {c.text}: {c.verdict} — {c.effect or c.ours}; p {c.p or '-'}")


def main(argv: list[str] | None = None) -> None:
    """``python -m confront.experiments.reproduce restate OUT``: regenerate OUT's report from its committed claims
    (battle experiments not re-run) and a fresh migration run."""
    import argparse

    ap = argparse.ArgumentParser(description=main.__doc__)
    ap.add_argument("command", choices=["restate"])
    ap.add_argument("out", type=Path)
    ap.add_argument("--battle-seeds", type=int, default=10, help="seeds per arm of the committed battle runs")
    ap.add_argument("--migration-seeds", type=int, default=MIGRATION_SEEDS)
    args = ap.parse_args(argv)
    if args.battle_seeds < 1 or args.migration_seeds < 1:
        ap.error("--battle-seeds and --migration-seeds must be at least 1")
    for o in restate(args.out, args.battle_seeds, args.migration_seeds):
        for c in o.claims:
            print(f"[{o.name}] {c.verdict}: {c.text} — {c.effect}; p {c.p}; detectable {c.mde}")


if __name__ == "__main__":
    main()
