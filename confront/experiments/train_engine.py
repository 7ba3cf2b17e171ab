"""Training a config's learner live in the real engine (``confront train --engine robocode``).

Our side is a team of BridgeBots sharing one learner through the bridge (parameter sharing; ``LearnerPolicy``:
a round trip only every ``arena.decision_turns`` turns, the gun/radar controller in Java, the Eq. 35 rewards from
the robots' per-turn energy history), the opponents are sample robots or the frozen TD team exported as
PolicyBots. The run folder is the simulator's: config.toml, metrics/rounds.csv (same columns),
metrics/sessions.csv, model/, plots/, summary.json (same keys, plus the engine's skipped turns and bridge
failures), and engine/battle-NNN/results.txt and results.csv (the engine's results for each battle). Per-round
score parts come from the runner's ``round_scores`` (each robot's battle totals at each round's end, differenced).
Curriculum transfer wraps the learner in ``TransferPolicy`` (Eq. 34) as the simulator does. The TD team plays
its frozen table (``opponent.learning`` is ignored).

Checkpoints: the rounds are played as a sequence of battles of ``train.checkpoint_every`` rounds (battle k has
engine seed ``train.seed + k``); after each battle the learner, the policy's RNG, counters and the rows so far
are checkpointed, so ``confront train --resume RUN --engine robocode`` continues after a kill at the next battle.
The engine's robot threads make a battle's course depend on timing, so a resumed engine run is not identical to
an uninterrupted one (the simulator's runs are); it loses at most the battle that was running.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from confront import checkpoint as ck
from confront.arena.observe import ObservationConfig
from confront.arena.state import SCORE_PARTS
from confront.checkpoint import CheckpointError
from confront.config import ConfigError
from confront.engine.battle import SCENARIO_SIZES, BattleSpec, robot_class, scenario_battle
from confront.engine.bridge import Action, Observation, TurnEnergy
from confront.engine.bridged import BRIDGE_BOT, BRIDGE_CPU_CONSTANT_MS, BridgedRun, run_bridged_battle
from confront.engine.evaluate import _single_star
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.install import find_engine
from confront.engine.learner_policy import LearnerPolicy
from confront.engine.runner import EngineOptions
from confront.experiments.spec import ExperimentConfig
from confront.experiments.train import (
    _plots,
    build_learner,
    load_model,
    new_run,
    resume_run,
    save_model,
    session_rows,
    td_team,
)
from confront.learning.base import Learner
from confront.learning.transfer import TransferParams, TransferPolicy
from confront.runs import Run

__all__ = ["train_in_engine", "round_rows", "ENGINE_PARTS", "POLICY_BOT"]

# simulator score part -> the engine's score snapshot key [Robocode RobotStatistics; ram_dmg already x2]
ENGINE_PARTS: dict[str, str] = {
    "survival": "survival", "last_survivor": "surv_bonus", "bullet_damage": "bullet_dmg",
    "bullet_kill_bonus": "bullet_bonus", "ram_damage": "ram_dmg", "ram_kill_bonus": "ram_bonus",
}
POLICY_BOT = "confront.PolicyBot*"
N_MOVES = 4  # the paper's four macro moves; the engine's robots know no fire-power actions


def round_rows(round_scores: list[dict[str, Any]], ours: int = 0) -> list[dict[str, Any]]:
    """Rows of ``metrics/rounds.csv`` (the simulator's columns) from the runner's per-round scores.

    Each entry holds every robot's battle totals at the end of a round; a round's parts are the differences
    to the previous round's totals, so they add up to the engine's results. ``ours`` is our contestant index;
    every other contestant is theirs. A round is decided when at most one contestant has a robot alive.
    """
    rows: list[dict[str, Any]] = []
    before: list[dict[str, float]] | None = None
    for i, rnd in enumerate(round_scores):
        robots = rnd["robots"]
        if before is not None and len(before) != len(robots):
            raise ValueError(f"round {rnd.get('round')} has {len(robots)} robots, the round before {len(before)}")
        prev = before or [{k: 0.0 for k in ENGINE_PARTS.values()} for _ in robots]
        # this round's part = battle total now - battle total after the previous round
        delta = [{k: float(r["score"][k]) - p[k] for k in ENGINE_PARTS.values()}
                 for r, p in zip(robots, prev, strict=True)]
        before = [{k: float(r["score"][k]) for k in ENGINE_PARTS.values()} for r in robots]
        mine = [j for j, r in enumerate(robots) if r["contestant"] == ours]
        other = [j for j, r in enumerate(robots) if r["contestant"] != ours]
        if not mine or not other:
            raise ValueError(f"round {rnd.get('round')} has no robots of contestant {ours} or no opponents")
        alive_o = sum(bool(robots[j]["alive"]) for j in mine)
        alive_t = sum(bool(robots[j]["alive"]) for j in other)
        decided = len({r["contestant"] for r in robots if r["alive"]}) <= 1
        parts_o = {p: sum(delta[j][k] for j in mine) for p, k in ENGINE_PARTS.items()}
        parts_t = {p: sum(delta[j][k] for j in other) for p, k in ENGINE_PARTS.items()}
        total_o, total_t = sum(parts_o.values()), sum(parts_t.values())
        row: dict[str, Any] = {"battle": 0, "turns": int(rnd["turns"]), "decided": decided,
                               "score_ours": total_o, "score_theirs": total_t,
                               "score_ratio": total_o / (total_o + total_t) if total_o + total_t > 0 else 0.5,
                               # defensive score: survival + last-survivor bonus, as the simulator's rows
                               "defensive_ours": parts_o["survival"] + parts_o["last_survivor"],
                               "defensive_theirs": parts_t["survival"] + parts_t["last_survivor"],
                               "won": decided and alive_o > 0, "alive_ours": alive_o, "alive_theirs": alive_t}
        for p in SCORE_PARTS:
            row[f"{p}_ours"] = parts_o[p]
            row[f"{p}_theirs"] = parts_t[p]
        row["round"] = i + 1
        rows.append(row)
    return rows


def _opponent(cfg: ExperimentConfig, obs_cfg: ObservationConfig, robots: Path,
              progress: bool) -> tuple[str, list[Path], dict[str, Any]]:
    """The opponents' robot name, extra robot folders and summary info ('td': the TD team as PolicyBots)."""
    kind = cfg.opponent.kind
    if kind != "td":
        return robot_class(kind), [], {}
    td, where = td_team(cfg, N_MOVES, progress=progress)
    policy = ExportedPolicy.from_learner(td, observation=obs_cfg, step_turns=cfg.arena.decision_turns)
    folder = export_robot(policy, robots)
    info: dict[str, Any] = {"td_model": str(where)}
    if cfg.opponent.learning:
        info["td_learning_ignored"] = True  # the exported TD team plays its frozen table
    return POLICY_BOT.rstrip("*"), [folder], info


def _check(cfg: ExperimentConfig) -> None:
    if cfg.arena.scenario not in SCENARIO_SIZES:
        raise ConfigError(f"arena.scenario = {cfg.arena.scenario!r}: the engine plays {sorted(SCENARIO_SIZES)}")
    if cfg.arena.sensing != "scanned":
        raise ConfigError("arena.sensing = 'true' is not possible in the engine (robots know what they scanned)")
    if cfg.arena.fire_power_actions:
        raise ConfigError("arena.fire_power_actions = true is not supported in the engine (4 moves only)")
    if cfg.opponent.kind != "td":
        try:
            robot_class(cfg.opponent.kind)
        except ValueError as exc:
            raise ConfigError(f"opponent.kind: {exc}") from None


def _transfer(cfg: ExperimentConfig, learner: Learner) -> tuple[Learner, dict[str, Any]]:
    """Curriculum transfer as in the simulator: the learner wrapped to act from the source with Eq. 34's eps."""
    tc = cfg.transfer
    if not tc.source:
        return learner, {}
    source, _ = load_model(tc.source)
    if (source.n_actions, source.observation) != (learner.n_actions, learner.observation):
        raise CheckpointError(
            f"transfer.source {tc.source} has {source.n_actions} actions on {source.observation} observations; "
            f"this task needs {learner.n_actions} on {learner.observation} (Eq. 33)")
    if tc.init_from_source:
        learner.load_state_dict(source.state_dict())
    wrapped = TransferPolicy(learner, source, TransferParams(tc.epsilon0, tc.decay, 0, tc.floor))
    return wrapped, {"transfer_source": tc.source}


class _Progress:
    """Bridge policy wrapper that advances a progress bar as rounds end (``done`` rounds before this battle)."""

    def __init__(self, policy: LearnerPolicy, bar: Any, done: int) -> None:
        self.policy, self.bar, self.done = policy, bar, done

    def __call__(self, obs: Observation) -> Action:
        if self.done + obs.round > self.bar.n:
            self.bar.update(self.done + obs.round - self.bar.n)
        return self.policy(obs)

    def end_episode(self, robot: str, round_: int, history: Sequence[TurnEnergy] = ()) -> None:
        self.policy.end_episode(robot, round_, history)


def _battle(cfg: ExperimentConfig, opponent: str, rounds: int) -> BattleSpec:
    spec = scenario_battle(cfg.arena.scenario, BRIDGE_BOT.rstrip("*"), opponent, rounds=rounds)
    return _single_star(_single_star(spec, BRIDGE_BOT), POLICY_BOT)


def _checkpoint(run: Run, learner: Learner, policy: LearnerPolicy, state: dict[str, Any]) -> None:
    arrays = {f"learner.{k}": v for k, v in learner.state_dict().items()}
    meta = {**state, "engine": "robocode", "rng": ck.rng_state(policy.rng), "decisions": policy.decisions,
            "updates": policy.updates}
    ck.save(run.checkpoints, f"round-{state['rounds_done']:06d}", arrays, meta)


def _restore(run: Run, learner: Learner, policy: LearnerPolicy) -> dict[str, Any]:
    latest = ck.latest(run.checkpoints)
    if latest is None:
        return {}
    arrays, meta = ck.load(latest)
    if meta.get("engine") != "robocode":
        raise CheckpointError(f"{latest} is a simulator checkpoint: resume it without --engine robocode")
    try:
        learner.load_state_dict({k[len("learner."):]: v for k, v in arrays.items() if k.startswith("learner.")})
        policy.rng = ck.rng_from_state(meta["rng"])
        policy.decisions, policy.updates = int(meta["decisions"]), int(meta["updates"])
        return {k: meta[k] for k in ("rounds_done", "battles", "rows", "skipped_turns", "bridge_failures",
                                     "bridge_errors", "rtt_sum_us", "rtt_battles", "setup_s", "elapsed_s")}
    except (KeyError, ValueError, TypeError) as exc:
        raise CheckpointError(f"checkpoint {latest} does not fit this run's config: {exc}") from None


def train_in_engine(
    cfg: ExperimentConfig | None,
    out: str | Path | None,
    progress: bool = True,
    cpu_constant_ms: float = BRIDGE_CPU_CONSTANT_MS,
    exist_ok: bool = False,
    resume: bool = False,
) -> dict[str, Any]:
    """Train ``cfg``'s learner for ``train.rounds`` rounds in the real engine into the run folder ``out``
    (default ``runs/<name>-<time>``, as the simulator's ``train_run``); ``resume`` continues the run in ``out``
    from its latest checkpoint (``cfg`` is then read from the run folder).

    Returns the summary (train_run's keys plus ``engine``, ``battles``, ``skipped_turns``, ``bridge_failures``,
    ``bridge_errors``, ``updates``, ``rtt_mean_us``, ``cpu_constant_ms``). Bad config values raise ValueError.
    """
    start = time.time()
    if resume:
        run, cfg = resume_run(out)
    elif cfg is None:
        raise ValueError("train_in_engine needs a config unless resuming")
    _check(cfg)
    find_engine()  # no engine: a one-line error before any run folder is made
    obs_cfg = ObservationConfig(target=cfg.arena.target)
    learner = build_learner(cfg, obs_cfg.n_features, N_MOVES)
    acting, transfer_info = _transfer(cfg, learner)
    if not resume:
        run = new_run(cfg, out, exist_ok)
    policy = LearnerPolicy(acting, np.random.default_rng([cfg.train.seed, 0]), train=True, explore=True,
                           observation=obs_cfg, step_turns=cfg.arena.decision_turns)
    state: dict[str, Any] = {"rounds_done": 0, "battles": 0, "rows": [], "skipped_turns": 0, "bridge_failures": [],
                             "bridge_errors": [], "rtt_sum_us": 0.0, "rtt_battles": 0, "setup_s": 0.0,
                             "elapsed_s": 0.0}
    if resume:
        state.update(_restore(run, acting, policy))
    elapsed_before = float(state["elapsed_s"])
    total, chunk = cfg.train.rounds, cfg.train.checkpoint_every
    (run.path / "engine").mkdir(exist_ok=True)
    from tqdm import tqdm

    bar = tqdm(total=total, initial=state["rounds_done"], desc=f"{cfg.name} {cfg.arena.scenario} (robocode)",
               unit="round", disable=not progress, dynamic_ncols=True)
    try:
        with tempfile.TemporaryDirectory(prefix="confront-train-") as tmp:
            try:
                opponent, extra, info = _opponent(cfg, obs_cfg, Path(tmp) / "robots", progress)
            except Exception:
                if not resume:
                    run.discard_if_new()  # a failed start leaves no half-made run folder
                raise
            while state["rounds_done"] < total:
                rounds = min(chunk, total - state["rounds_done"])
                # a training battle gets time: 10 s per round on top of the default limit
                opts = EngineOptions(seed=cfg.train.seed + state["battles"], cpu_constant_ms=cpu_constant_ms)
                opts = replace(opts, timeout_s=opts.timeout_s + 10.0 * rounds)
                res: BridgedRun = run_bridged_battle(_battle(cfg, opponent, rounds),
                                                     _Progress(policy, bar, state["rounds_done"]), opts,
                                                     extra_robots=extra, **policy.bridge_kwargs())
                policy.end_all()  # rounds restart at 0 in the next battle
                rows = round_rows(res.run.summary["round_scores"])
                for r in rows:
                    r["battle"], r["round"] = state["battles"], r["round"] + state["rounds_done"]
                folder = run.path / "engine" / f"battle-{state['battles']:03d}"
                folder.mkdir(exist_ok=True)
                (folder / "results.txt").write_text(res.run.results_text)  # the engine's own results file
                (folder / "results.csv").write_text(res.run.results.to_csv())
                state["rows"] += rows
                state["rounds_done"] += rounds
                state["battles"] += 1
                state["skipped_turns"] += sum(res.run.skipped_turns.values())
                state["bridge_failures"] += list(res.failures)
                state["bridge_errors"] += list(res.server_errors)
                if not np.isnan(res.rtt_mean_us):
                    state["rtt_sum_us"] += res.rtt_mean_us
                    state["rtt_battles"] += 1
                state["setup_s"] += res.run.setup_s
                state["elapsed_s"] = elapsed_before + time.time() - start
                bar.update(state["rounds_done"] - bar.n)
                run.write_table("rounds", state["rows"])
                if state["rounds_done"] < total:
                    _checkpoint(run, acting, policy, state)
    finally:
        bar.close()
    rows = state["rows"]
    sessions = session_rows(rows, cfg.train.session_rounds)
    run.write_table("rounds", rows)
    run.write_table("sessions", sessions)
    save_model(run.path / "model", learner,
               {"scenario": cfg.arena.scenario, "decision_turns": cfg.arena.decision_turns,
                "fire_power_actions": False, "target": cfg.arena.target, "engine": "robocode"})
    figures = _plots(run, rows, sessions, cfg)
    tail = rows[-min(100, len(rows)):]
    o, t = sum(r["score_ours"] for r in tail), sum(r["score_theirs"] for r in tail)
    summary: dict[str, Any] = {
        "name": cfg.name, "run": str(run.path), "scenario": cfg.arena.scenario, "rounds": len(rows),
        "sessions": len(sessions), "decisions": policy.decisions,
        "final_score_ratio": o / (o + t) if o + t else 0.5, "final_window_rounds": len(tail),
        "win_rate_last": sum(r["won"] for r in tail) / max(1, len(tail)),
        "score_ours": sum(r["score_ours"] for r in rows), "score_theirs": sum(r["score_theirs"] for r in rows),
        "learner": acting.diagnostics(), "wall_time_s": elapsed_before + time.time() - start,
        "figures": [str(f) for f in figures], "replay": None,
        "n_actions": N_MOVES, "n_features": obs_cfg.n_features, **info, **transfer_info,
        "engine": "robocode", "battles": state["battles"], "cpu_constant_ms": cpu_constant_ms,
        "updates": policy.updates, "skipped_turns": state["skipped_turns"],
        "bridge_failures": state["bridge_failures"], "bridge_errors": state["bridge_errors"],
        "rtt_mean_us": state["rtt_sum_us"] / state["rtt_battles"] if state["rtt_battles"] else None,
        "engine_setup_s": state["setup_s"],
    }
    run.write_summary(summary)
    return summary
