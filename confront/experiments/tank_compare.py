"""PPO tanks against the paper's method, SB3 PPO and random moves, matchup by matchup, paired over training seeds.

    python -m confront.experiments.tank_compare RUN [RUN ...] --out docs/results/tanks [--rounds 100]
    python -m confront.experiments.tank_compare --from-report docs/results/tanks/results.json --out ...

(``--from-report``: PPO tanks' shares from a tank_report; paired over its runs' training seeds, ``seedK``.)

Each RUN is a PPO tanks run (``confront train -c tanks --set train.seed=K``); its seed K is the pairing key.
For every seed K the other methods are trained as ``confront reproduce baselines`` trains them (the paper's
4v4 against the seed's TD team, 500 rounds, the paper's state and four moves, T = 10):

- ``DMNN (FLM)``: the paper's method (DMNN, adaptive momentum, fuzzy learning rate, SSAQ);
- ``PPO (SB3)``: Stable-Baselines3's PPO shared by the team's tanks (:func:`baselines.train_sb3`);
- ``Random moves``: each tank picks one of the paper's four moves at random (no training).

Then every method plays ``--rounds`` greedy rounds per league entry that names a sample robot, the TD team or
the dodge, in the simulator: PPO tanks through :func:`tanks.evaluate_tanks`, the others through
:func:`evaluate.sim_evaluate` with the entry's scenario (1v1 or 4v4). Both sides of a seed face the same
TD-team artefact (the PPO run's) and the same dodge (:func:`dodge_learner`), each at its own step length. Per
entry and method: the mean share over seeds and ``PPO tanks - method`` paired over seeds (BCa interval, one-sided
sign-flip permutation p).

Writes ``compare.json`` and ``compare.md`` into ``--out``. Trained baselines and per-(method, seed) results are
cached under ``--work`` (default ``runs/tank-compare``), so an interrupted comparison resumes.

    python -m confront.experiments.tank_compare --from-report docs/results/tanks/results.json \
        --engine robocode \
        --out docs/results/tanks [--rounds 30] [--engine-seed 1]

``--engine robocode``: the same comparison in Robocode 1.9.3.9, paired over the report's engine runs (``seedK``:
training seed K). PPO tanks' share per seed and entry is the mean of the report's engine battles (the exported
TankBot); the baselines are trained as above and play as exported PolicyBots (:func:`engine_policy`), one battle
of ``--rounds`` rounds (engine seed ``--engine-seed``) per entry, against the sample robots or the seed's TD team
(exported PolicyBots, greedy with random ties, at the baselines' step length). Writes ``compare-engine.json`` and
``compare-engine.md``; each battle is cached under ``--work``/engine as it ends.
"""

from __future__ import annotations

import argparse
import json
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from confront import checkpoint as ck
from confront.arena.bots import BOT_NAMES
from confront.experiments.baselines import (
    DMNN_METHOD,
    RANDOM_METHOD,
    BaselinesConfig,
    SB3Policy,
    baseline_experiment,
    pooled_ratio,
    sb3_activation,
    sb3_exported_policy,
    train_sb3,
)
from confront.experiments.evaluate import exported_policy, sim_evaluate
from confront.experiments.jobs import Job, run_jobs
from confront.experiments.tank_evaluate import evaluate_tanks
from confront.learning.base import Learner
from confront.learning.tabular import TabularQ
from confront.stats import paired_comparison
from confront.train.league import paper_move_robot, paper_move_values
from confront.train.ppo_model import load_tank_model
from confront.train.spec import ExperimentConfig, config_from_dict, load_toml

__all__ = ["OURS", "METHODS", "compare_entries", "method_shares", "compare", "engine_policy",
           "engine_method_shares", "compare_engine", "write_markdown"]

OURS = "PPO tanks"
SB3_PPO = "PPO (SB3)"
METHODS = (DMNN_METHOD, SB3_PPO, RANDOM_METHOD)
TRAIN_ROUNDS = 500  # the baselines' budget (the paper's)
ENGINE_SEED = 1  # the baselines' engine battle (tank_report played PPO tanks' at engine seeds 1, 2, 3)


def compare_entries(opponents: tuple[str, ...]) -> list[str]:
    """The league entries every method can play: a sample robot (1v1 or as a team), the TD team or the dodge."""
    out = []
    for e in opponents:
        scen, _, opp = e.partition(":")
        if scen in ("1v1", "4v4") and (opp in BOT_NAMES or opp == "dodge" or (opp == "td" and scen == "4v4")):
            out.append(e)
    return out


