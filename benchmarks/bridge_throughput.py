"""Cost of the Python bridge: turns per second of bridged battles against the same battles without Python.

Per battle (1v1 against Walls; 4v4 against Walls, Tracker, SpinBot, RamFire; same seed, rounds and CPU
constant everywhere) four modes, interleaved and repeated (the order rotates each repetition):
- ``sample``: a sample robot (Tracker) in our place: the engine's own speed with sample robots only;
- ``java``: the policy exported to Java (PolicyBot, a random Q table, a move every T turns, the fixed
  gun/radar controller every turn): the same robot behaviour with no Python;
- ``bridge T``: BridgeBots asking the Python twin of that policy in turns 1, 1 + T, ... with the controller
  running in Java in between (``run_bridged_battle(every=T, controller=...)``): the same battle as ``java``
  turn by turn when no turn is skipped (the benchmark checks the turn counts);
- ``bridge T lead``: the same, but each observation leaves ``--lead`` turns before its decision turn, so the
  policy runs while the engine plays on (decisions rest on a state that many turns old: a different battle);
- ``bridge 1``: the Python twin decides every turn, gun and radar included (no controller in Java);
- ``acting T``: the robots play the same Q table themselves (``run_bridged_battle(acting=...)``: their own copy
  of the policy, first maximum as PolicyBot) and send each observation with the move taken; Python takes it in
  (the twin checks the move: ``mismatches``) and acknowledges it, and a robot waits only when ``--acting-lag``
  observations are unacknowledged: again the same battle as ``java``;
- ``learn T`` / ``learn T acting``: a learning SSAQ tank (``LearnerPolicy`` around a fresh ``TabularQ``,
  Boltzmann exploration, each SMDP step learned at once), deciding in Python (one round trip per decision) or
  acting from its own copy of the Q table that every update reaches (``LearnerPolicy.bridge_kwargs()``, waiting
  at ``--max-lag`` unacknowledged observations);
  learning changes the battle, so its turns differ from ``java``'s.
T is the configs' ``arena.decision_turns`` (10). Bridge cost = 1 - bridged turns/s / reference turns/s,
per repetition (neighbouring runs, similar machine load), excluding the round-start wait; the wait is
reported on its own. "excl. policy" also leaves out the time spent inside the Python policy itself (what a
Java policy would cost instead is in the ``java`` row). Goal of issue 5: cost <= 25%.

Usage: python benchmarks/bridge_throughput.py [--rounds 10] [--repeats 3] [--cpu-ms 100] [--lead 5]
       [--max-lag 1] [--acting-lag 8] [--check-rounds 100] [--battles 1v1,4v4] [--modes sample,java,...] [--one-cpu]
       [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from confront.engine.battle import BattleSpec, Team
from confront.engine.bridged import BRIDGE_BOT, BRIDGE_CPU_CONSTANT_MS, BridgedRun, run_bridged_battle
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.learner_policy import LearnerPolicy
from confront.engine.runner import EngineOptions, EngineRun, run_battle
from confront.learning.tabular import TabularQ
from confront.train.spec import ArenaSection

OPPONENTS = ("Walls", "Tracker", "SpinBot", "RamFire")
STAND_IN = "Tracker"  # the sample robot that takes our place in the sample-only battle
MODES = ("sample", "java", "bridge T", "bridge T lead", "bridge 1", "acting T", "learn T", "learn T acting")
BRIDGED = MODES[2:]


def _spec(size: int, ours: str, rounds: int) -> BattleSpec:
    if size == 1:
        return BattleSpec((ours, "Walls"), rounds=rounds)
    return BattleSpec((Team("Ours4", (ours.rstrip("*"),) * size), Team("Them4", OPPONENTS[:size])), rounds=rounds)


def _record(battle: str, mode: str, rep: int, run: EngineRun, wall: float, br: BridgedRun | None) -> dict[str, Any]:
    busy = max(run.elapsed_s - run.setup_s, 1e-9)
    policy_s = br.policy_us * br.decisions / 1e6 if br is not None and br.decisions else 0.0
    return {
        "battle": battle, "mode": mode, "repeat": rep, "turns": run.turns,
        "turns_per_s": run.turns / run.elapsed_s, "turns_per_s_excl_setup": run.turns / busy,
        "turns_per_s_excl_policy": run.turns / max(busy - policy_s, 1e-9),
        "setup_s": run.setup_s, "elapsed_s": run.elapsed_s, "wall_s": wall,
        "skipped_turns": sum(run.skipped_turns.values()),
        "decisions": br.decisions if br else 0, "failures": len(br.failures) if br else 0,
        "rtt_mean_us": br.rtt_mean_us if br else None, "rtt_over_1ms": br.rtt_over_1ms if br else None,
        "policy_us": br.policy_us if br else None, "handling_us": br.handling_us if br else None,
        "work_us_per_turn": br.work_us_per_turn if br else None,
        "mismatches": None, "behind": br.behind if br else None,
    }


class _Checked:
    """The twin as the policy of robots that act themselves: counts the moves it would not have taken."""

    def __init__(self, policy: ExportedPolicy) -> None:
        self.policy, self.mismatches = policy, 0

    def __call__(self, obs):  # noqa: ANN001, ANN204 - a bridge policy
        self.mismatches += self.policy.act(obs) != obs.action
        return self.policy(obs)


def _runner(mode: str, size: int, rounds: int, opts: EngineOptions, policy: ExportedPolicy, exported: Path,
            every: int, lead: int, max_lag: int, acting_lag: int,
            seed: int) -> Callable[[], tuple[EngineRun, BridgedRun | None]]:
    def run() -> tuple[EngineRun, BridgedRun | None]:
        if mode == "sample":
            return run_battle(_spec(size, STAND_IN, rounds), opts), None
        if mode == "java":
            return run_battle(_spec(size, "confront.PolicyBot*", rounds), opts, extra_robots=[exported]), None
        if mode in ("bridge T", "bridge T lead"):
            br = run_bridged_battle(_spec(size, BRIDGE_BOT, rounds), policy, opts, every=every,
                                    controller=policy.control, lead=lead if mode == "bridge T lead" else 0)
        elif mode == "acting T":
            checked = _Checked(policy)
            br = run_bridged_battle(_spec(size, BRIDGE_BOT, rounds), checked, opts, every=every,
                                    controller=policy.control, acting=policy.robot_acting(acting_lag))
            run.mismatches = checked.mismatches  # type: ignore[attr-defined]
        elif mode in ("learn T", "learn T acting"):
            learner = LearnerPolicy(TabularQ(), np.random.default_rng(seed), train=True, step_turns=every,
                                    acting=mode == "learn T acting", max_lag=max_lag)
            br = run_bridged_battle(_spec(size, BRIDGE_BOT, rounds), learner, opts, **learner.bridge_kwargs())
        else:
            br = run_bridged_battle(_spec(size, BRIDGE_BOT, rounds), policy, opts, every=1)
        return br.run, br
    run.mismatches = None  # type: ignore[attr-defined]
    return run


def _fmt(values: list[float], digits: int = 0) -> str:
    """Median and range."""
    med = statistics.median(values)
    if len(values) == 1:
        return f"{med:.{digits}f}"
    return f"{med:.{digits}f} ({min(values):.{digits}f}-{max(values):.{digits}f})"


def _mean(records: list[dict[str, Any]], key: str) -> str:
    vals = [r[key] for r in records if r[key] is not None and not np.isnan(r[key])]
    return _fmt(vals) if vals else "-"


def report(records: list[dict[str, Any]]) -> None:
    """Print per battle and mode the medians (ranges) over the repetitions, then the costs."""
    print("battle | mode | turns | turns/s excl. set-up | turns/s | set-up s | skipped | decisions | "
          "held up by round trip us | over 1 ms | policy us | server us | robot work us/turn")
    for battle in dict.fromkeys(r["battle"] for r in records):
        for mode in MODES:
            rs = [r for r in records if r["battle"] == battle and r["mode"] == mode]
            if not rs:
                continue
            print(f"{battle} | {mode} | {_fmt([r['turns'] for r in rs])} | "
                  f"{_fmt([r['turns_per_s_excl_setup'] for r in rs])} | {_fmt([r['turns_per_s'] for r in rs])} | "
                  f"{_fmt([r['setup_s'] for r in rs], 2)} | {sum(r['skipped_turns'] for r in rs)} | "
                  f"{_fmt([r['decisions'] for r in rs])} | {_mean(rs, 'rtt_mean_us')} | {_mean(rs, 'rtt_over_1ms')} | "
                  f"{_mean(rs, 'policy_us')} | {_mean(rs, 'handling_us')} | {_mean(rs, 'work_us_per_turn')}")
    print("\nbridge cost = 1 - bridged/reference turns/s excl. set-up, per repetition: median (range); goal <= 25%")
    for battle in dict.fromkeys(r["battle"] for r in records):
        for mode in BRIDGED:
            for ref in ("sample", "java"):
                for key, label in (("turns_per_s_excl_setup", ""), ("turns_per_s_excl_policy", ", excl. policy")):
                    costs = []
                    for rep in sorted({r["repeat"] for r in records}):
                        b = [r for r in records if (r["battle"], r["mode"], r["repeat"]) == (battle, mode, rep)]
                        a = [r for r in records if (r["battle"], r["mode"], r["repeat"]) == (battle, ref, rep)]
                        if a and b:
                            costs.append(100 * (1 - b[0][key] / a[0]["turns_per_s_excl_setup"]))
                    if costs:
                        ok = "meets" if statistics.median(costs) <= 25 else "misses"
                        print(f"{battle} {mode} vs {ref}{label}: {_fmt(costs, 1)} % -> {ok} the goal")
    for battle in dict.fromkeys(r["battle"] for r in records):
        same = [(j["turns"], b["turns"]) for j in records for b in records
                if j["battle"] == b["battle"] == battle and j["repeat"] == b["repeat"]
                and (j["mode"], b["mode"]) == ("java", "bridge T")]
        print(f"{battle}: turns java vs bridge T per repetition {same} (equal = the same battle)")
        same = [(j["turns"], b["turns"]) for j in records for b in records
                if j["battle"] == b["battle"] == battle and j["repeat"] == b["repeat"]
                and (j["mode"], b["mode"]) == ("java", "acting T")]
        print(f"{battle}: turns java vs acting T per repetition {same} (equal = the same battle)")


def check_skipped(rounds: int, every: int, opts: EngineOptions, policy: ExportedPolicy) -> dict[str, Any]:
    """A bridged 1v1 evaluation (the twin, a move every T turns, the Java controller) of ``rounds`` rounds."""
    t0 = time.perf_counter()
    br = run_bridged_battle(_spec(1, BRIDGE_BOT, rounds), policy, opts, every=every, controller=policy.control)
    rec = _record("1v1", f"check {rounds} rounds", 0, br.run, time.perf_counter() - t0, br)
    print(f"\n{rounds}-round bridged 1v1 (T={every}, controller in Java, CPU constant {opts.cpu_constant_ms} ms): "
          f"{rec['skipped_turns']} skipped turns, {rec['failures']} fallbacks, {rec['decisions']} decisions, "
          f"mean round trip {rec['rtt_mean_us']:.0f} us ({rec['rtt_over_1ms']} over 1 ms), set-up wait "
          f"{rec['setup_s']:.1f} s of {rec['elapsed_s']:.1f} s, "
          f"{rec['turns_per_s_excl_setup']:.0f} turns/s excl. set-up")
    return rec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cpu-ms", type=float, default=BRIDGE_CPU_CONSTANT_MS, help="engine CPU constant (ms)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--every", type=int, default=ArenaSection().decision_turns, help="T: turns per decision")
    ap.add_argument("--lead", type=int, default=5, help="turns ahead for the 'bridge T lead' mode")
    ap.add_argument("--max-lag", type=int, default=1, help="unacknowledged observations before a learning robot waits")
    ap.add_argument("--acting-lag", type=int, default=8, help="the same for the robots playing the fixed twin")
    ap.add_argument("--battles", default="1v1,4v4")
    ap.add_argument("--modes", default=",".join(MODES))
    ap.add_argument("--check-rounds", type=int, default=0, help="also a bridged 1v1 of this many rounds")
    ap.add_argument("--json", type=Path, help="write the records here")
    ap.add_argument("--one-cpu", action="store_true",
                    help="every engine process (the references too) on one CPU (EngineOptions.one_cpu)")
    args = ap.parse_args()
    modes = [m for m in MODES if m in args.modes.split(",")]
    sizes = {"1v1": 1, "4v4": 4}
    battles = [b for b in args.battles.split(",") if b]
    if unknown := [b for b in battles if b not in sizes]:
        raise ValueError(f"unknown battle {unknown[0]!r}; choose from {sorted(sizes)}")
    opts = EngineOptions(seed=args.seed, cpu_constant_ms=args.cpu_ms, one_cpu=args.one_cpu)
    policy = ExportedPolicy("qtable", q=np.random.default_rng(args.seed).normal(size=(320, 4)),
                            step_turns=args.every)
    print(f"rounds={args.rounds} repeats={args.repeats} cpu_constant_ms={args.cpu_ms} seed={args.seed} "
          f"one_cpu={args.one_cpu} "
          f"T={args.every} lead={args.lead} load average at start {os.getloadavg()[0]:.1f}", flush=True)
    records = []
    with tempfile.TemporaryDirectory(prefix="confront-bench-") as tmp:
        exported = export_robot(policy, Path(tmp) / "robots")
        for rep in range(args.repeats):
            order = modes[rep % len(modes):] + modes[:rep % len(modes)]
            for battle in battles:
                for mode in order:
                    t0 = time.perf_counter()
                    runner = _runner(mode, sizes[battle], args.rounds, opts, policy, exported, args.every,
                                     args.lead, args.max_lag, args.acting_lag, args.seed + rep)
                    run, br = runner()
                    rec = _record(battle, mode, rep, run, time.perf_counter() - t0, br)
                    rec["mismatches"] = runner.mismatches  # type: ignore[attr-defined]
                    records.append(rec)
                    print(f"  [{rep}] {battle} {mode}: {rec['turns']} turns, {rec['turns_per_s_excl_setup']:.0f} "
                          f"turns/s excl. set-up ({rec['setup_s']:.2f} s set-up), "
                          f"held up {rec['rtt_mean_us'] or 0:.0f} us/decision, "
                          f"{rec['skipped_turns']} skipped, mismatches {rec['mismatches']}, behind {rec['behind']}, "
                          f"load {os.getloadavg()[0]:.1f}", flush=True)
        report(records)
        if args.check_rounds:
            records.append(check_skipped(args.check_rounds, args.every, opts, policy))
    print(f"load average at end {os.getloadavg()[0]:.1f}")
    if args.json:
        args.json.write_text(json.dumps(records, indent=1))


if __name__ == "__main__":
    main()
