"""PPO tanks against a league of opponents in the batched simulator: :class:`TankTrainer`.

    league entries (scenario x opponent) -> PoolEnv (all battles, one call per entry: ``league.build_pool``)
    -> tank views (N, F) -> PPO.act -> joint tank actions (N,) -> PoolEnv.step -> score-margin rewards
    -> every S steps: PPO.update (GAE, clipped surrogate), metrics, self-play snapshot, checkpoint

Run folder: ``metrics/rounds.csv`` (one row per round: opponent, scores, share), ``metrics/sessions.csv``,
``metrics/updates.csv`` and TensorBoard scalars in ``tb/`` (share per opponent, losses, entropy,
decisions/s), ``model/`` (``ppo_model.save_tank_model``), data-only checkpoints after every
``train.checkpoint_every`` rounds (at an update boundary: a resumed run is identical).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from confront import checkpoint as ck
from confront.arena.pool import PoolEnv, PoolStep
from confront.arena.tank import FEATURE_NAMES
from confront.learning.ppo import PPO, UPDATE_STATS, Rollout
from confront.runs import Run
from confront.train.league import build_pool, pfsp_playing, recent_shares
from confront.train.loop import share_by_opponent
from confront.train.ppo_model import save_tank_model, skill_logits, tank_space
from confront.train.spec import ExperimentConfig

__all__ = ["TankTrainer", "collect_rollout", "critic_input"]


class TankTrainer:
    """Rollouts over the pool and PPO updates, one of each per ``advance`` (a trainer of ``loop.run_trainer``);
    all state is data (checkpoints resume exactly)."""

    engine = "sim"
    bar_scalars = {"decisions_per_s": "dps"}
    final_window = 200

    def __init__(self, cfg: ExperimentConfig, progress: bool = False) -> None:
        self.cfg = cfg
        self.pool, self.snap = build_pool(cfg, cfg.train.seed, progress=progress)
        self.ppo = PPO(self.pool.n_features, self.pool.action_dims, cfg.ppo, seed=cfg.train.seed,
                       init_logits=skill_logits(tank_space(cfg), cfg.tank.skill_prior))
        self.snapshots: list[dict[str, np.ndarray]] = []
        self.obs = self.pool.reset()
        self.rows: list[dict[str, Any]] = []
        self.updates: list[dict[str, Any]] = []
        self.decisions = 0
        self.elapsed = 0.0
        self.pending: Rollout | None = None  # the last rollout, which the next update() learns from
        self.desc = f"{cfg.name} ppo"
        self._take_snapshot()

    @classmethod
    def from_config(cls, cfg: ExperimentConfig, run: Run | None = None, progress: bool = False,
                    cpu_constant_ms: float | None = None) -> TankTrainer:
        """``cfg``'s trainer (``factory.make_trainer``; the simulator takes no CPU constant)."""
        return TankTrainer(cfg, progress=progress)

    @property
    def rounds_done(self) -> int:
        return len(self.rows)

    def _take_snapshot(self) -> None:
        self.snapshots.append(self.ppo.actor_arrays())
        del self.snapshots[: -self.cfg.league.snapshots]

    def _pick_snapshot(self) -> None:
        self.snap.load(self.snapshots[int(self.pool.rng.integers(len(self.snapshots)))])

    def advance(self, limit: int, tick: Any = None) -> dict[str, Any]:
        """One rollout and update (:meth:`update`); rounds past ``limit`` are kept (every battle ends its round)."""
        return self.update()

    def update(self) -> dict[str, Any]:
        """One rollout of S steps, and one PPO update on the rollout before it (``ppo.overlap``: the two side by
        side); returns the update's log row (no losses for the first rollout, which has no update before it; a
        run's last rollout is collected but not learned from)."""
        t0 = time.perf_counter()
        first_row = len(self.rows)
        self._pick_snapshot()
        pending, self.pending = self.pending, None
        if pending is not None:
            self.ppo.set_progress(self.rounds_done / self.cfg.train.rounds)
            self.ppo.start_update(pending)  # with overlap it returns at once
        t_up = time.perf_counter() - t0
        buf, t_env = self._collect()
        t1 = time.perf_counter()
        stats = self.ppo.finish_update() if pending is not None else dict.fromkeys(UPDATE_STATS, math.nan)
        t_up += time.perf_counter() - t1
        self.pending = buf
        if pending is not None and self.ppo.updates % self.cfg.league.snapshot_every == 0:
            self._take_snapshot()
        dt = time.perf_counter() - t0
        self.elapsed += dt
        row = {"update": self.ppo.updates, "rounds": self.rounds_done, "decisions": self.decisions,
               "wall_s": self.elapsed, "decisions_per_s": float(buf.active.sum()) / dt,
               "env_fraction": t_env / dt, "update_wait_fraction": t_up / dt, **stats}
        for r in self.rows[first_row:]:  # the rounds that ended in this update, at its end
            r["wall_s"] = self.elapsed
        self.updates.append(row)
        return row

    def _playing(self) -> np.ndarray | None:
        """The entries that play the next rollout: all, or with ``league.prioritise`` those that
        :func:`~confront.train.league.pfsp_playing` draws from their recent shares."""
        lc = self.cfg.league
        if not lc.prioritise:
            return None
        names = [e.name for e in self.pool.entries]
        shares = recent_shares(self.rows, names, lc.share_window)
        return pfsp_playing(shares, self.pool.rng, lc.play_fraction, lc.play_floor, lc.pfsp_power)

    def _collect(self) -> tuple[Rollout, float]:
        """S steps of every battle with the acting policy: the rollout, and the seconds spent in the env."""
        buf, self.obs, active, ended, t_env = collect_rollout(self.ppo, self.pool, self.obs, self._playing())
        self._record(active, ended)
        return buf, t_env

    def _record(self, active: np.ndarray, ended: list[list[dict[str, Any]]]) -> None:
        """Count a rollout's decisions (``active`` (S,): the agents active at each step) and add the rounds that
        ended at each step (``ended``), each row with the decisions made by the end of its step."""
        for k, rounds in enumerate(ended):
            self.decisions += int(active[k])
            for r in rounds:
                self.rows.append({"round": len(self.rows) + 1, **r, "decisions": self.decisions})

    def finish(self, run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]]) -> dict[str, Any]:
        """The model, ``metrics/updates.csv``, the figures; the summary's PPO keys."""
        from confront.plots import plot_curves, session_plots

        cfg = self.cfg
        run.write_table("updates", self.updates)
        self.ppo.adopt_average()  # with ppo.ema_decay the model plays the averaged actor
        save_tank_model(run.path / "model", self.ppo, cfg, {"trained_rounds": len(rows)})
        figs = session_plots(run.plots, sessions, cfg.name, cfg.train.session_rounds)
        per: dict[str, list[float]] = {}
        window = max(10, cfg.train.session_rounds // 4)
        for name in sorted({r["opponent"] for r in rows}):
            sub = [r for r in rows if r["opponent"] == name]
            per[name] = [share_by_opponent(sub[i:i + window])[name] for i in range(0, len(sub) - window + 1, window)]
        n = min((len(v) for v in per.values()), default=0)
        if n > 1:
            figs.append(plot_curves({k: np.array(v[:n]) for k, v in per.items()}, run.plots / "share_by_opponent.png",
                                    ylabel="score share", hline=0.5, xlabel=f"window of {window} rounds",
                                    title=f"{cfg.name}: share per opponent ({window}-round windows)"))
        replay = record_tank_round(cfg, self.ppo, run.replays) if cfg.train.replay else None
        return {"learner": "ppo", "scenario": "league", "updates": self.ppo.updates, "replay": replay,
                "share_by_opponent_last": share_by_opponent(rows[-min(self.final_window, len(rows)):]),
                "decisions_per_s": self.decisions / max(self.elapsed, 1e-9), "figures": [str(f) for f in figs]}

    def close(self) -> None:
        self.ppo.close()

    # checkpoint state
    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays, meta = self._learner_state()
        arrays.update({f"pool.{k}": v for k, v in self.pool.state_dict().items()})
        arrays["obs"] = self.obs
        meta["pool_rng"] = ck.rng_state(self.pool.rng)
        return arrays, meta

    def _learner_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """What the learner holds: PPO, snapshots, the pending rollout, rows and counters."""
        arrays = {f"ppo.{k}": v for k, v in self.ppo.state_dict().items()}
        for i, snap in enumerate(self.snapshots):
            arrays.update({f"snap{i}.{k}": v for k, v in snap.items()})
        if self.pending is not None:
            arrays.update({f"pending.{k}": v for k, v in asdict(self.pending).items()})
        meta = {"kind": "ppo", "rounds_done": self.rounds_done, "decisions": self.decisions, "rows": self.rows,
                "updates": self.updates, "update_elapsed_s": self.elapsed, "snapshots": len(self.snapshots)}
        return arrays, meta

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        if meta.get("rollout_workers"):
            raise ck.CheckpointError(f"this run was trained on Ray with {meta['rollout_workers']} rollout workers: "
                                     "resume it with --address (confront train --resume RUN --address ...)")
        try:
            self._load_learner(arrays, meta)
            self.pool.load_state_dict(_sub(arrays, "pool."))
            self.obs = np.asarray(arrays["obs"], dtype=np.float32)
            self.pool.rng = ck.rng_from_state(meta["pool_rng"])
        except (KeyError, ValueError, TypeError) as exc:
            raise ck.CheckpointError(f"checkpoint does not fit this run's config: {exc}") from None

    def _load_learner(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        """Restore :meth:`_learner_state` (KeyError, ValueError or TypeError on a checkpoint that does not fit)."""
        if meta.get("kind") != "ppo":
            raise ValueError("not a PPO checkpoint")
        self.ppo.load_state_dict(_sub(arrays, "ppo."))
        n_snaps = int(meta["snapshots"])
        held = {k.split(".", 1)[0] for k in arrays if k.startswith("snap")}
        # the count first: the set of 10**8 names alone would take GBs (the snapshots' loop, hours)
        if n_snaps != len(held) or held != {f"snap{i}" for i in range(n_snaps)}:
            raise ValueError(f"snapshots = {n_snaps} but it holds {len(held)} snapshot(s)")
        self.snapshots = [_sub(arrays, f"snap{i}.") for i in range(n_snaps)]
        actor = {k: (v.shape, v.dtype.kind) for k, v in self.ppo.actor_arrays().items()}
        for i, snap in enumerate(self.snapshots):
            if {k: (v.shape, v.dtype.kind) for k, v in snap.items()} != actor:
                raise ValueError(f"snapshot {i} does not fit the actor")
        pending = _sub(arrays, "pending.")
        self.pending = Rollout(**pending) if pending else None
        self.rows, self.updates = list(meta["rows"]), list(meta["updates"])
        self.decisions = int(meta["decisions"])
        self.elapsed = float(meta.get("update_elapsed_s", meta.get("elapsed_s", 0.0)))


def _sub(arrays: dict[str, np.ndarray], prefix: str) -> dict[str, np.ndarray]:
    """The arrays whose names start with ``prefix``, without it."""
    return {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}


def critic_input(ppo: PPO, pool: PoolEnv, obs: np.ndarray) -> np.ndarray:
    """The critic's inputs (N, C) of the pool's agents at ``obs`` (N, F)."""
    alive = obs[:, FEATURE_NAMES.index("energy")] > 0  # a dead tank has no energy
    return ppo.critic_input(obs, pool.group, pool.n_groups, alive)


def collect_rollout(ppo: PPO, pool: PoolEnv, obs: np.ndarray, playing: np.ndarray | None
                    ) -> tuple[Rollout, np.ndarray, np.ndarray, list[list[dict[str, Any]]], float]:
    """``ppo.config.rollout_steps`` steps of the pool's battles (the ``playing`` entries', or all) from ``obs``,
    acting with ``ppo``: (the rollout, the observations after it, the agents active at each step (S,), the rounds
    that ended at each step, the seconds spent in the env)."""
    c = ppo.config
    s, n = c.rollout_steps, pool.n_agents
    crit = critic_input(ppo, pool, obs)
    buf = Rollout(obs=np.zeros((s, n, obs.shape[1]), np.float32),
                  critic=np.zeros((s, n, crit.shape[1]), np.float32),
                  heads=np.zeros((s, n, len(ppo.dims)), np.int64), logp=np.zeros((s, n), np.float32),
                  value=np.zeros((s, n), np.float32), reward=np.zeros((s, n)), done=np.zeros((s, n), bool),
                  active=np.zeros((s, n), bool), last_value=np.zeros(n, np.float32))
    t_env = 0.0
    ended: list[list[dict[str, Any]]] = []
    for k in range(s):
        joint, heads, logp = ppo.act(obs)
        te = time.perf_counter()
        st: PoolStep = pool.step(joint, playing)
        t_env += time.perf_counter() - te
        buf.obs[k], buf.critic[k], buf.heads[k], buf.logp[k] = obs, crit, heads, logp
        buf.reward[k], buf.done[k], buf.active[k] = st.reward * c.reward_scale, st.done, st.active
        ended.append(list(st.rounds))
        obs = st.obs
        crit = critic_input(ppo, pool, obs)
    # the values of the whole rollout in one product (the weights acted with; cheaper than one per step)
    buf.value[...] = ppo.values(buf.critic.reshape(s * n, -1), threads=c.threads).reshape(s, n)
    buf.last_value = ppo.values(crit)
    return buf, obs, buf.active.sum(axis=1), ended, t_env


def record_tank_round(cfg: ExperimentConfig, ppo: PPO, out_dir: Path, entry: str | None = None) -> str:
    """One round of the trained tanks (sampling their heads, as they trained and as the exported robot plays) in a
    fresh battle of ``entry`` (default the league's first team entry, say ``4v4:td``), as replay JSON + GIF + HTML
    in ``out_dir``."""
    from dataclasses import replace

    from confront.train.episodes import write_replay

    names = list(cfg.league.opponents)
    entry = entry or next((e for e in names if not e.startswith("1v1:")), names[0])
    pool, snap = build_pool(replace(cfg, league=replace(cfg.league, opponents=(entry,), focus=())),
                            cfg.train.seed + 1000, battles=1)
    snap.load(ppo.actor_arrays())
    obs = pool.reset()
    env = pool.envs[0]
    env.start_recording(0)
    while True:
        joint, *_ = ppo.act(obs, explore=True)
        st = pool.step(joint)
        obs = st.obs
        if st.rounds:
            break
    replay = env.stop_recording()
    if replay is None:
        raise RuntimeError("the replay of the trained tanks recorded nothing")
    return write_replay(replay, out_dir, f"confront: {cfg.name}, {entry}")