def dodge_learner(exp: ExperimentConfig) -> TabularQ:
    """The hand-written dodge as a greedy table learner: its move values (:func:`tanks.paper_move_values`), the
    two moves it draws from tied, so greedy play with random ties is the dodge's uniform draw."""
    learner = TabularQ()
    learner.q[...] = paper_move_values(exp, "dodge")
    return learner


def _baseline_policy(method: str, seed: int, work: Path, td_name: str) -> tuple[Learner, ExperimentConfig]:
    """The trained (or, for random moves, built) policy of ``method`` at ``seed``, and its experiment config
    (a trained DMNN is kept per TD-team artefact ``td_name``)."""
    from confront.learning.uniform import UniformParams, UniformPolicy
    from confront.train.paper_model import load_model, smdp_config

    bcfg = BaselinesConfig()
    exp = baseline_experiment(bcfg, seed, TRAIN_ROUNDS)
    if method == RANDOM_METHOD:
        return UniformPolicy(UniformParams(n_actions=smdp_config(exp).n_actions)), exp
    if method == DMNN_METHOD:
        folder = work / "runs" / "dmnn-flm" / td_name / f"seed-{seed}"
        run_jobs([Job("tank-compare", DMNN_METHOD, seed, bcfg.base,
                      bcfg.overrides + ('learner.learning_rate="fuzzy"',), folder)], TRAIN_ROUNDS, 1)
        learner, _ = load_model(folder)
        return learner, exp
    if method == SB3_PPO:
        model, info = train_sb3("PPO", bcfg, seed, TRAIN_ROUNDS)
        policy = SB3Policy(model, int(model.action_space.n))
        folder = work / "sb3-ppo" / f"seed-{seed}"
        folder.mkdir(parents=True, exist_ok=True)
        ck.write_npz(folder / "policy.npz", policy.state_dict())
        ck.write_atomic(folder / "train.json", json.dumps({**info, "activation": sb3_activation(model)},
                                                          indent=1).encode())
        return policy, exp
    raise ValueError(f"unknown method {method!r}; use one of {', '.join(METHODS)}")


def _result_file(method: str, seed: int) -> str:
    """The cache file name of a method's results at a seed."""
    return f"{method.replace(' ', '_').replace('(', '').replace(')', '')}-seed-{seed}.json"


def method_shares(method: str, seed: int, entries: list[str], td_model: str, rounds: int, work: Path
                  ) -> dict[str, float]:
    """Greedy share per entry of a baseline method at ``seed`` (cached in ``work``, with the TD team it trained
    against and faced: a cache made against another TD-team artefact is played again)."""
    done = work / "results" / _result_file(method, seed)
    td_name = Path(td_model).name  # the artefact's digest folder (its config and seed), not this machine's path
    if done.exists():
        cached = json.loads(done.read_text())
        if (cached.get("rounds") == rounds and cached.get("td_team") == td_name
                and all(e in cached["shares"] for e in entries)):
            return {e: cached["shares"][e] for e in entries}
    policy, exp = _baseline_policy(method, seed, work, td_name)
    shares = {}
    for e in entries:
        scen, _, opp = e.partition(":")
        cfg = replace(exp, arena=replace(exp.arena, scenario=scen))
        rows = sim_evaluate(cfg, policy, "td" if opp == "dodge" else opp, rounds, 10_000 + seed,
                            td_model if opp == "td" else None,
                            opponent_learner=dodge_learner(exp) if opp == "dodge" else None)
        shares[e] = pooled_ratio(rows)[2]
    done.parent.mkdir(parents=True, exist_ok=True)
    ck.write_atomic(done, json.dumps({"method": method, "seed": seed, "rounds": rounds, "td_team": td_name,
                                      "shares": shares}, indent=1).encode())
    return shares


def engine_paper_move_robot(exp: ExperimentConfig, opp: str) -> Any:
    """A paper-move opponent (``"random"``, ``"dodge"``) as the engine's PolicyBot at the baselines' step length
    and observation (:func:`tanks.paper_move_robot` with the baselines' experiment ``exp``)."""
    from confront.train.paper_model import smdp_config

    return replace(paper_move_robot(exp, opp), observation=smdp_config(exp).observation,
                   step_turns=exp.arena.decision_turns)


