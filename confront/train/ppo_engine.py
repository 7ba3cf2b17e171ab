"""PPO tanks trained in the real engine (``confront train -c <ppo config> --engine robocode``): the
:class:`EngineTankTrainer` of the one training loop (``loop.run_trainer``), one battle per step, one PPO update
per battle (on-policy: the battle is the rollout).

    PPO actor -> TankPolicy (play sampled) -> policy file -> one engine battle of train.checkpoint_every rounds
    (our TankBots read the file: -Dconfront.tank.model; each logs its decisions, view and joint action:
    -Dconfront.tank.log; the runner logs every robot's current-round score per turn: -Dconfront.scores)
    -> per robot and round one episode of decisions, rewards = change of our team's score minus theirs over each
    decision's turns (x ppo.reward_scale) -> Rollout (S decisions x N episodes, ``active`` masks)
    -> log-probs and values recomputed by the PPO that acted -> PPO.update (GAE, clipped surrogate)

No Python runs during a battle: the robots play at the exported robot's speed, drawing each action head from the
policy's softmax with Robocode's seeded random (``TankModel.sample``). The log-probabilities are recomputed in
float32 torch from the logged views (Java samples from float64 logits of the float32-rounded view; the two differ
by float32 rounding, ~1e-6 in a log-probability). Battle k plays ``league.opponents[k mod len]`` (scripted
sample robots, or the paper-move opponents td / random / dodge as exported PolicyBots, as ``tank_report --engine``
plays them) with engine seed ``train.seed + k``. ``train.init`` starts the learner from another PPO run's
``model/ppo.npz`` (e.g. a simulator run: fine-tuning in the real engine).

Differences to the simulator's reward (``tank.reward = "score"``): a round is cut at the engine's deciding turn
(decisions after it are dropped, the one spanning it ends there), as the simulator ends the round there; the
engine's 150 turns after the decision are not learned from. A decision turn a robot skipped is made up a turn
later (the step is a turn longer, the one before it shorter). The team critic's mean view is taken over the
team-mates that decided in the same turn (the simulator includes dead tanks with weight 1e-6). The rewards follow
the robots' current-round scores (as the simulator's), which in team battles grow after a robot's death by its
bullets in flight; the rows (``round_rows``: the engine's totals, closed at each robot's death) do not count them.

Run folder: the simulator's (config.toml, metrics/rounds.csv with EngineTrainer's columns plus ``opponent``,
``decisions`` and ``wall_s``, metrics/sessions.csv, metrics/updates.csv, model/ as ``ppo_model.save_tank_model`` writes
it, plots/, summary.json) and engine/battle-NNN/results.txt and results.csv. Checkpoints after every battle
(the PPO's state, rows, counters; data only), so ``--resume`` continues after a kill at the next battle.
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from confront import checkpoint as ck
from confront.arena.control import ControlConfig
from confront.arena.scenarios import SAMPLE_TEAMS
from confront.arena.tank import FEATURE_NAMES
from confront.config import ConfigError
from confront.engine.battle import SCENARIO_SIZES, BattleSpec, scenario_battle, single_star
from confront.engine.export import export_robot
from confront.engine.install import find_engine
from confront.engine.runner import EngineOptions, EngineRun, run_battle
from confront.engine.tank_export import TANK_CPU_CONSTANT_MS, TANK_ROBOT, TankPolicy, export_tank_robot
from confront.learning.ppo import PPO, UPDATE_STATS, Rollout
from confront.runs import Run
from confront.train.engine_logs import Decision, ScoreLog, read_decisions, read_scores, round_rows
from confront.train.league import PAPER_MOVE_OPPONENTS, paper_move_robot
from confront.train.loop import share_by_opponent
from confront.train.ppo_model import load_tank_model, save_tank_model, skill_logits, tank_space
from confront.train.spec import SCRIPTED_BOTS, TECH_BOTS, ExperimentConfig

__all__ = ["EngineTankTrainer", "episode_rewards", "pack_episodes", "engine_entries"]

POLICY_BOT = "confront.PolicyBot"


def episode_rewards(turns: Sequence[int], margin: Any, end: int, alive_at_end: bool, step_turns: int
                    ) -> np.ndarray:
    """Score-margin rewards of one robot's decisions in one round (unscaled, score points): decision i, made
    at turn ``turns[i]`` (ascending), earns ``margin(e_i) - margin(turns[i])`` with e_i the next decision's
    turn; the last one's window ends at ``end`` (the round's deciding turn) if the robot is alive then, else
    ``step_turns`` later (its step runs on after its death, as in the simulator) or at ``end`` if sooner.
    Decisions at or after ``end`` are dropped: the result has one reward per decision before ``end``."""
    kept = [t for t in turns if t < end]
    out = np.zeros(len(kept))
    for i, t in enumerate(kept):
        if i + 1 < len(kept):
            stop = kept[i + 1]
        elif alive_at_end or (i + 1 < len(turns)):  # alive, or it decided again (after the end)
            stop = end
        else:
            stop = min(t + step_turns, end)
        out[i] = margin(stop) - margin(t)
    return out


def pack_episodes(lengths: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Episodes of ``lengths`` decisions as the columns of (S, N) arrays, S the longest: the flat index (S, N)
    of each cell (-1 padding), ``active`` (S, N) and ``done`` (S, N) (each episode's last decision)."""
    n, s = len(lengths), max(lengths, default=0)
    index = np.full((s, n), -1, dtype=np.int64)
    done = np.zeros((s, n), dtype=bool)
    start = 0
    for j, m in enumerate(lengths):
        index[:m, j] = np.arange(start, start + m)
        if m:
            done[m - 1, j] = True
        start += m
    return index, index >= 0, done


