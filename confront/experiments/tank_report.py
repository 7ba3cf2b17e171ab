"""The report of the recommended learner: trained PPO tank runs, evaluated per opponent in the simulator and
(the exported TankBot, no Python) in the real engine, against the issue's targets.

    python -m confront.experiments.tank_report RUN [RUN ...] --out docs/results/tanks [--engine [--unseen]
        [--engine-runs K]] [--compare WORK] [--play sampled|greedy] [--rumble FOLDER [--rumble-seeds N]]

Each RUN is one training seed (``confront train -c tanks --set train.seed=K``). Per league entry: the greedy
(or with ``--play sampled`` the sampling) simulator share (``--rounds`` rounds, the mean over runs with a
t-interval when there are 2 or more), and with ``--engine`` the exported robot's share in Robocode over
``--engine-seeds`` battles of ``--rounds`` rounds per sample-robot and paper-move entry (the TD team, the
dodge, random moves: exported PolicyBots), for the first run or the first ``--engine-runs`` runs (then also
the mean of their run means with a t-interval, and how many runs reach the target). Engine battles are kept
per run (``<run>/eval/engine-<rounds>.json``), so runs can be played by separate processes side by side first.
With ``--rumble FOLDER`` (repeatable) the first run's exported robot also plays a 1v1 rumble against every robot
of a folder of robot jars (:mod:`confront.experiments.rumble`: ``--rumble-rounds`` rounds, 35 by default as the
RoboRumble, on 800x600 x ``--rumble-seeds`` engine seeds), kept in ``<out>/rumble/<folder>-<play>/`` (resumable);
``--results-from`` takes every other row from an earlier ``results.json`` of the same first run, so rumble rows can
be added to a report whose other runs are gone.
Writes ``report.md``, ``results.json`` and the learning curves (share against decisions and against wall
time, per opponent).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from confront import checkpoint as ck
from confront.experiments.tank_evaluate import evaluate_tanks
from confront.runs import Run
from confront.train.league import PAPER_MOVE_OPPONENTS, paper_move_robot
from confront.train.loop import share_windows
from confront.train.ppo_model import load_tank_model
from confront.train.spec import config_from_dict, load_toml

if TYPE_CHECKING:
    from confront.engine.tank_export import Play

# the targets per kind of entry: (share, what)
TARGETS = {"1v1": 0.90, "4v4": 0.80, "4v4:td": 0.75, "4v4:dodge": 0.65}
TECH_TARGETS = {"1v1": 0.60, "4v4": 0.70}  # against the technique robots (issue 32)
# robots of the Robocode distribution the policy never met in training (the engine's own, no simulator twin
# needed): does it win by what it learned about tanks rather than about its eight opponents?
UNSEEN = ("1v1:MyFirstRobot", "1v1:sample.MyFirstJuniorRobot", "1v1:sample.PaintingRobot", "1v1:Target",
          "1v1:TrackFire", "1v1:VelociRobot", "4v4:TrackFire", "4v4:VelociRobot")


def target_of(entry: str) -> float | None:
    """The share the issue asks for in this entry (engine), None where it names none."""
    scen, _, opp = entry.partition(":")
    if entry in TARGETS:
        return TARGETS[entry]
    if opp in ("self", "strafe", "random", "dodge", "td"):
        return None
    from confront.arena.tech import TECH_ROBOTS

    return (TECH_TARGETS if opp in TECH_ROBOTS else TARGETS).get(scen)


def mean_interval(values: list[float]) -> tuple[float, float, float]:
    """Mean and a 95% t-interval (NaN bounds with fewer than 2 values)."""
    from scipy import stats

    v = np.asarray(values, dtype=float)
    if len(v) < 2:
        return float(v.mean()), math.nan, math.nan
    lo, hi = stats.t.interval(0.95, len(v) - 1, loc=v.mean(), scale=stats.sem(v)) if v.std() > 0 else (v[0], v[0])
    return float(v.mean()), float(lo), float(hi)


def _curves(runs: list[Path], out: Path) -> list[Path]:
    """Share per opponent against decisions and against wall time (windows of rounds per opponent) for the first
    run that kept its per-round metrics (``metrics/rounds.csv``); none when no run did (a shipped model folder)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run = next((r for r in runs if (r / "metrics" / "rounds.csv").is_file()), None)
    if run is None:
        print("note: no run has metrics/rounds.csv: the report has no learning curves", file=sys.stderr)
        return []
    rows = Run(run).read_table("rounds")
    figs = []
    for x_key, label in (("decisions", "agent decisions"), ("wall_s", "training wall time (s)")):
        fig, ax = plt.subplots(figsize=(9, 5))
        for name in sorted({r["opponent"] for r in rows}):
            sub = [r for r in rows if r["opponent"] == name]
            windows = share_windows(sub, max(20, len(sub) // 30))
            ax.plot([float(sub[end - 1][x_key]) for end, _ in windows], [v for _, v in windows], label=name, lw=1.2)
        ax.axhline(0.5, color="k", ls=":", lw=0.8)
        ax.set_xlabel(label)
        ax.set_ylabel("score share (training, sampled actions)")
        ax.set_title(f"PPO tanks: share per opponent against {label} (seed of {run.name})")
        ax.legend(fontsize=6, ncol=3)
        path = out / f"share_vs_{x_key}.png"
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        figs.append(path)
    return figs


def engine_share(run: Path, policy: Any, entry: str, rounds: int, seed: int, cfg: Any = None) -> float:
    """The exported robot's score share in one Robocode battle of ``rounds`` rounds (engine ``seed``), kept in
    ``<run>/eval/engine-<rounds>.json`` (``engine-sampled-<rounds>.json`` for a sampling robot) as soon as it
    is played (a long report that dies keeps its battles).
    A paper-move opponent (the TD team, the dodge, random moves) plays as the exported PolicyBot of the run's
    config ``cfg`` (:func:`confront.train.league.paper_move_robot`)."""
    from confront.engine.tank_export import evaluate_tank_policy

    cache = run / "eval" / ("engine-" + ("sampled-" if policy.play == "sampled" else "") + f"{rounds}.json")
    got = json.loads(cache.read_text()) if cache.is_file() else {}
    key = f"{entry}@{seed}"
    if key not in got:
        scen, _, opp = entry.partition(":")
        theirs = paper_move_robot(cfg, opp) if opp in PAPER_MOVE_OPPONENTS else None
        got[key] = evaluate_tank_policy(policy, scen, opp, rounds=rounds, seed=seed, opponent_policy=theirs)[1]
        cache.parent.mkdir(parents=True, exist_ok=True)
        ck.write_atomic(cache, json.dumps(got, indent=1).encode())
    return float(got[key])


def sim_shares(run: Path, cfg: Any, rounds: int, play: Play = "greedy") -> dict[str, float]:
    """The run's simulator share per league entry over ``rounds`` rounds (battle seed 10000), playing greedy
    or sampled, kept in ``<run>/eval/<play>-<rounds>.json`` (a model is evaluated once, whichever report
    asks)."""
    cache = run / "eval" / f"{play}-{rounds}.json"
    entries = list(cfg.league.opponents)
    if cache.is_file():
        got = json.loads(cache.read_text())
        if all(e in got for e in entries):
            return got
    res = evaluate_tanks(cfg, load_tank_model(run, cfg), rounds, seed=10_000, explore=play == "sampled")
    shares = {e: res[e]["share"] for e in entries}
    cache.parent.mkdir(parents=True, exist_ok=True)
    cache.write_text(json.dumps(shares, indent=1))
    return shares


@dataclass(frozen=True)
class ReportRumble:
    """The report's rumbles: the first run's exported robot in 1v1 against every robot of each folder of robot jars,
    ``rounds`` rounds on 800x600 x ``seeds`` engine seeds (0..seeds-1), ``workers`` battles at once (None: the
    CPUs)."""

    folders: tuple[Path, ...]
    seeds: int = 2
    rounds: int = 35  # the RoboRumble's
    workers: int | None = None


def report(runs: list[Path], out: Path, rounds: int, engine: bool, engine_seeds: int, unseen: bool = False,
           compare_work: Path | None = None, engine_from: Path | None = None, engine_runs: int = 1,
           play: Play = "greedy", rumble: ReportRumble | None = None,
           results_from: Path | None = None) -> dict[str, Any]:
    """Evaluate the runs and write the report; return the results (``unseen``: also the first run's exported
    robot in the engine against :data:`UNSEEN`, robots no league entry names; ``compare_work``: also the
    comparison with the baselines, :mod:`confront.experiments.tank_compare`, trained and cached there;
    ``engine_from``: the engine rows of an earlier ``results.json`` of the same first run, instead of playing;
    ``engine_runs``: how many of the runs, from the first, play in the engine; ``play``: the policy's actions,
    greedy or sampled, in the simulator and the exported robot; ``rumble``: also the first run's rumbles;
    ``results_from``: every row but the rumbles from an earlier ``results.json`` of the same first run, nothing
    evaluated)."""
    out.mkdir(parents=True, exist_ok=True)
    if results_from is not None:
        result = earlier_results(results_from, runs[0], play)
    else:
        result = _evaluate(runs, out, rounds, engine, engine_seeds, unseen, compare_work, engine_from, engine_runs,
                           play)
    if rumble is not None:
        played = play_rumbles(runs[0], out, rumble, play)
        result["rumbles"] = [r for r in result.get("rumbles", []) if r["out"] not in {p["out"] for p in played}]
        result["rumbles"] += played
    (out / "results.json").write_text(json.dumps(result, indent=1))
    _curves(runs, out)
    write_markdown(result, out)
    return result


def _earlier_of(path: Path, run: Path) -> dict[str, Any]:
    """An earlier report's results.json, checked to be of ``run`` as its first run: the same name, or the same
    training (the summary's rounds and decisions; a run folder may be renamed when it is shipped)."""
    earlier: dict[str, Any] = json.loads(path.read_text())
    summary = json.loads((run / "summary.json").read_text())
    trained = (earlier.get("trained") or [{}])[0]
    if earlier["runs"][0] != run.name and not all(trained.get(k) == summary.get(k) for k in ("rounds", "decisions")):
        raise ValueError(f"{path} is of run {earlier['runs'][0]}, not {run.name} (neither the name nor the training "
                         "summary's rounds and decisions match)")
    return earlier


def earlier_results(path: Path, run: Path, play: Play) -> dict[str, Any]:
    """An earlier report's results (every row as it was), checked to be of ``run`` playing ``play``."""
    earlier = _earlier_of(path, run)
    if earlier.get("play", "greedy") != play:
        raise ValueError(f"{path} is of the {earlier.get('play', 'greedy')} policy: give --play "
                         f"{earlier.get('play', 'greedy')}")
    return earlier


def play_rumbles(run: Path, out: Path, rumble: ReportRumble, play: Play) -> list[dict[str, Any]]:
    """The run's exported robot (playing ``play``) in a 1v1 rumble against each folder
    (:func:`confront.experiments.rumble.run_rumble`), kept in ``<out>/rumble/<folder>-<play>/`` so that its battles
    are never played twice; per folder the rumble's title and table rows, as its ``rumble.json`` has them."""
    import tempfile
    from dataclasses import asdict

    from confront.experiments.evaluate import run_jar
    from confront.experiments.rumble import RumbleSettings, default_workers, run_rumble

    settings = RumbleSettings("1v1", seeds=rumble.seeds, rounds=rumble.rounds)
    played = []
    with tempfile.TemporaryDirectory(prefix="confront-report-") as tmp:
        jar = run_jar(run, Path(tmp), play)  # the same robot each time: a rerun resumes the stored battles
        for folder in rumble.folders:
            where = Path("rumble") / f"{folder.name}-{play}"
            got = run_rumble(str(jar), folder, settings, out / where, workers=rumble.workers or default_workers(),
                             progress=sys.stderr.isatty())
            played.append({"folder": folder.name, "out": str(where), "title": got.title,
                           "rows": [asdict(r) for r in got.rows]})
    return played


def _evaluate(runs: list[Path], out: Path, rounds: int, engine: bool, engine_seeds: int, unseen: bool,
              compare_work: Path | None, engine_from: Path | None, engine_runs: int, play: Play) -> dict[str, Any]:
    """The simulator and engine rows of :func:`report` (and the comparison's files in ``out``)."""
    cfgs = [config_from_dict(load_toml(r / "config.toml")) for r in runs]
    entries = list(cfgs[0].league.opponents)
    sim: dict[str, list[float]] = {e: [] for e in entries}
    for run, cfg in zip(runs, cfgs, strict=True):
        res = sim_shares(run, cfg, rounds, play)
        for e in entries:
            sim[e].append(res[e])
    real: dict[str, list[float]] = {}
    real_runs: dict[str, list[list[float]]] = {}  # per engine run, its battles
    if engine:
        from confront.arena.bots import BOT_NAMES
        from confront.arena.scenarios import SAMPLE_TEAMS
        from confront.arena.tech import TECH_ROBOTS
        from confront.engine.tank_export import load_tank_policy

        policy = load_tank_policy(runs[0], play)
        for i, run in enumerate(runs[:engine_runs]):
            pol = policy if i == 0 else load_tank_policy(run, play)
            for e in entries:
                if e.partition(":")[2] in (*BOT_NAMES, *TECH_ROBOTS, *SAMPLE_TEAMS, *PAPER_MOVE_OPPONENTS):
                    real_runs.setdefault(e, []).append([engine_share(run, pol, e, rounds, k + 1, cfgs[i])
                                                        for k in range(engine_seeds)])
        real = {e: v[0] for e, v in real_runs.items()}
    unseen_rows: list[dict[str, Any]] = []
    earlier_rumbles: list[dict[str, Any]] = []
    if engine_from is not None:
        earlier = _earlier_of(engine_from, runs[0])
        real = {r["entry"]: r["engine"] for r in earlier["rows"] if r.get("engine")}
        unseen_rows = earlier.get("unseen", [])
        earlier_rumbles = earlier.get("rumbles", [])
        engine_seeds = earlier["engine_seeds"]
    if engine and unseen:
        for e in UNSEEN:
            unseen_rows.append({"entry": e, "engine": [engine_share(runs[0], policy, e, rounds, k + 1)
                                                       for k in range(engine_seeds)]})
    summaries = [json.loads((r / "summary.json").read_text()) for r in runs]
    result = {"runs": [r.name for r in runs], "rounds": rounds, "play": play,
              "engine_seeds": engine_seeds if engine or engine_from is not None else 0,
              "trained": [{k: s[k] for k in ("rounds", "wall_time_s", "decisions")} for s in summaries],
              "engine_runs": [r.name for r in runs[:engine_runs]] if engine else [],
              "rows": [{"entry": e, "sim": sim[e], "engine": real.get(e), "engine_runs": real_runs.get(e),
                        "target": target_of(e)} for e in entries],
              "unseen": unseen_rows, "rumbles": earlier_rumbles}
    if compare_work is not None:
        from confront.experiments.tank_compare import compare, compare_entries

        compare(runs, out, rounds, compare_work, ours={e: sim[e] for e in compare_entries(tuple(entries))},
                play=play)
    return result


def write_markdown(result: dict[str, Any], out: Path) -> Path:
    """``report.md`` from ``results.json``'s content (the figures beside it)."""
    runs, trained, rounds, seeds = result["runs"], result["trained"], result["rounds"], result["engine_seeds"]
    lines = [
        "# PPO tanks: the recommended learner, per opponent",
        "",
        f"Runs (training seeds): {', '.join(runs)}; each trained "
        f"{', '.join(str(s['rounds']) for s in trained)} rounds in "
        f"{', '.join(format(s['wall_time_s'], '.0f') for s in trained)} s "
        f"({', '.join(format(s['decisions'], ',') for s in trained)} decisions).",
        f"Simulator: the {result.get('play', 'greedy')} policy, {rounds} rounds per opponent (battle seed 10000)"
        + (f"; mean and 95% t-interval over {len(runs)} training seeds, then the first run alone." if len(runs) > 1
           else "; one training seed, so no interval over seeds."),
        (f"Engine: the exported `confront.TankBot` jar (no Python; playing {result.get('play', 'greedy')}) in "
         f"Robocode 1.9.3.9, {seeds} battles of "
         f"{rounds} rounds per sample-robot and paper-move entry (engine seeds 1..{seeds}; the TD team, the dodge "
         "and random moves play as the exported `confront.PolicyBot`, random ties drawn with Math.random, which "
         "the engine's seed does not reach), the first run's policy; `sim - engine` compares that same policy."
         if seeds else "Engine: not run (pass --engine)."),
        "Target: the issue's engine share for the entry; `met` compares the engine mean with it.",
        "",
    ]
    k_runs = len(result.get("engine_runs", []))
    if k_runs > 1:
        lines.insert(-2, f"Engine, {k_runs} runs ({', '.join(result['engine_runs'])}): each run's mean over its "
                        f"{seeds} battles, then the mean of those and its 95% t-interval over runs; `runs met`: how "
                        "many of the runs' engine means reach the target.")
    extra = (f" engine, {k_runs} runs | runs met |", "---:|:---:|") if k_runs > 1 else ("", "")
    lines += [f"| opponent | simulator, {len(runs)} seeds | simulator, {runs[0]} | engine, {runs[0]} (battles) | "
              f"engine mean | sim - engine |{extra[0]} target | met |",
              f"|---|---:|---:|---:|---:|---:|{extra[1]}---:|:---:|"]
    for row in result["rows"]:
        e, sim, r, tgt = row["entry"], row["sim"], row["engine"], row["target"]
        m, lo, hi = mean_interval(sim)
        s_txt = f"{m:.3f}" + (f" [{lo:.3f}, {hi:.3f}]" if not math.isnan(lo) else "")
        t_txt = "-" if tgt is None else f"{tgt:.2f}"
        k_txt = ""
        if k_runs > 1:
            per_run = [float(np.mean(b)) for b in row.get("engine_runs") or []]
            if per_run:
                km, klo, khi = mean_interval(per_run)
                n_met = "" if tgt is None else f"{sum(v >= tgt for v in per_run)}/{len(per_run)}"
                k_txt = f" {km:.3f} [{klo:.3f}, {khi:.3f}] | {n_met} |"
            else:
                k_txt = " - | |"
        if r:
            em = float(np.mean(r))
            met = "" if tgt is None else ("yes" if em >= tgt else "no")
            lines.append(f"| {e} | {s_txt} | {sim[0]:.3f} | {' / '.join(f'{v:.3f}' for v in r)} | {em:.3f} | "
                         f"{sim[0] - em:+.3f} |{k_txt} {t_txt} | {met} |")
        else:
            lines.append(f"| {e} | {s_txt} | {sim[0]:.3f} | - | - | - |{k_txt} {t_txt} | |")
    if result.get("unseen"):
        n_b = len(result["unseen"][0]["engine"])
        lines += ["", f"Robots no league entry names (the first run's exported robot in the engine, {n_b} battle(s) of "
                  f"{rounds} rounds each, engine seeds 1..{n_b}; the issue sets no target for them):", "",
                  "| opponent | engine (battles) | engine mean |", "|---|---:|---:|"]
        lines += [f"| {u['entry']} | {' / '.join(f'{v:.3f}' for v in u['engine'])} | {np.mean(u['engine']):.3f} |"
                  for u in result["unseen"]]
    for rum in result.get("rumbles", []):
        lines += ["", *_rumble_lines(rum)]
    if (out / "compare.md").is_file():
        lines += ["", "Against the paper's method, SB3 PPO and random moves over training seeds, with one-sided tests: "
                  "[compare.md](compare.md) (`python -m confront.experiments.tank_compare`)."]
    figs = sorted(out.glob("share_vs_*.png"))
    lines += ["", *[f"![{f.stem}]({f.name})" for f in figs], ""]
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def _rumble_lines(rum: dict[str, Any]) -> list[str]:
    """A rumble's section of report.md: the rumble's own Markdown table (``rumble.md``) of its stored rows."""
    from confront.experiments.rumble import RumbleRow, to_markdown

    rows = [RumbleRow(**r) for r in rum["rows"]]
    return [f"Rumble against the robots of `{rum['folder']}` (the first run's exported robot, as `confront rumble` "
            f"plays it; battles and files in [{rum['out']}/]({rum['out']}/rumble.md)):", "",
            *to_markdown(rows, rum["title"]).rstrip("\n").splitlines()]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--rounds", type=int, default=100)
    ap.add_argument("--engine", action="store_true")
    ap.add_argument("--engine-seeds", type=int, default=3)
    ap.add_argument("--unseen", action="store_true", help="with --engine: also robots no league entry names")
    ap.add_argument("--engine-runs", type=int, default=1, metavar="K",
                    help="with --engine: play the first K runs in the engine (default: the first only)")
    ap.add_argument("--compare", type=Path, default=None, metavar="WORK",
                    help="also compare with the paper's method, SB3 PPO and random moves (baselines cached in WORK)")
    ap.add_argument("--engine-from", type=Path, default=None, metavar="RESULTS_JSON",
                    help="take the engine rows from an earlier results.json of the same first run")
    ap.add_argument("--play", choices=("sampled", "greedy"), default="sampled",
                    help="the policy's actions in the simulator and the exported robot: drawn from each head's "
                         "softmax as `confront export` plays (default), or each head's maximum")
    ap.add_argument("--rumble", type=Path, action="append", default=[], metavar="FOLDER",
                    help="also a 1v1 rumble of the first run's exported robot against every robot jar in FOLDER "
                         "(repeatable; kept in OUT/rumble/<folder>-<play>/, resumable)")
    ap.add_argument("--rumble-seeds", type=int, default=2, help="with --rumble: battles per opponent (default 2)")
    ap.add_argument("--rumble-rounds", type=int, default=35, help="with --rumble: rounds per battle (default 35)")
    ap.add_argument("--workers", type=int, default=None, help="with --rumble: battles at once (default: the CPUs)")
    ap.add_argument("--results-from", type=Path, default=None, metavar="RESULTS_JSON",
                    help="every row but the rumbles from an earlier results.json of the same first run (nothing "
                         "evaluated; to add rumbles to a report whose other runs are gone)")
    args = ap.parse_args()
    if args.rumble_seeds < 1 or args.rumble_rounds < 1 or (args.workers is not None and args.workers < 1):
        ap.error("--rumble-seeds, --rumble-rounds and --workers must be at least 1")
    for f in args.rumble:
        if not f.is_dir():
            ap.error(f"--rumble {f}: no such folder")
    if len({f.name for f in args.rumble}) < len(args.rumble):
        ap.error("--rumble folders must have different names (each keeps its battles in OUT/rumble/<name>-<play>/)")
    if args.results_from is not None and (args.engine or args.engine_from or args.compare or len(args.runs) > 1):
        ap.error("--results-from takes every row from an earlier report: give one run, without --engine, "
                 "--engine-from or --compare")
    if args.rounds < 1 or args.engine_seeds < 1 or not 1 <= args.engine_runs <= len(args.runs):
        ap.error("--rounds and --engine-seeds must be at least 1, --engine-runs between 1 and the number of runs")
    if args.engine_from is not None and args.engine:
        ap.error("--engine plays the battles, --engine-from reads them: give one")
    for r in args.runs:
        if not (r / "config.toml").is_file() or not (r / "model" / "model.json").is_file():
            ap.error(f"{r} is not a trained run folder (config.toml and model/model.json)")
    rumble = (ReportRumble(tuple(args.rumble), args.rumble_seeds, args.rumble_rounds, args.workers)
              if args.rumble else None)
    try:
        res = report(args.runs, args.out, args.rounds, args.engine, args.engine_seeds, args.unseen, args.compare,
                     args.engine_from, args.engine_runs, args.play, rumble, args.results_from)
    except (ValueError, FileNotFoundError) as err:  # bad input found on the way: one line, exit 2
        ap.error(str(err))
    print((args.out / "report.md").read_text())
    print(json.dumps({"report": str(args.out / "report.md"), "entries": len(res["rows"])}))


if __name__ == "__main__":
    main()