def engine_policy(method: str, seed: int, work: Path, td_name: str) -> Any:
    """``method`` at ``seed`` as the engine's PolicyBot (an ExportedPolicy at the baselines' step length), trained
    by :func:`_baseline_policy` where it is not yet in ``work``: DMNN (FLM) greedy (``ExportedPolicy.from_learner``),
    SB3 PPO deterministic (:func:`sb3_exported_policy` of the kept ``policy.npz``), random moves as zero move
    values with random ties (:func:`engine_paper_move_robot`)."""
    from confront.train.paper_model import smdp_config

    exp = baseline_experiment(BaselinesConfig(), seed, TRAIN_ROUNDS)
    observation, step_turns = smdp_config(exp).observation, exp.arena.decision_turns
    if method == RANDOM_METHOD:
        return engine_paper_move_robot(exp, "random")
    if method == SB3_PPO:
        folder = work / "sb3-ppo" / f"seed-{seed}"
        info = json.loads((folder / "train.json").read_text()) if (folder / "train.json").is_file() else {}
        if "activation" not in info or not (folder / "policy.npz").is_file():
            _baseline_policy(method, seed, work, td_name)
            info = json.loads((folder / "train.json").read_text())
        with np.load(folder / "policy.npz", allow_pickle=False) as z:
            state = {k: z[k] for k in z.files}
        return sb3_exported_policy(state, info["activation"], observation, step_turns)
    learner, exp = _baseline_policy(method, seed, work, td_name)
    return exported_policy(learner, exp)


def engine_method_shares(method: str, seed: int, entries: list[str], td_model: str, rounds: int, work: Path,
                         engine_seed: int = ENGINE_SEED) -> dict[str, float]:
    """Share per entry of a baseline method at ``seed`` in Robocode: :func:`engine_policy` for our side, one
    battle of ``rounds`` rounds (engine seed ``engine_seed``) against the entry's sample robot(s) or the TD team
    ``td_model`` or the dodge (exported PolicyBots, greedy with random ties, at the baselines' step length and
    observation: :func:`engine_paper_move_robot`). Each battle is
    kept in ``work/engine`` as it ends; one of other rounds, engine seed or TD-team artefact is played again."""
    from confront.engine.evaluate import evaluate_policy
    from confront.train.paper_model import load_model

    path = work / "engine" / _result_file(method, seed)
    key: dict[str, Any] = {"method": method, "seed": seed, "rounds": rounds, "engine_seed": engine_seed,
           "td_team": Path(td_model).name}
    cached = json.loads(path.read_text()) if path.is_file() else {}
    shares: dict[str, float] = dict(cached["shares"]) if all(cached.get(k) == v for k, v in key.items()) else {}
    ours = None
    theirs: dict[str, Any] = {}
    for e in entries:
        if e in shares:
            continue
        scen, _, opp = e.partition(":")
        if ours is None:
            ours = engine_policy(method, seed, work, key["td_team"])
        if opp in ("td", "dodge") and opp not in theirs:
            exp = baseline_experiment(BaselinesConfig(), seed, TRAIN_ROUNDS)
            theirs[opp] = (replace(exported_policy(load_model(td_model)[0], exp), ties="random") if opp == "td"
                           else engine_paper_move_robot(exp, opp))
        shares[e] = evaluate_policy(ours, scen, opp, rounds=rounds, seed=engine_seed,
                                    opponent_policy=theirs.get(opp))[1]
        path.parent.mkdir(parents=True, exist_ok=True)
        ck.write_atomic(path, json.dumps({**key, "shares": shares}, indent=1).encode())
    return {e: shares[e] for e in entries}


def _paired_tests(shares: dict[str, dict[str, list[float]]], entries: list[str]) -> dict[str, Any]:
    """``PPO tanks - method`` per method and entry, paired over seeds (:func:`stats.paired_comparison`)."""
    rng = np.random.default_rng(2026)
    tests: dict[str, Any] = {m: {} for m in METHODS}
    for m in METHODS:
        for e in entries:
            pc = paired_comparison(np.array(shares[OURS][e]), np.array(shares[m][e]), rng)
            tests[m][e] = {"diff": pc.diff.mean, "lo": pc.diff.lo, "hi": pc.diff.hi, "p": pc.p}
    return tests


