"""Training a config's learner live in the real engine (``confront train --engine robocode``): the
:class:`EngineTrainer` of the one training loop (``loop.run_trainer``), one battle per step.

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
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from confront import checkpoint as ck
from confront.arena.observe import ObservationConfig
from confront.checkpoint import CheckpointError
from confront.config import ConfigError
from confront.engine.battle import SCENARIO_SIZES, BattleSpec, robot_class, scenario_battle, single_star
from confront.engine.bridge import Action, Observation, TurnEnergy
from confront.engine.bridged import BRIDGE_BOT, BRIDGE_CPU_CONSTANT_MS, BridgedRun, run_bridged_battle
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.install import find_engine
from confront.engine.learner_policy import LearnerPolicy
from confront.engine.runner import EngineOptions
from confront.runs import Run
from confront.train.engine_logs import round_rows
from confront.train.league import td_team
from confront.train.paper_model import build_learner, save_model, with_transfer
from confront.train.spec import ExperimentConfig

__all__ = ["EngineTrainer", "POLICY_BOT"]

POLICY_BOT = "confront.PolicyBot*"
N_MOVES = 4  # the paper's four macro moves; the engine's robots know no fire-power actions


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


class _Progress:
    """Bridge policy wrapper that reports rounds as they start (``done`` rounds before this battle) to ``tick``."""

    def __init__(self, policy: LearnerPolicy, tick: Any, done: int) -> None:
        self.policy, self.tick, self.done, self.seen = policy, tick, done, 0

    def __call__(self, obs: Observation) -> Action:
        if self.tick is not None and obs.round > self.seen:
            self.seen = obs.round
            self.tick(self.done + obs.round)
        return self.policy(obs)

    def end_episode(self, robot: str, round_: int, history: Sequence[TurnEnergy] = ()) -> None:
        self.policy.end_episode(robot, round_, history)


def _battle(cfg: ExperimentConfig, opponent: str, rounds: int) -> BattleSpec:
    spec = scenario_battle(cfg.arena.scenario, BRIDGE_BOT.rstrip("*"), opponent, rounds=rounds)
    return single_star(single_star(spec, BRIDGE_BOT), POLICY_BOT)


class EngineTrainer:
    """The paper's learners live in Robocode: each ``advance`` plays one battle of ``train.checkpoint_every``
    rounds (engine seed ``train.seed + battle``) with the learner deciding for our BridgeBots."""

    engine = "robocode"
    bar_scalars: dict[str, str] = {}
    final_window = 100

    def __init__(self, cfg: ExperimentConfig, run: Run, progress: bool = False,
                 cpu_constant_ms: float | None = None) -> None:
        _check(cfg)
        find_engine()  # no engine: a one-line error
        self.cfg, self.run = cfg, run
        self.cpu_constant_ms = BRIDGE_CPU_CONSTANT_MS if cpu_constant_ms is None else cpu_constant_ms
        self.obs_cfg = ObservationConfig(target=cfg.arena.target)
        self.learner = build_learner(cfg, self.obs_cfg.n_features, N_MOVES)
        self.acting, self.info = with_transfer(cfg, self.learner)
        self.policy = LearnerPolicy(self.acting, np.random.default_rng([cfg.train.seed, 0]), train=True,
                                    explore=True, observation=self.obs_cfg, step_turns=cfg.arena.decision_turns)
        self.rows: list[dict[str, Any]] = []
        self.battles, self.skipped_turns, self.rtt_sum_us, self.rtt_battles, self.engine_setup_s = 0, 0, 0.0, 0, 0.0
        self.failures: list[str] = []
        self.errors: list[str] = []
        self._tmp = tempfile.TemporaryDirectory(prefix="confront-train-")
        try:
            self.opponent, self.extra, opp_info = _opponent(cfg, self.obs_cfg, Path(self._tmp.name) / "robots",
                                                            progress)
        except Exception:
            self._tmp.cleanup()
            raise
        self.info.update(opp_info)
        self.desc = f"{cfg.name} {cfg.arena.scenario} (robocode)"

    @classmethod
    def from_config(cls, cfg: ExperimentConfig, run: Run, progress: bool = False,
                    cpu_constant_ms: float | None = None) -> EngineTrainer:
        """``cfg``'s trainer (``factory.make_trainer``)."""
        return EngineTrainer(cfg, run, progress=progress, cpu_constant_ms=cpu_constant_ms)

    @property
    def rounds_done(self) -> int:
        return len(self.rows)

    @property
    def decisions(self) -> int:
        return self.policy.decisions

    def advance(self, limit: int, tick: Any = None) -> dict[str, float]:
        """One battle of up to ``train.checkpoint_every`` rounds; its engine results go to engine/battle-NNN/."""
        done = self.rounds_done
        rounds = min(self.cfg.train.checkpoint_every, limit - done)
        # a training battle gets time: 10 s per round on top of the default limit
        opts = EngineOptions(seed=self.cfg.train.seed + self.battles, cpu_constant_ms=self.cpu_constant_ms,
                             one_cpu=True)
        opts = replace(opts, timeout_s=opts.timeout_s + 10.0 * rounds)
        res: BridgedRun = run_bridged_battle(_battle(self.cfg, self.opponent, rounds),
                                             _Progress(self.policy, tick, done), opts, extra_robots=self.extra,
                                             **self.policy.bridge_kwargs())
        self.policy.end_all()  # rounds restart at 0 in the next battle
        rows = round_rows(res.run.summary["round_scores"])
        for r in rows:
            r["battle"], r["round"] = self.battles, r["round"] + done
        folder = self.run.path / "engine" / f"battle-{self.battles:03d}"
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "results.txt").write_text(res.run.results_text)  # the engine's own results file
        (folder / "results.csv").write_text(res.run.results.to_csv())
        self.rows += rows
        self.battles += 1
        self.skipped_turns += sum(res.run.skipped_turns.values())
        self.failures += list(res.failures)
        self.errors += list(res.server_errors)
        if not np.isnan(res.rtt_mean_us):
            self.rtt_sum_us += res.rtt_mean_us
            self.rtt_battles += 1
        self.engine_setup_s += res.run.setup_s
        return {"skipped_turns": float(self.skipped_turns), "updates": float(self.policy.updates),
                **({"rtt_mean_us": res.rtt_mean_us} if not np.isnan(res.rtt_mean_us) else {})}

    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays = {f"learner.{k}": v for k, v in self.acting.state_dict().items()}
        meta = {"rounds_done": self.rounds_done, "rows": self.rows, "battles": self.battles,
                "skipped_turns": self.skipped_turns, "bridge_failures": self.failures, "bridge_errors": self.errors,
                "rtt_sum_us": self.rtt_sum_us, "rtt_battles": self.rtt_battles, "setup_s": self.engine_setup_s,
                "rng": ck.rng_state(self.policy.rng), "decisions": self.policy.decisions,
                "updates": self.policy.updates, "lost_end_lines": self.policy.lost_ends}
        return arrays, meta

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        try:
            self.acting.load_state_dict({k[len("learner."):]: v for k, v in arrays.items()
                                         if k.startswith("learner.")})
            self.policy.rng = ck.rng_from_state(meta["rng"])
            self.policy.decisions, self.policy.updates = int(meta["decisions"]), int(meta["updates"])
            self.policy.lost_ends = int(meta.get("lost_end_lines", 0))  # not in checkpoints before 2026-12-04
            self.rows, self.battles = list(meta["rows"]), int(meta["battles"])
            self.skipped_turns, self.rtt_battles = int(meta["skipped_turns"]), int(meta["rtt_battles"])
            self.failures, self.errors = list(meta["bridge_failures"]), list(meta["bridge_errors"])
            self.rtt_sum_us, self.engine_setup_s = float(meta["rtt_sum_us"]), float(meta["setup_s"])
        except (KeyError, ValueError, TypeError) as exc:
            raise CheckpointError(f"the checkpoint does not fit this run's config: {exc}") from None

    def finish(self, run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]]) -> dict[str, Any]:
        """The model and figures; the summary keys (train_run's plus the engine's skipped turns, bridge
        failures and errors, round trips, the engine's own setup time, and the SMDP steps closed without the
        robot's end line)."""
        from confront.plots import session_plots

        cfg = self.cfg
        save_model(run.path / "model", self.learner,
                   {"scenario": cfg.arena.scenario, "decision_turns": cfg.arena.decision_turns,
                    "fire_power_actions": False, "target": cfg.arena.target, "engine": "robocode"})
        figures = session_plots(run.plots, sessions, cfg.name, cfg.train.session_rounds)
        return {"scenario": cfg.arena.scenario, "learner": self.acting.diagnostics(),
                "figures": [str(f) for f in figures], "replay": None, "n_actions": N_MOVES,
                "n_features": self.obs_cfg.n_features, **self.info, "battles": self.battles,
                "cpu_constant_ms": self.cpu_constant_ms, "updates": self.policy.updates,
                "skipped_turns": self.skipped_turns, "bridge_failures": self.failures, "bridge_errors": self.errors,
                "rtt_mean_us": self.rtt_sum_us / self.rtt_battles if self.rtt_battles else None,
                "engine_setup_s": self.engine_setup_s, "lost_end_lines": self.policy.lost_ends}

    def close(self) -> None:
        self._tmp.cleanup()