# -- opponents --------------------------------------------------------------------------------------------------

def engine_entries(cfg: ExperimentConfig) -> tuple[str, ...]:
    """``league.opponents`` if every entry can be played in the engine, else a ConfigError naming the first that
    cannot (self-play snapshots and the strafer exist only in the simulator)."""
    for e in cfg.league.opponents:
        scen, _, opp = e.partition(":")
        if scen not in SCENARIO_SIZES:
            raise ConfigError(f"league.opponents entry {e!r}: the engine plays the scenarios "
                              f"{', '.join(sorted(SCENARIO_SIZES))}")
        if opp not in (*SCRIPTED_BOTS, *TECH_BOTS, *SAMPLE_TEAMS, *PAPER_MOVE_OPPONENTS):
            raise ConfigError(f"league.opponents entry {e!r} cannot be played in the engine: use a sample robot "
                              f"({', '.join(SCRIPTED_BOTS)}), a technique robot ({', '.join(TECH_BOTS)}), a sample "
                              f"team ({', '.join(SAMPLE_TEAMS)}) or a paper-move opponent "
                              f"({', '.join(PAPER_MOVE_OPPONENTS)}); {opp!r} exists only in the simulator")
    return tuple(cfg.league.opponents)


def _battle(entry: str, rounds: int) -> BattleSpec:
    scen, _, opp = entry.partition(":")
    spec = scenario_battle(scen, TANK_ROBOT, POLICY_BOT if opp in PAPER_MOVE_OPPONENTS else opp, rounds=rounds)
    return single_star(spec, POLICY_BOT + "*")


# -- the trainer ------------------------------------------------------------------------------------------------