def compare(runs: list[Path], out: Path, rounds: int, work: Path, ours: dict[str, list[float]] | None = None,
            play: str = "greedy") -> dict[str, Any]:
    """Evaluate PPO tanks and every baseline method per seed and entry; write the report; return the results.
    ``ours``: PPO tanks' shares per entry (one per run, in order) when already measured (tank_report's);
    ``play``: how PPO tanks played them (``"greedy"`` or ``"sampled"``; the baselines play greedily)."""
    from confront.train.league import td_team

    cfgs = [config_from_dict(load_toml(r / "config.toml")) for r in runs]
    seeds = [c.train.seed for c in cfgs]
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"the runs must have distinct training seeds, got {seeds}")
    entries = compare_entries(tuple(cfgs[0].league.opponents))
    shares: dict[str, dict[str, list[float]]] = {m: {e: [] for e in entries} for m in (OURS, *METHODS)}
    for k, (run, cfg) in enumerate(zip(runs, cfgs, strict=True)):
        _, td_path = td_team(cfg, 4)
        if ours is None:
            got_ours = evaluate_tanks(cfg, load_tank_model(run, cfg), rounds, seed=10_000 + cfg.train.seed,
                                      opponents=tuple(entries), explore=play == "sampled")
        for e in entries:
            shares[OURS][e].append(ours[e][k] if ours is not None else got_ours[e]["share"])
        for m in METHODS:
            got = method_shares(m, cfg.train.seed, entries, str(td_path), rounds, work)
            for e in entries:
                shares[m][e].append(got[e])
    tests = _paired_tests(shares, entries)
    result = {"runs": [r.name for r in runs], "seeds": seeds, "rounds": rounds, "train_rounds": TRAIN_ROUNDS,
              "entries": entries, "shares": shares, "tests": tests, "play": play,
              "ours_battle_seed": "10000" if ours is not None else "10000 + seed"}
    out.mkdir(parents=True, exist_ok=True)
    (out / "compare.json").write_text(json.dumps(result, indent=1))
    write_markdown(result, out)
    return result


def welch_greater(a: list[float], b: list[float]) -> dict[str, float]:
    """Mean difference a - b, its 95% Welch interval and the one-sided Welch t p (a > b), unpaired."""
    from scipy import stats

    x, y = np.asarray(a, float), np.asarray(b, float)
    d = float(x.mean() - y.mean())
    if x.std() == 0 and y.std() == 0:
        return {"diff": d, "lo": d, "hi": d, "p": 0.0 if d > 0 else 1.0}
    t = stats.ttest_ind(x, y, equal_var=False, alternative="greater")
    ci = stats.ttest_ind(x, y, equal_var=False).confidence_interval(0.95)
    return {"diff": d, "lo": float(ci.low), "hi": float(ci.high), "p": float(t.pvalue)}


def compare_report(results: Path, out: Path, work: Path, base_seeds: list[int], rounds: int = 100
                   ) -> dict[str, Any]:
    """PPO tanks' shares from a tank_report ``results.json`` against the baselines, per seed's TD team
    (``confront train -c tanks``'s). When every run names its training seed (``seedK``) the baselines are trained at
    those seeds and the comparison is paired over them (as ``--engine robocode``); otherwise at ``base_seeds``,
    unpaired: Welch's t."""
    from confront.train.league import td_team
    from confront.train.spec import load_experiment

    rep = json.loads(results.read_text())
    if rep["rounds"] != rounds:
        raise ValueError(f"{results} evaluated {rep['rounds']} rounds per entry, this comparison {rounds}")
    seeds = _named_seeds(rep["runs"])
    if seeds is not None:
        base_seeds = seeds
    entries = compare_entries(tuple(r["entry"] for r in rep["rows"]))
    shares: dict[str, dict[str, list[float]]] = {OURS: {r["entry"]: r["sim"] for r in rep["rows"]
                                                        if r["entry"] in entries}}
    shares.update({m: {e: [] for e in entries} for m in METHODS})
    for seed in base_seeds:
        _, td_path = td_team(load_experiment("tanks", (f"train.seed={seed}",)), 4)
        for m in METHODS:
            got = method_shares(m, seed, entries, str(td_path), rounds, work)
            for e in entries:
                shares[m][e].append(got[e])
    result: dict[str, Any] = {"runs": rep["runs"], "base_seeds": base_seeds, "rounds": rounds,
                              "train_rounds": TRAIN_ROUNDS, "entries": entries, "shares": shares,
                              "play": rep.get("play", "greedy"), "ours_battle_seed": 10_000}
    if seeds is not None:
        result.update(seeds=seeds, tests=_paired_tests(shares, entries), test="paired")
    else:
        result.update(seeds=rep["runs"], test="welch",
                      tests={m: {e: welch_greater(shares[OURS][e], shares[m][e]) for e in entries} for m in METHODS})
    out.mkdir(parents=True, exist_ok=True)
    (out / "compare.json").write_text(json.dumps(result, indent=1))
    write_markdown(result, out)
    return result


