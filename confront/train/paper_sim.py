"""The paper's learners in the batched simulator: :class:`SMDPTrainer`, one SMDP step of every battle per
``advance`` (``episodes.Loop``), against scripted robots or the TD team, with curriculum transfer as configured.

Run folder (besides ``loop.run_trainer``'s): ``model/`` (``paper_model.save_model``), the session figures and,
with ``train.replay``, the last round of a fresh battle as a replay (``replays/``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from confront.arena.smdp import TeamBattleEnv
from confront.runs import Run
from confront.train.episodes import Loop, Side, record_round
from confront.train.league import td_team
from confront.train.paper_model import build_learner, save_model, scenario_of, smdp_config, with_transfer
from confront.train.spec import ExperimentConfig

__all__ = ["SMDPTrainer"]


class SMDPTrainer:
    """The paper's learners in the simulator as a trainer of the one training loop (``loop.run_trainer``): one
    SMDP step of every battle per ``advance``. :meth:`from_config` builds a config's (the learner vs scripted
    robots or the TD team, curriculum transfer as configured)."""

    engine = "sim"
    bar_scalars = Loop.bar_scalars
    final_window = 100

    def __init__(self, loop: Loop, desc: str, cfg: ExperimentConfig | None = None,
                 info: dict[str, Any] | None = None) -> None:
        self.loop, self.desc, self.cfg, self.info = loop, desc, cfg, info or {}

    @classmethod
    def from_config(cls, cfg: ExperimentConfig, run: Run | None = None, progress: bool = False,
                    cpu_constant_ms: float | None = None) -> SMDPTrainer:
        """``cfg``'s trainer (``factory.make_trainer``; the simulator takes no CPU constant)."""
        scenario = scenario_of(cfg.arena.scenario)
        env = TeamBattleEnv(scenario, n_battles=cfg.arena.battles, seed=cfg.train.seed, opponents=cfg.opponent.kind,
                            config=smdp_config(cfg))
        team = env.team_ids()
        learner = build_learner(cfg, env.n_features, env.n_actions)
        info: dict[str, Any] = {"scenario": scenario.name, "n_actions": env.n_actions, "n_features": env.n_features}
        side = Side(learner, ours=team == 0)
        if cfg.opponent.kind == "td":
            td, where = td_team(cfg, env.n_actions, progress=progress)
            side.opponent, side.theirs, side.opponent_learns = td, team != 0, cfg.opponent.learning
            info["td_model"] = str(where)
        side.learner, transfer_info = with_transfer(cfg, learner)
        info.update(transfer_info)
        return cls(Loop(env, side, seed=cfg.train.seed), f"{cfg.name} {scenario.name}", cfg, info)

    @property
    def rows(self) -> list[dict[str, Any]]:
        return self.loop.rows

    @property
    def rounds_done(self) -> int:
        return self.loop.rounds_done

    @property
    def decisions(self) -> int:
        return self.loop.decisions

    def advance(self, limit: int, tick: Any = None) -> dict[str, float]:
        """One SMDP step; rounds past ``limit`` are dropped (battles share out the rounds)."""
        return self.loop.advance(limit, tick)

    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        return self.loop.state()

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        self.loop.load(arrays, meta)

    def finish(self, run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]]) -> dict[str, Any]:
        from confront.plots import session_plots

        cfg, side = self.cfg, self.loop.side
        if cfg is None:
            raise ValueError("finish needs the trainer's config (SMDPTrainer.from_config)")
        save_model(run.path / "model", side.learner,
                   {"scenario": self.info["scenario"], "decision_turns": cfg.arena.decision_turns,
                    "fire_power_actions": cfg.arena.fire_power_actions, "target": cfg.arena.target})
        figures = session_plots(run.plots, sessions, cfg.name, cfg.train.session_rounds)
        replay = record_round(cfg, side, run.replays) if cfg.train.replay else None
        return {"scenario": self.info["scenario"], "learner": side.learner.diagnostics(),
                "figures": [str(f) for f in figures], "replay": replay, **self.info}

    def close(self) -> None:
        pass
