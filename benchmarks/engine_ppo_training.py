"""PPO tanks trained in the engine against the exported robot playing the same battles untrained (issue: "engine
PPO training of 100 rounds 1v1 vs SpinBot within 1.3x of the exported robot's battles").

Two runs, alternated over ``--repeats`` (the order flips each repetition):
- ``train``: ``train_run(cfg, out, engine="robocode")`` for ``load_experiment(--config, league.opponents =
  ['1v1:SpinBot'], train.rounds=--rounds, train.checkpoint_every=--battle-rounds)`` (with ``--init RUN``:
  ``train.init``), i.e. ``confront train -c tanks-engine --engine robocode --init RUN --set ...``: one engine battle
  of TankBots (sampled, logging their decisions) and one PPO update per ``--battle-rounds`` rounds, checkpoints,
  tables, model and plots;
- ``exported``: the training run's saved policy (sampled) in the same battles (rounds, engine seeds
  ``train.seed + k``, CPU constant, the engine on one CPU as in training) through ``evaluate_tank_policy``, which
  exports the jar on every call; one export is timed apart (``export_s``) and ``battles_s`` is the wall time less
  one export per battle.

Per run: wall s (the whole ``train_run`` call / the evaluations), the training's time in its battles (writing the
policy file and the engine process: ``engine_s`` of metrics/updates.csv), in reading the logs and building the
rollout (``rollout_s``) and in its updates (``update_s``), the rest (set-up: the jar's export, torch;
checkpoints, tables, model, plots), turns, decisions and x exported = train wall / exported wall (and / exported
battles without the per-call exports).
Before any timing, one untimed training of ``--warmup-rounds`` rounds and one evaluation warm up what a process
pays once (imports, the Java build check).

Usage: python benchmarks/engine_ppo_training.py [--repeats 3] [--rounds 100] [--battle-rounds 20]
       [--config tanks-engine] [--init RUN] [--set KEY=VALUE ...] [--json FILE]
Prints a table, the medians and a last line of JSON.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from confront.engine.tank_export import TANK_CPU_CONSTANT_MS, evaluate_tank_policy, export_tank_robot, load_tank_policy
from confront.train.factory import train_run
from confront.train.spec import ExperimentConfig, load_experiment

OPPONENT = "SpinBot"


def train_once(cfg: ExperimentConfig, out: Path, rep: int) -> dict[str, Any]:
    t0 = time.perf_counter()
    summary = train_run(cfg, out, progress=False, engine="robocode")
    wall = time.perf_counter() - t0
    with open(out / "metrics" / "updates.csv") as f:
        ups = list(csv.DictReader(f))
    with open(out / "metrics" / "rounds.csv") as f:
        turns = sum(int(r["turns"]) for r in csv.DictReader(f))
    engine_s = sum(float(u["engine_s"]) for u in ups)
    rollout_s = sum(float(u["rollout_s"]) for u in ups)
    update_s = sum(float(u["update_s"]) for u in ups)
    return {"mode": "train", "repeat": rep, "wall_s": wall, "battles_s": engine_s, "rollout_s": rollout_s,
            "update_s": update_s, "outside_s": wall - engine_s - rollout_s - update_s, "turns": turns,
            "decisions": summary["decisions"],
            "skipped_turns": summary["skipped_turns"], "score_ratio": summary["final_score_ratio"],
            "load": os.getloadavg()[0], "run": str(out)}


def exported_once(cfg: ExperimentConfig, run: Path, rep: int, tmp: Path) -> dict[str, Any]:
    policy = load_tank_policy(run, "sampled")
    t0 = time.perf_counter()
    export_tank_robot(policy, tmp / f"export-{rep}.jar")
    export_s = time.perf_counter() - t0
    n = -(-cfg.train.rounds // cfg.train.checkpoint_every)
    t0 = time.perf_counter()
    ratios = []
    for k in range(n):
        rounds = min(cfg.train.checkpoint_every, cfg.train.rounds - k * cfg.train.checkpoint_every)
        res, ratio = evaluate_tank_policy(policy, "1v1", OPPONENT, rounds=rounds, seed=cfg.train.seed + k,
                                          cpu_constant_ms=TANK_CPU_CONSTANT_MS, one_cpu=True)  # as training
        ratios.append(ratio)
    wall = time.perf_counter() - t0
    return {"mode": "exported", "repeat": rep, "wall_s": wall, "battles_s": wall - n * export_s,
            "export_s": export_s, "update_s": None, "outside_s": None, "turns": None, "decisions": None,
            "skipped_turns": res.skipped_turns, "score_ratio": statistics.mean(ratios), "load": os.getloadavg()[0],
            "rollout_s": None}


COLUMNS = (("wall s", "wall_s", 1), ("in battles s", "battles_s", 1), ("logs to rollout s", "rollout_s", 2),
           ("updates s", "update_s", 2),
           ("outside s", "outside_s", 1), ("export s", "export_s", 2), ("turns", "turns", 0),
           ("decisions", "decisions", 0), ("skipped", "skipped_turns", 0), ("score ratio", "score_ratio", 3),
           ("load", "load", 1), ("x exported", "ratio", 2), ("x exported battles", "ratio_battles", 2))


def _cell(v: Any, digits: int) -> str:
    if v is None:
        return "-"
    return f"{round(v):,}".replace(",", " ") if digits == 0 else f"{v:.{digits}f}"


def print_table(records: list[dict[str, Any]]) -> None:
    print("\n| run | rep | " + " | ".join(c[0] for c in COLUMNS) + " |")
    print("|---|---:|" + "---:|" * len(COLUMNS))
    for r in records:
        print(f"| {r['mode']} | {r['repeat']} | " + " | ".join(_cell(r.get(k), d) for _, k, d in COLUMNS) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=100)
    ap.add_argument("--battle-rounds", type=int, default=20, help="train.checkpoint_every: rounds per battle")
    ap.add_argument("--config", default="tanks-engine")
    ap.add_argument("--init", type=Path, default=None, help="train.init: a PPO run to start from")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--warmup-rounds", type=int, default=2)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    overrides = [f"league.opponents=['1v1:{OPPONENT}']", f"train.rounds={args.rounds}",
                 f"train.checkpoint_every={args.battle_rounds}", f"train.session_rounds={args.battle_rounds}",
                 *([f"train.init={json.dumps(str(args.init.resolve()))}"] if args.init else []), *args.set]
    cfg = load_experiment(args.config, overrides)
    load0 = os.getloadavg()
    print(f"{' '.join(overrides)}; {args.repeats} repetitions; load average {load0[0]:.1f}", flush=True)
    records: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="confront-bench-") as tmpdir:
        tmp = Path(tmpdir)
        if args.warmup_rounds > 0:
            n = args.warmup_rounds
            warm = load_experiment(args.config, [*overrides, f"train.rounds={n}", f"train.session_rounds={n}",
                                                 f"train.checkpoint_every={n}"])
            train_once(warm, tmp / "warmup", -1)
            exported_once(warm, tmp / "warmup", -1, tmp)
        last: Path | None = None
        for rep in range(args.repeats):
            pair: dict[str, dict[str, Any]] = {}
            for mode in (("train", "exported") if rep % 2 == 0 else ("exported", "train")):
                if mode == "train":
                    last = tmp / f"train-{rep}"
                    rec = train_once(cfg, last, rep)
                else:
                    assert last is not None
                    rec = exported_once(cfg, last, rep, tmp)
                pair[mode] = rec
                records.append(rec)
                print(f"rep {rep} {mode}: wall {rec['wall_s']:.1f} s, load {rec['load']:.1f}", flush=True)
            pair["train"]["ratio"] = pair["train"]["wall_s"] / pair["exported"]["wall_s"]
            pair["train"]["ratio_battles"] = pair["train"]["wall_s"] / pair["exported"]["battles_s"]
    print_table(records)

    def med(mode: str, key: str) -> float:
        return statistics.median(r[key] for r in records if r["mode"] == mode)

    result = {"benchmark": "engine_ppo_training", "rounds": args.rounds, "battle_rounds": args.battle_rounds,
              "init": str(args.init) if args.init else None, "repeats": args.repeats,
              "median_ratio": med("train", "ratio"), "median_ratio_battles": med("train", "ratio_battles"),
              "train_wall_s": med("train", "wall_s"), "train_battles_s": med("train", "battles_s"),
              "train_rollout_s": med("train", "rollout_s"),
              "train_update_s": med("train", "update_s"), "train_outside_s": med("train", "outside_s"),
              "exported_wall_s": med("exported", "wall_s"), "exported_battles_s": med("exported", "battles_s"),
              "export_s": med("exported", "export_s"), "load_average_start": list(load0),
              "load_average_end": list(os.getloadavg())}
    if args.json is not None:
        args.json.write_text(json.dumps({"result": result, "records": records}, indent=1) + "\n")
    print(json.dumps(result))


if __name__ == "__main__":
    main()