def _named_seeds(runs: list[str]) -> list[int] | None:
    """The runs' training seeds when every run names a distinct one (``seedK``), else None."""
    try:
        seeds = [run_seed(r) for r in runs]
    except ValueError:
        return None
    return seeds if len(set(seeds)) == len(seeds) else None


def run_seed(name: str) -> int:
    """The training seed a report's run is named by (``seedK``, as ``confront train -c tanks --set train.seed=K``
    runs are named in the reports)."""
    m = re.fullmatch(r"(?:.*\D)?seed-?(\d+)", name)
    if m is None:
        raise ValueError(f"run {name!r} does not name its training seed (seedK)")
    return int(m.group(1))


def compare_engine(results: Path, out: Path, rounds: int, work: Path, engine_seed: int = ENGINE_SEED
                   ) -> dict[str, Any]:
    """PPO tanks' Robocode shares from a tank_report ``results.json`` (per engine run, training seed K: the mean
    of its battles) against every baseline at seed K in Robocode (:func:`engine_method_shares`), paired over
    seeds; writes ``compare-engine.json`` and ``compare-engine.md``."""
    from confront.train.league import td_team
    from confront.train.spec import load_experiment

    rep = json.loads(results.read_text())
    runs = list(rep.get("engine_runs") or [])
    if not runs:
        raise ValueError(f"{results} has no engine runs (tank_report --engine --engine-runs K)")
    seeds = [run_seed(r) for r in runs]
    rows = {r["entry"]: r for r in rep["rows"]}
    entries = compare_entries(tuple(rows))
    ours: dict[str, list[float]] = {}
    for e in entries:
        battles = rows[e].get("engine_runs")
        if not battles or len(battles) != len(runs):
            raise ValueError(f"{results}: entry {e} lacks the engine battles of the runs {runs}")
        ours[e] = [float(np.mean(b)) for b in battles]
    shares: dict[str, dict[str, list[float]]] = {OURS: ours, **{m: {e: [] for e in entries} for m in METHODS}}
    for seed in seeds:
        _, td_path = td_team(load_experiment("tanks", (f"train.seed={seed}",)), 4)
        for m in METHODS:
            got = engine_method_shares(m, seed, entries, str(td_path), rounds, work, engine_seed)
            for e in entries:
                shares[m][e].append(got[e])
    result = {"runs": runs, "seeds": seeds, "rounds": rounds, "train_rounds": TRAIN_ROUNDS, "entries": entries,
              "shares": shares, "tests": _paired_tests(shares, entries),
              "engine": {"engine_seed": engine_seed, "ours_rounds": rep["rounds"],
                         "ours_battles": rep["engine_seeds"], "ours_play": rep.get("play", "greedy")}}
    out.mkdir(parents=True, exist_ok=True)
    (out / "compare-engine.json").write_text(json.dumps(result, indent=1))
    write_markdown(result, out, "compare-engine.md")
    return result


