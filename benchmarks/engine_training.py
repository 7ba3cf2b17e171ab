"""Training in the engine against the exported robot on the same battles (issue 11: "Engine training of 100
rounds of 1v1 against SpinBot: wall time within 1.3x of the same battle with the exported robot, the round-start
waits measured and reported").

Two runs, alternated over ``--repeats`` (the order flips each repetition: train first, then export first, ...):
- ``train``: ``train_run(cfg, out, engine="robocode")`` for ``load_experiment(--config, arena.scenario=1v1,
  opponent.kind=SpinBot, learner.kind=ssaq, train.rounds=--rounds)``, i.e. ``confront train -c demo --engine
  robocode --set arena.scenario=1v1 --set opponent.kind=SpinBot --set learner.kind=ssaq --set train.rounds=100``:
  BridgeBot tanks that act from their own copy of the Q table while Python learns, one engine battle per
  ``train.checkpoint_every`` rounds (engine seeds ``train.seed + k``), the checkpoints, tables, model and plots
  of a run folder;
- ``exported``: the last training run's table as the exported PolicyBot (``exported_policy``, ``export_robot``)
  in the same battles (``exported_battle``: the same scenario, opponent, rounds, engine seeds, CPU constant and
  one-CPU setting (``EngineOptions.one_cpu``, on in engine training; ``--stock-engine``: off on both sides) as
  the training's battles, taken from the battles the training played), JVM start included; the export itself
  (writing and compiling the robot once per repetition) is timed apart and left out.

Per run: wall s (the whole ``train_run`` call / the battles), of it inside the battles (``run_bridged_battle`` /
``exported_battle``, JVM start included) and outside them (learner set-up, checkpoint, tables, model, plots), the
engine's own elapsed time and its round set-up time (``EngineRun.setup_s``: from each round's end to the next
round's first turn; a lost round-start wake-up would add min(300 x CPU constant, 10 s) to it, docs/engine.md
"Round-start wait"; the last line says whether any run's set-up could hold one), turns, decisions, the time the
robots were held up per decision (as the robots timed it: sending the observation, and waiting for the
acknowledgements that count for the move, ``RobotActing.wait``), how many decisions went ahead of
acknowledgements that could not change them, the server's time per decision inside the policy (learning) and
its own (parse, updates, send), the learning robots' own time per turn outside ``execute()`` (BridgeBot's energy
record and controller every turn, its decisions with their sends and waits: the engine time the exported robot
does not spend), the CPU seconds of this process and of the engine processes (its waited
children), and x exported = train wall / exported wall of the same repetition.
Before any timing, one untimed training of ``--warmup-rounds`` rounds and its exported robot's battle warm up what
a first run pays once per process (imports of torch's TensorBoard writer and matplotlib, loading the compiled
numba kernels, the Java build check), so every repetition measures the same thing; a fresh ``confront train``
process pays those on top.

Usage: python benchmarks/engine_training.py [--repeats 3] [--rounds 100] [--config demo] [--set KEY=VALUE ...]
       [--cpu-ms 100] [--warmup-rounds 2] [--keep DIR] [--json FILE] [--stock-engine]
Prints a table, the medians, and a last line of JSON (median ratio, load average).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import resource
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

from confront.engine.bridged import BRIDGE_CPU_CONSTANT_MS
from confront.engine.evaluate import exported_battle
from confront.engine.export import export_robot
from confront.engine.runner import EngineOptions
from confront.experiments.evaluate import exported_policy
from confront.train import paper_engine
from confront.train.factory import train_run
from confront.train.paper_model import load_model
from confront.train.spec import ExperimentConfig, load_experiment

ISSUE_SETTINGS = ("arena.scenario=1v1", "opponent.kind=SpinBot", "learner.kind=ssaq")
OPPONENT = "SpinBot"


def _cpu() -> tuple[float, float]:
    """CPU seconds so far of this process (all threads) and of its waited children (the engine processes)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime, kids.ru_utime + kids.ru_stime


