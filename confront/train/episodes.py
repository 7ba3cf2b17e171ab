"""The paper learners' episodes: a learning team against its opponents in the batched simulator (Algorithm 2).

Per SMDP step (T engine turns):

    observations (B, R) --learner.act--> our actions --+--> env.step --> rewards (B, R, T), next obs
                        --opponent.act-> their actions -+        |
    learner.learn(transitions of our living tanks)  <-----------+   (parameter sharing: one learner, all tanks)

B battles run side by side and share out the configured number of rounds; rounds are numbered in the
order they end (deterministic for a seed). :class:`Loop` holds everything that changes (arena arrays,
learner, opponent, RNG states, metrics so far) as data, so a checkpointed run resumes exactly; its
:meth:`Loop.advance` is a trainer's step (``loop.run_rounds``: ``paper_sim.SMDPTrainer``, the TD team's
pre-training). :func:`record_round` plays one greedy round as a replay.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from confront import checkpoint as ck
from confront.arena.smdp import TeamBattleEnv
from confront.arena.state import SCORE_PARTS
from confront.learning.base import Learner, Transition
from confront.train.paper_model import scenario_of, smdp_config
from confront.train.spec import ExperimentConfig

__all__ = ["Side", "Loop", "record_round"]


def _obs(learner: Learner, disc: np.ndarray, feats: np.ndarray) -> np.ndarray:
    return disc if learner.observation == "discrete" else feats



@dataclass
class Side:
    """Who drives which robots: the learner (team 0) and an optional learning opponent (the TD team)."""

    learner: Learner
    ours: np.ndarray  # (R,) bool
    opponent: Learner | None = None
    theirs: np.ndarray | None = None  # (R,) bool, robots the opponent learner drives
    opponent_learns: bool = False


def _round_row(end: Any, b: int, team: np.ndarray) -> dict[str, Any]:
    ours, theirs = team == 0, team != 0
    s = end.score[b]
    row: dict[str, Any] = {"battle": b, "turns": int(end.turns[b]), "decided": bool(end.decided[b])}
    total_o, total_t = float(s[ours].sum()), float(s[theirs].sum())
    row.update(score_ours=total_o, score_theirs=total_t,
               score_ratio=total_o / (total_o + total_t) if total_o + total_t > 0 else 0.5,
               defensive_ours=float(s[ours][:, :2].sum()), defensive_theirs=float(s[theirs][:, :2].sum()),
               won=bool(end.decided[b] and end.alive[b][ours].any()),
               alive_ours=int(end.alive[b][ours].sum()), alive_theirs=int(end.alive[b][theirs].sum()))
    for i, part in enumerate(SCORE_PARTS):
        row[f"{part}_ours"] = float(s[ours][:, i].sum())
        row[f"{part}_theirs"] = float(s[theirs][:, i].sum())
    return row


class Loop:
    """The SMDP interaction loop over a TeamBattleEnv; state is data so it can be checkpointed."""

    bar_scalars = {"temperature": "T"}  # the progress bar's (loop.run_rounds)

    def __init__(self, env: TeamBattleEnv, side: Side, seed: int, learning: bool = True) -> None:
        self.env, self.side = env, side
        self.learning = learning  # False: evaluate greedily, nothing learns
        self.team = env.team_ids()
        self.rngs = {name: np.random.default_rng([seed, i]) for i, name in enumerate(("act", "opp"))}
        self.rounds_done = 0
        self.decisions = 0
        self.rows: list[dict[str, Any]] = []
        self.disc, self.feats = env.reset()
        self.last_learn: dict[str, float] = {}

    # checkpoint state
    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays = {f"env.{k}": v for k, v in self.env.state_dict().items()}
        arrays.update({f"learner.{k}": v for k, v in self.side.learner.state_dict().items()})
        if self.side.opponent is not None:
            arrays.update({f"opponent.{k}": v for k, v in self.side.opponent.state_dict().items()})
        arrays["obs.discrete"], arrays["obs.features"] = self.disc, self.feats
        meta = {"rounds_done": self.rounds_done, "decisions": self.decisions, "rows": self.rows,
                "rngs": {k: ck.rng_state(g) for k, g in self.rngs.items()}}
        return arrays, meta

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        def sub(prefix: str) -> dict[str, np.ndarray]:
            return {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}

        try:
            self.env.load_state_dict(sub("env."))
            self.side.learner.load_state_dict(sub("learner."))
            if self.side.opponent is not None:
                self.side.opponent.load_state_dict(sub("opponent."))
            self.disc, self.feats = arrays["obs.discrete"], arrays["obs.features"]
            self.rounds_done, self.decisions = int(meta["rounds_done"]), int(meta["decisions"])
            self.rows = list(meta["rows"])
            self.rngs = {k: ck.rng_from_state(v) for k, v in meta["rngs"].items()}
        except (KeyError, ValueError, TypeError) as exc:
            raise ck.CheckpointError(f"checkpoint does not fit this run's config: {exc}") from None

    def step(self) -> list[dict[str, Any]]:
        """One SMDP step in every battle; returns the rows of the rounds that ended."""
        env, side = self.env, self.side
        b, r = env.n_battles, env.n_robots
        actions = np.zeros((b, r), dtype=np.int64)
        obs_ours = _obs(side.learner, self.disc, self.feats)[:, side.ours]
        flat = obs_ours.reshape((-1,) + obs_ours.shape[2:])
        actions[:, side.ours] = side.learner.act(flat, self.rngs["act"], explore=self.learning).reshape(b, -1)
        if side.opponent is not None and side.theirs is not None:
            obs_t = _obs(side.opponent, self.disc, self.feats)[:, side.theirs]
            their_a = side.opponent.act(obs_t.reshape((-1,) + obs_t.shape[2:]), self.rngs["opp"],
                                        explore=side.opponent_learns and self.learning)
            actions[:, side.theirs] = their_a.reshape(b, -1)
        res = env.step(actions)
        self.decisions += 1
        if self.learning:
            self._learn(side.learner, side.ours, res, actions)
        if self.learning and side.opponent is not None and side.opponent_learns and side.theirs is not None:
            self._learn(side.opponent, side.theirs, res, actions)
        ended: list[dict[str, Any]] = []
        if res.round_end is not None:
            for bi in np.flatnonzero(res.round_end.mask):
                row = _round_row(res.round_end, int(bi), self.team)
                self.rounds_done += 1
                row["round"] = self.rounds_done
                ended.append(row)
        self.disc, self.feats = res.discrete, res.features
        return ended

    def advance(self, limit: int, tick: Any = None) -> dict[str, float]:
        """One SMDP step as a trainer's step (``loop.run_rounds``): the rows of the rounds that ended are kept,
        rounds past ``limit`` dropped (battles share out the rounds); returns the learner's scalars."""
        ended = self.step()
        if not ended:
            return {}
        self.rows.extend(ended)
        if len(self.rows) > limit:
            del self.rows[limit:]
            self.rounds_done = limit
        return {k: v for k, v in self.side.learner.diagnostics().items() if isinstance(v, int | float)}

    def _learn(self, learner: Learner, robots: np.ndarray, res: Any, actions: np.ndarray) -> None:
        next_disc, next_feats = res.discrete, res.features
        if res.final_discrete is not None:
            ended = res.round_done[:, None]
            next_disc = np.where(ended, res.final_discrete, res.discrete)
            next_feats = np.where(ended[..., None], res.final_features, res.features)
        active = res.active[:, robots]
        if not active.any():
            return
        obs = _obs(learner, self.disc, self.feats)[:, robots][active]
        nxt = _obs(learner, next_disc, next_feats)[:, robots][active]
        batch = Transition(obs=obs, action=actions[:, robots][active], rewards=res.rewards[:, robots][active],
                           next_obs=nxt, done=res.terminated[:, robots][active])
        out = learner.learn(batch)
        if learner is self.side.learner:
            self.last_learn = out