def write_markdown(result: dict[str, Any], out: Path, name: str = "compare.md") -> Path:
    """``compare.md`` (or ``name``) from ``compare.json``'s (or ``compare-engine.json``'s) content."""
    seeds, entries, shares, tests = result["seeds"], result["entries"], result["shares"], result["tests"]
    n = len(seeds)
    paired = (f"Cells: mean share over the {n} seeds; `vs X`: PPO tanks - X, mean [95% BCa interval], one-sided "
              "paired sign-flip permutation p (the smallest possible p with n seeds is 2^-n).")
    if "engine" in result:
        eng = result["engine"]
        how = [f"Training seeds {', '.join(map(str, seeds))} (runs {', '.join(result['runs'])}; the baselines "
               f"trained {result['train_rounds']} rounds against the same seed's TD team, as `confront reproduce "
               "baselines`). Robocode 1.9.3.9, exported robots, no Python in the loop. PPO tanks: the exported "
               f"TankBot, {eng['ours_play']}, the mean of {eng['ours_battles']} battles x {eng['ours_rounds']} "
               f"rounds (engine seeds 1-{eng['ours_battles']}) per entry and seed, from the report's results.json. "
               "The baselines: exported PolicyBots, greedy (random moves: a uniform draw each step), "
               f"1 battle x {result['rounds']} rounds (engine seed {eng['engine_seed']}) per entry and seed. "
               "The TD team: the seed's artefact as exported PolicyBots (greedy, random ties), at the step length "
               "of the side it faces, as in the simulator comparison.",
               paired]
    elif result.get("test") == "welch":
        how = [f"PPO tanks: training seeds {', '.join(map(str, seeds))} ({result.get('play', 'greedy')} shares of "
               f"the report, battle seed 10000); the baselines: seeds {', '.join(map(str, result['base_seeds']))}, "
               "each trained "
               f"{result['train_rounds']} rounds against that seed's TD team, as `confront reproduce baselines` "
               "(battle seed 10000 + seed). Simulator, greedy, "
               f"{result['rounds']} rounds per entry and seed.",
               "Cells: mean share over seeds; `vs X`: PPO tanks - X, mean [95% Welch interval], one-sided Welch t p "
               "(unpaired: the seed sets differ)."]
    else:
        play = result.get("play", "greedy")
        how = [f"Training seeds {', '.join(map(str, seeds))} (one PPO tanks run each; the baselines trained "
               f"{result['train_rounds']} rounds against the same seed's TD team, as `confront reproduce "
               f"baselines`). Simulator, PPO tanks {play} (battle seed {result.get('ours_battle_seed', '10000 + seed')}"
               f"), the baselines greedy (battle seed 10000 + seed), {result['rounds']} rounds per entry and seed.",
               paired]
    lines = [
        "# PPO tanks against the paper's method, SB3 PPO and random moves" + (" in Robocode" if "engine" in result
                                                                              else ""),
        "",
        *how,
        "",
        "| entry | " + " | ".join([OURS, *METHODS]) + " | " + " | ".join(f"vs {m}" for m in METHODS) + " |",
        "|---|" + "---:|" * (1 + len(METHODS)) + ":---|" * len(METHODS),
    ]
    beats = {m: 0 for m in METHODS}
    for e in entries:
        cells = [f"{np.mean(shares[k][e]):.3f}" for k in (OURS, *METHODS)]
        vs = []
        for m in METHODS:
            t = tests[m][e]
            beats[m] += t["p"] < 0.05 and t["diff"] > 0
            vs.append(f"{t['diff']:+.3f} [{t['lo']:+.3f}, {t['hi']:+.3f}] p={t['p']:.3g}")
        lines.append(f"| {e} | " + " | ".join(cells) + " | " + " | ".join(vs) + " |")
    lines += ["", "PPO tanks ahead at p < 0.05: " + "; ".join(f"{m} on {beats[m]} of {len(entries)} entries"
                                                          for m in METHODS) + ".", ""]
    path = out / name
    path.write_text("\n".join(lines) + "\n")
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="*", type=Path)
    ap.add_argument("--from-report", type=Path, default=None, metavar="RESULTS_JSON",
                    help="PPO tanks' shares from a tank_report results.json instead of RUNs (paired over the runs' "
                         "training seeds when they are named seedK, else unpaired: Welch)")
    ap.add_argument("--base-seeds", type=int, default=5,
                    help="with --from-report whose runs do not name their training seeds (seedK): baseline seeds "
                         "0..N-1")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--rounds", type=int, default=100)
    ap.add_argument("--work", type=Path, default=Path("runs") / "tank-compare")
    ap.add_argument("--engine", choices=("sim", "robocode"), default="sim",
                    help="robocode: the baselines in the real engine against PPO tanks' engine shares of the report "
                         "(needs --from-report), paired over its runs' training seeds")
    ap.add_argument("--engine-seed", type=int, default=ENGINE_SEED, help="the baselines' engine battle seed")
    args = ap.parse_args()
    if args.rounds < 1:
        ap.error("--rounds must be at least 1")
    if args.engine == "robocode":
        if args.from_report is None or args.runs:
            ap.error("--engine robocode takes --from-report (PPO tanks' engine shares), not RUNs")
        compare_engine(args.from_report, args.out, args.rounds, args.work, args.engine_seed)
        print((args.out / "compare-engine.md").read_text())
        return
    if args.from_report is not None:
        compare_report(args.from_report, args.out, args.work, list(range(args.base_seeds)), args.rounds)
        print((args.out / "compare.md").read_text())
        return
    if not args.runs:
        ap.error("give the PPO tanks RUN folders, or --from-report")
    for r in args.runs:
        if not (r / "config.toml").is_file() or not (r / "model" / "model.json").is_file():
            ap.error(f"{r} is not a trained run folder (config.toml and model/model.json)")
    compare(args.runs, args.out, args.rounds, args.work)
    print((args.out / "compare.md").read_text())


if __name__ == "__main__":
    main()