@contextlib.contextmanager
def _battles_of_training(one_cpu: bool | None = None) -> Iterator[list[dict[str, Any]]]:
    """Time every battle the engine trainer plays (``run_bridged_battle`` as ``paper_engine`` calls it) and keep
    what it needs to be replayed by the exported robot: rounds, engine seed, CPU constant, one-CPU setting
    (``one_cpu``: None keeps the trainer's, else forced on both sides)."""
    played: list[dict[str, Any]] = []
    original = paper_engine.run_bridged_battle

    def timed(spec, policy, options=None, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
        if one_cpu is not None:
            options = replace(options, one_cpu=one_cpu)
        t0 = time.perf_counter()
        res = original(spec, policy, options, *args, **kwargs)
        played.append({"wall_s": time.perf_counter() - t0, "rounds": spec.rounds, "seed": options.seed,
                       "cpu_constant_ms": options.cpu_constant_ms, "one_cpu": options.one_cpu, "bridged": res})
        return res

    paper_engine.run_bridged_battle = timed
    try:
        yield played
    finally:
        paper_engine.run_bridged_battle = original


def _record(mode: str, rep: int, wall: float, cpu0: tuple[float, float], battles: list[dict[str, Any]],
            extra: dict[str, Any]) -> dict[str, Any]:
    cpu1 = _cpu()
    runs = [b["run"] for b in battles]
    rec = {"mode": mode, "repeat": rep, "wall_s": wall, "battles_s": sum(b["wall_s"] for b in battles),
           "engine_s": sum(r.elapsed_s for r in runs), "setup_s": sum(r.setup_s for r in runs),
           "rounds": sum(b["rounds"] for b in battles), "turns": sum(r.turns for r in runs),
           "skipped_turns": sum(sum(r.skipped_turns.values()) for r in runs),
           "python_cpu_s": cpu1[0] - cpu0[0], "engine_cpu_s": cpu1[1] - cpu0[1],
           "load": os.getloadavg()[0], **extra}
    rec["outside_s"] = rec["wall_s"] - rec["battles_s"]
    rec["setup_ms_per_round"] = 1e3 * rec["setup_s"] / rec["rounds"]
    bridged = [b["bridged"] for b in battles if b.get("bridged") is not None]
    n = sum(br.decisions for br in bridged)
    rec["decisions"] = n if bridged else None

    def per_decision(key: str) -> float | None:
        return sum(getattr(br, key) * br.decisions for br in bridged if br.decisions) / n if n else None

    rec["held_up_us"] = per_decision("rtt_mean_us")
    rec["held_up_s"] = rec["held_up_us"] * n / 1e6 if n else None
    rec["policy_us"], rec["server_us"] = per_decision("policy_us"), per_decision("handling_us")
    timed = [br for br in bridged if math.isfinite(br.work_us_per_turn)]  # per turn, weighted by the battles' turns
    turns = sum(br.run.turns for br in timed)
    rec["work_us"] = sum(br.work_us_per_turn * br.run.turns for br in timed) / turns if turns else None
    rec["behind"] = sum(br.behind for br in bridged) if bridged else None
    rec["ahead"] = sum(getattr(br, "ahead", 0) for br in bridged) if bridged else None
    rec["failures"] = sum(len(br.failures) + len(br.server_errors) for br in bridged) if bridged else None
    return rec


def train_once(cfg: ExperimentConfig, out: Path, rep: int, cpu_ms: float,
               one_cpu: bool | None = None) -> tuple[dict[str, Any], list[dict]]:
    """One training run (``train_run(engine="robocode")``) into ``out``: its record and its battles."""
    with _battles_of_training(one_cpu) as played:
        cpu0 = _cpu()
        t0 = time.perf_counter()
        summary = train_run(cfg, out, progress=False, engine="robocode", cpu_constant_ms=cpu_ms)
        wall = time.perf_counter() - t0
    battles = [{**b, "run": b["bridged"].run} for b in played]
    rec = _record("train", rep, wall, cpu0, battles,
                  {"updates": summary["updates"], "score_ratio": summary["final_score_ratio"], "run": str(out)})
    return rec, played


def exported_once(cfg: ExperimentConfig, run: Path, played: list[dict[str, Any]], rep: int,
                  tmp: Path) -> dict[str, Any]:
    """The trained table of ``run`` as the exported PolicyBot on the battles ``played`` by the training."""
    learner, _ = load_model(run)
    t0 = time.perf_counter()
    robot = export_robot(exported_policy(learner, cfg), tmp / f"robots-{rep}")
    export_s = time.perf_counter() - t0
    battles = []
    cpu0 = _cpu()
    t0 = time.perf_counter()
    for b in played:
        t1 = time.perf_counter()
        res = exported_battle(robot, cfg.arena.scenario, OPPONENT, b["rounds"],
                              EngineOptions(seed=b["seed"], cpu_constant_ms=b["cpu_constant_ms"], one_cpu=b["one_cpu"]))
        battles.append({"wall_s": time.perf_counter() - t1, "rounds": b["rounds"], "run": res})
    wall = time.perf_counter() - t0
    ratio = statistics.mean(r["run"].results.score_ratio(_ours(r["run"])) for r in battles)
    return _record("exported", rep, wall, cpu0, battles, {"export_s": export_s, "score_ratio": ratio,
                                                          "run": str(run)})


def _ours(run: Any) -> str:
    return next(c.name for c in run.results.contestants if c.name.startswith("confront."))


def _cell(v: Any, digits: int = 1) -> str:
    if v is None:
        return "-"
    if digits == 0:
        return f"{round(v):,}".replace(",", " ")
    return f"{v:.{digits}f}"


COLUMNS = (("wall s", "wall_s", 1), ("in battles s", "battles_s", 1), ("outside s", "outside_s", 1),
           ("engine s", "engine_s", 1), ("round set-up s", "setup_s", 2),
           ("set-up ms/round", "setup_ms_per_round", 0), ("turns", "turns", 0),
           ("skipped", "skipped_turns", 0), ("decisions", "decisions", 0), ("held up us/decision", "held_up_us", 0),
           ("held up s", "held_up_s", 1), ("went ahead", "ahead", 0), ("policy us", "policy_us", 0),
           ("server us", "server_us", 0), ("robot work us/turn", "work_us", 1),
           ("Python CPU s", "python_cpu_s", 1), ("engine CPU s", "engine_cpu_s", 1), ("load", "load", 1),
           ("x exported", "ratio", 2))


def print_table(records: list[dict[str, Any]]) -> None:
    print("\n| run | rep | " + " | ".join(c[0] for c in COLUMNS) + " |")
    print("|---|---:|" + "---:|" * len(COLUMNS))
    for r in records:
        print(f"| {r['mode']} | {r['repeat']} | " + " | ".join(_cell(r.get(k), d) for _, k, d in COLUMNS) + " |")
    print("\nmedians:")
    print("| run | " + " | ".join(c[0] for c in COLUMNS) + " |")
    print("|---|" + "---:|" * len(COLUMNS))
    for mode in ("train", "exported"):
        rows = [r for r in records if r["mode"] == mode]
        cells = []
        for _, k, d in COLUMNS:
            vals = [r[k] for r in rows if r.get(k) is not None]
            cells.append(_cell(statistics.median(vals), d) if vals else "-")
        print(f"| {mode} | " + " | ".join(cells) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=100, help="train.rounds")
    ap.add_argument("--config", default="demo", help="the experiment the issue's command names (-c)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="more config overrides")
    ap.add_argument("--cpu-ms", type=float, default=BRIDGE_CPU_CONSTANT_MS, help="engine CPU constant (ms)")
    ap.add_argument("--warmup-rounds", type=int, default=2, help="untimed training and export first (0: none)")
    ap.add_argument("--keep", type=Path, default=None, help="keep the run folders here (default: a temp dir)")
    ap.add_argument("--json", type=Path, default=None, help="write every record here")
    ap.add_argument("--stock-engine", action="store_true",
                    help="engine processes unpinned (EngineOptions.one_cpu off) on both sides, as before")
    args = ap.parse_args()
    one_cpu = False if args.stock_engine else None
    overrides = [*ISSUE_SETTINGS, f"train.rounds={args.rounds}", *args.set]
    cfg = load_experiment(args.config, overrides)
    load0 = os.getloadavg()
    print(f"{args.rounds} rounds, {' '.join(overrides)}, CPU constant {args.cpu_ms:g} ms, "
          f"{'engine unpinned' if args.stock_engine else 'engine on one CPU'}, "
          f"{args.repeats} repetitions; load average {load0[0]:.1f} {load0[1]:.1f} {load0[2]:.1f}", flush=True)
    records: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="confront-bench-") as tmpdir:
        tmp = Path(tmpdir)
        base = args.keep if args.keep is not None else tmp
        base.mkdir(parents=True, exist_ok=True)
        if args.warmup_rounds > 0:
            t0 = time.perf_counter()
            n = args.warmup_rounds
            warm = load_experiment(args.config, [*overrides, f"train.rounds={n}", f"train.session_rounds={n}"])
            _, played = train_once(warm, tmp / "warmup", -1, args.cpu_ms, one_cpu)
            exported_once(warm, tmp / "warmup", played, -1, tmp)
            print(f"warm-up ({args.warmup_rounds} rounds each, not timed below): {time.perf_counter() - t0:.1f} s",
                  flush=True)
        last: tuple[Path, list[dict[str, Any]]] | None = None
        for rep in range(args.repeats):
            pair: dict[str, dict[str, Any]] = {}
            order = ("train", "exported") if rep % 2 == 0 else ("exported", "train")
            for mode in order:
                if mode == "train":
                    out = base / f"train-{rep}"
                    rec, played = train_once(cfg, out, rep, args.cpu_ms, one_cpu)
                    last = (out, played)
                else:
                    assert last is not None  # the first repetition trains first
                    rec = exported_once(cfg, last[0], last[1], rep, tmp)
                pair[mode] = rec
                records.append(rec)
                print(f"rep {rep} {mode}: wall {rec['wall_s']:.1f} s, round set-up {rec['setup_s']:.2f} s, "
                      f"load {rec['load']:.1f}", flush=True)
            pair["train"]["ratio"] = pair["train"]["wall_s"] / pair["exported"]["wall_s"]
            pair["exported"]["ratio"] = 1.0
    print_table(records)
    ratios = [r["ratio"] for r in records if r["mode"] == "train"]
    load1 = os.getloadavg()

    def med(mode: str, key: str) -> float:
        return statistics.median(r[key] for r in records if r["mode"] == mode)

    result = {"benchmark": "engine_training", "rounds": args.rounds, "repeats": args.repeats,
              "median_ratio": statistics.median(ratios), "ratios": ratios,
              "train_wall_s": med("train", "wall_s"), "exported_wall_s": med("exported", "wall_s"),
              "train_setup_s": med("train", "setup_s"), "exported_setup_s": med("exported", "setup_s"),
              "held_up_us": med("train", "held_up_us"), "robot_work_us_per_turn": med("train", "work_us"),
              # a lost round-start wake-up costs min(300 x CPU constant, 10 s) [RobotPeer.startRound]
              "lost_wakeup_s": min(0.3 * args.cpu_ms, 10.0), "max_setup_s": max(r["setup_s"] for r in records),
              "load_average_start": list(load0), "load_average_end": list(load1),
              "load_average_runs": [r["load"] for r in records]}
    if args.json is not None:
        args.json.write_text(json.dumps({"result": result, "records": records}, indent=1) + "\n")
    print(json.dumps(result))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