def record_round(cfg: ExperimentConfig, side: Side, out_dir: Path, seed: int | None = None) -> str | None:
    """One greedy round of the trained team in a single fresh battle, as replay JSON + GIF + HTML."""
    env = TeamBattleEnv(scenario_of(cfg.arena.scenario), n_battles=1,
                        seed=cfg.train.seed + 1000 if seed is None else seed,
                        opponents="td" if side.opponent is not None else cfg.opponent.kind,
                        config=smdp_config(cfg))
    loop = Loop(env, Side(side.learner, side.ours, side.opponent, side.theirs), seed=cfg.train.seed, learning=False)
    env.start_recording(0)
    while loop.rounds_done < 1:
        loop.step()
    replay = env.stop_recording()
    return write_replay(replay, out_dir, f"confront: {cfg.name}") if replay is not None else None


def write_replay(replay: Any, out_dir: Path, title: str) -> str:
    """A recorded round as ``out_dir/last_round.replay.json.gz`` with a GIF and an HTML player beside it."""
    from confront.arena import replay as rp

    out_dir.mkdir(parents=True, exist_ok=True)
    path = replay.save(out_dir / "last_round.replay.json.gz")
    rp.write_gif(replay, out_dir / "last_round.gif")
    rp.write_html(replay, out_dir / "last_round.html", title=title)
    return str(path)