class EngineTankTrainer:
    """PPO tanks in Robocode: each ``advance`` plays one battle of ``train.checkpoint_every`` rounds with the
    current policy (sampled, in Java), then learns from it with one PPO update."""

    engine = "robocode"
    bar_scalars = {"entropy": "H"}
    final_window = 200

    def __init__(self, cfg: ExperimentConfig, run: Run, progress: bool = False,
                 cpu_constant_ms: float | None = None) -> None:
        self.entries = engine_entries(cfg)
        self.cfg, self.run = cfg, run
        self.cpu_constant_ms = TANK_CPU_CONSTANT_MS if cpu_constant_ms is None else cpu_constant_ms
        self.space = tank_space(cfg)
        self.ppo = PPO(self.space.n_features, self.space.dims, cfg.ppo, seed=cfg.train.seed,
                       init_logits=skill_logits(self.space, cfg.tank.skill_prior))
        self.info: dict[str, Any] = {}
        if cfg.train.init:
            self.ppo.load_state_dict(load_tank_model(cfg.train.init, cfg).state_dict())
            self.info["init"] = cfg.train.init
        install = find_engine()  # no engine: a one-line error
        self.rows: list[dict[str, Any]] = []
        self.updates: list[dict[str, Any]] = []
        self.battles = self.decisions = self.skipped_turns = 0
        self.elapsed = self.engine_s = self.rollout_s = self.update_s = self.engine_setup_s = 0.0
        self.desc = f"{cfg.name} ppo (robocode)"
        self._tmp = tempfile.TemporaryDirectory(prefix="confront-tanks-engine-")
        try:
            tmp = Path(self._tmp.name)
            # the robot once, without TankData (no javac): each battle's policy comes from confront.tank.model
            self.jar = export_tank_robot(self.policy(), tmp / "tankbot.jar", install, embed=False)
            self.opponents: dict[str, Path] = {}
            for opp in sorted({e.partition(":")[2] for e in self.entries} & set(PAPER_MOVE_OPPONENTS)):
                self.opponents[opp] = export_robot(paper_move_robot(cfg, opp), tmp / f"opponent-{opp}", install)
        except Exception:
            self._tmp.cleanup()
            raise

    @classmethod
    def from_config(cls, cfg: ExperimentConfig, run: Run, progress: bool = False,
                    cpu_constant_ms: float | None = None) -> EngineTankTrainer:
        """``cfg``'s trainer (``factory.make_trainer``)."""
        return EngineTankTrainer(cfg, run, progress=progress, cpu_constant_ms=cpu_constant_ms)

    @property
    def rounds_done(self) -> int:
        return len(self.rows)

    def policy(self) -> TankPolicy:
        """The acting policy: the PPO's actor, sampled."""
        return replace(TankPolicy.from_state(self.ppo.actor_arrays(), self.space, ControlConfig(),
                                             self.cfg.tank.decision_turns), play="sampled")

    def advance(self, limit: int, tick: Any = None) -> dict[str, float]:
        """One battle of up to ``train.checkpoint_every`` rounds against the next league entry, then one PPO
        update on its decisions; the engine's results go to engine/battle-NNN/."""
        t0 = time.perf_counter()
        done = self.rounds_done
        rounds = min(self.cfg.train.checkpoint_every, limit - done)
        entry = self.entries[self.battles % len(self.entries)]
        with tempfile.TemporaryDirectory(prefix="battle-", dir=self._tmp.name) as tmp:
            folder = Path(tmp)
            (folder / "policy.txt").write_text(self.policy().to_text(), encoding="utf-8")
            (folder / "log").mkdir()
            props = (f"-Dconfront.tank.model={folder / 'policy.txt'}", f"-Dconfront.tank.log={folder / 'log'}",
                     f"-Dconfront.scores={folder / 'scores.txt'}")
            opts = EngineOptions(seed=self.cfg.train.seed + self.battles, cpu_constant_ms=self.cpu_constant_ms,
                                 nosecurity=True, extra_jvm_args=props, one_cpu=True)
            opts = replace(opts, timeout_s=opts.timeout_s + 10.0 * rounds)
            opp = entry.partition(":")[2]
            extra = [self.jar] + ([self.opponents[opp]] if opp in self.opponents else [])
            res = run_battle(_battle(entry, rounds), opts, extra_robots=extra)
            t_battle = time.perf_counter()
            logged = read_decisions(folder / "log")
            ro, n_dec = self._rollout(res, logged, read_scores(folder / "scores.txt", len(res.summary["robots"])))
            t1 = time.perf_counter()
        rows = round_rows(res.summary["round_scores"])
        self.decisions += n_dec
        for r in rows:
            r.update(battle=self.battles, round=r["round"] + done, opponent=entry, decisions=self.decisions)
        self.rows += rows
        self.ppo.set_progress(done / self.cfg.train.rounds)  # the schedules at the battle's start
        stats = self.ppo.update(ro) if n_dec else dict.fromkeys(UPDATE_STATS, math.nan)
        t2 = time.perf_counter()
        out = self.run.path / "engine" / f"battle-{self.battles:03d}"
        out.mkdir(parents=True, exist_ok=True)
        (out / "results.txt").write_text(res.results_text)  # the engine's own results file
        (out / "results.csv").write_text(res.results.to_csv())
        self.battles += 1
        self.skipped_turns += sum(res.skipped_turns.values())
        self.engine_setup_s += res.setup_s
        self.engine_s += t_battle - t0
        self.rollout_s += t1 - t_battle
        self.update_s += t2 - t1
        self.elapsed += t2 - t0
        for r in rows:
            r["wall_s"] = self.elapsed
        row = {"update": self.ppo.updates, "battle": self.battles - 1, "opponent": entry, "rounds": self.rounds_done,
               "decisions": self.decisions, "battle_decisions": n_dec, "decisions_logged": len(logged),
               "reward_points": float(ro.reward[ro.active].sum()) / self.ppo.config.reward_scale,
               "wall_s": self.elapsed, "engine_s": t_battle - t0, "rollout_s": t1 - t_battle, "update_s": t2 - t1,
               "decisions_per_s": n_dec / max(t2 - t0, 1e-9), "skipped_turns": sum(res.skipped_turns.values()),
               **stats}
        self.updates.append(row)
        return {k: float(v) for k, v in row.items() if isinstance(v, int | float)}

    def _rollout(self, res: EngineRun, decisions: list[Decision], scores: dict[int, ScoreLog]
                 ) -> tuple[Rollout, int]:
        """The battle's decisions as a Rollout (one column per robot and round), with the acting PPO's
        log-probabilities and values; and the number of decisions in it."""
        robots = res.summary["robots"]
        index = {r["name"]: i for i, r in enumerate(robots)}
        contestant = np.array([r["contestant"] for r in robots])
        ours = contestant == 0
        unknown = {d.robot for d in decisions} - set(index)
        if unknown:
            raise RuntimeError(f"decisions logged by robots the engine does not know: {sorted(unknown)}")
        episodes: dict[tuple[str, int], list[Decision]] = {}
        for d in decisions:  # sorted by robot, round, turn
            episodes.setdefault((d.robot, d.round), []).append(d)
        kept: list[Decision] = []
        rewards: list[np.ndarray] = []
        lengths: list[int] = []
        round_turns = res.summary["round_turns"]
        empty = ScoreLog(np.zeros(0, np.int64), np.zeros((0, len(robots)), bool), np.zeros((0, len(robots))))
        ends: dict[int, int | None] = {}  # each round's deciding turn, found once for all its robots
        for (robot, rnd), eps in episodes.items():
            log = scores.get(rnd, empty)
            if rnd not in ends:
                ends[rnd] = log.decided(contestant)
            end = ends[rnd]
            if end is None:  # not decided (the battle stopped): the round's last turn
                end = int(round_turns[rnd]) if rnd < len(round_turns) else eps[-1].turn + 1
            k = log.at(end)
            alive = bool(log.alive[k, index[robot]]) if k >= 0 else True
            r = episode_rewards([d.turn for d in eps], lambda t, log=log: log.margin(t, ours), end, alive,
                                self.cfg.tank.decision_turns)
            kept += eps[:len(r)]
            rewards.append(r)
            lengths.append(len(r))
        n = len(kept)
        obs = np.array([d.view for d in kept], dtype=np.float32).reshape(n, self.space.n_features)
        heads = np.array(np.unravel_index(np.array([d.action for d in kept], dtype=np.int64), self.space.dims),
                         dtype=np.int64).T.reshape(n, len(self.space.dims))
        # the team critic: each view beside its team's mean view at that decision turn (the simulator's _critic)
        order = sorted(range(n), key=lambda i: (kept[i].round, kept[i].turn, kept[i].robot))
        key = [(kept[i].round, kept[i].turn) for i in order]
        group = np.cumsum([0] + [int(a != b) for a, b in zip(key, key[1:], strict=False)])
        living = obs[order, FEATURE_NAMES.index("energy")] > 0
        crit = np.zeros((n, 2 * obs.shape[1] if self.ppo.config.team_critic else obs.shape[1]), np.float32)
        if n:
            crit[order] = self.ppo.critic_input(obs[order], group, int(group[-1]) + 1, living)
        logp = self.ppo.log_prob(obs, heads) if n else np.zeros(0, np.float32)
        value = self.ppo.values(crit, threads=self.ppo.config.threads) if n else np.zeros(0, np.float32)
        reward = np.concatenate(rewards) * self.ppo.config.reward_scale if rewards else np.zeros(0)
        idx, active, done = pack_episodes(lengths)
        safe = np.where(active, idx, 0)

        def cells(a: np.ndarray) -> np.ndarray:
            if n == 0:
                return np.zeros(idx.shape + a.shape[1:], a.dtype)
            out = a[safe]
            out[~active] = 0
            return out

        ro = Rollout(obs=cells(obs), critic=cells(crit), heads=cells(heads), logp=cells(logp.astype(np.float32)),
                     value=cells(value.astype(np.float32)), reward=cells(reward.astype(np.float64)), done=done,
                     active=active, last_value=np.zeros(idx.shape[1], np.float32))
        return ro, n

    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays = {f"ppo.{k}": v for k, v in self.ppo.state_dict().items()}
        meta = {"kind": "ppo", "rounds_done": self.rounds_done, "rows": self.rows, "updates": self.updates,
                "battles": self.battles, "decisions": self.decisions, "skipped_turns": self.skipped_turns,
                "update_elapsed_s": self.elapsed, "engine_s": self.engine_s, "rollout_s": self.rollout_s,
                "update_s": self.update_s,
                "setup_s": self.engine_setup_s}
        return arrays, meta

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        try:
            if meta.get("kind") != "ppo":
                raise ValueError("not a PPO checkpoint")
            self.ppo.load_state_dict({k[4:]: v for k, v in arrays.items() if k.startswith("ppo.")})
            self.rows, self.updates = list(meta["rows"]), list(meta["updates"])
            self.battles, self.decisions = int(meta["battles"]), int(meta["decisions"])
            self.skipped_turns = int(meta["skipped_turns"])
            self.elapsed, self.engine_s = float(meta["update_elapsed_s"]), float(meta["engine_s"])
            self.update_s, self.engine_setup_s = float(meta["update_s"]), float(meta["setup_s"])
            self.rollout_s = float(meta["rollout_s"])
        except (KeyError, ValueError, TypeError) as exc:
            raise ck.CheckpointError(f"the checkpoint does not fit this run's config: {exc}") from None

    def finish(self, run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]]) -> dict[str, Any]:
        """The model (``save_tank_model``: ``confront evaluate`` / ``export`` work on the run),
        ``metrics/updates.csv``, the figures; the summary's PPO and engine keys."""
        from confront.plots import session_plots

        cfg = self.cfg
        run.write_table("updates", self.updates)
        self.ppo.adopt_average()  # with ppo.ema_decay the model plays the averaged actor
        save_tank_model(run.path / "model", self.ppo, cfg, {"trained_rounds": len(rows), "engine": "robocode"})
        figs = session_plots(run.plots, sessions, cfg.name, cfg.train.session_rounds)
        return {"learner": "ppo", "scenario": "league", "updates": self.ppo.updates,
                "share_by_opponent_last": share_by_opponent(rows[-min(self.final_window, len(rows)):]),
                "decisions_per_s": self.decisions / max(self.elapsed, 1e-9), "figures": [str(f) for f in figs],
                "battles": self.battles, "cpu_constant_ms": self.cpu_constant_ms,
                "skipped_turns": self.skipped_turns, "engine_s": self.engine_s, "rollout_s": self.rollout_s,
                "update_s": self.update_s,
                "engine_setup_s": self.engine_setup_s, **self.info}

    def close(self) -> None:
        self.ppo.close()
        self._tmp.cleanup()
