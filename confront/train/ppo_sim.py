"""Training the recommended learner: PPO tanks against a league of opponents in the batched simulator.

    league entries (scenario x opponent) -> PoolEnv (all battles, one call per entry)
    -> tank views (N, F) -> PPO.act -> joint tank actions (N,) -> PoolEnv.step -> score-margin rewards
    -> every S steps: PPO.update (GAE, clipped surrogate), metrics, self-play snapshot, checkpoint

Opponents (``league.opponents``, ``SCENARIO:OPPONENT``): a scripted sample robot (in 4v4 a team of four),
``td`` (the paper's TD team, greedy, paper moves), ``random`` (uniform paper moves), ``dodge`` (a hand-written
stochastic dodge over the paper's state and moves), ``strafe`` (a hand-written strafer with the learners' own
actions and gun), ``self`` (a snapshot of the policy, sampled from the last few). Opponents in the paper's
moves play the paper's controller (no lead, power by distance).
Nothing in a tank's view names its opponent.

Run folder: ``metrics/rounds.csv`` (one row per round: opponent, scores, share), ``metrics/sessions.csv``,
``metrics/updates.csv`` and TensorBoard scalars in ``tb/`` (share per opponent, losses, entropy,
decisions/s), ``model/`` (``model.json`` kind ppo, ``actor.npz``, ``tank.json``), data-only checkpoints
after every ``train.checkpoint_every`` rounds (at an update boundary: a resumed run is identical).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
import numpy as np

from confront import checkpoint as ck
from confront.arena.observe import N_DIST_BINS, N_HEADING_BINS, N_STATES, ObservationConfig
from confront.arena.pool import OpponentPolicy, PoolEntry, PoolEnv, PoolStep
from confront.arena.smdp import SMDPConfig
from confront.arena.tank import FEATURE_NAMES, OWN_FEATURES, TankSpace
from confront.experiments.spec import ExperimentConfig
from confront.learning.ppo import PPO, UPDATE_STATS, PPOConfig, Rollout
from confront.runs import Run

if TYPE_CHECKING:
    from confront.engine.export import ExportedPolicy
    from confront.engine.tank_export import Play
    from confront.learning.base import Learner

__all__ = ["TankTrainer", "tank_space", "smdp_tank_config", "build_pool", "dodge_policy", "strafe_policy",
           "PAPER_MOVE_OPPONENTS", "paper_move_values", "paper_move_robot",
           "SnapshotPolicy",
           "save_tank_model", "load_tank_model", "evaluate_tanks"]


def tank_space(cfg: ExperimentConfig) -> TankSpace:
    """The config's tank actions and view."""
    t = cfg.tank
    return TankSpace(distances=tuple(t.distances), turns_deg=tuple(t.turns_deg), turn_mode=t.turn_mode,
                     fire_powers=tuple(t.fire_powers), enemy_slots=t.enemy_slots, mate_slots=t.mate_slots,
                     leads=tuple(t.leads))


def smdp_tank_config(cfg: ExperimentConfig) -> SMDPConfig:
    """The SMDP step of a PPO tank."""
    return SMDPConfig(turns_per_step=cfg.tank.decision_turns, tank=tank_space(cfg), reward=cfg.tank.reward,
                      observation=ObservationConfig(sensing="scanned"))


def ppo_config(cfg: ExperimentConfig) -> PPOConfig:
    """The config's PPO section as the learner's."""
    return PPOConfig(**asdict(cfg.ppo))


# -- opponents driven by Python ----------------------------------------------------------------------------------

def random_policy(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Uniform random paper moves."""
    return rng.integers(0, 4, size=len(disc))


def dodge_policy(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The hand-written stochastic dodge over the paper's own state and moves (§6.1): with the target ahead or
    behind (rel bins 0, 2) turn 45 deg either way at random, with it at a side (bins 1, 3) drive forward or
    backward at random; the paper's gun controller (no lead)."""
    rel = disc // (N_HEADING_BINS * N_DIST_BINS)
    side = (rel == 1) | (rel == 3)
    return np.where(side, rng.integers(0, 2, len(disc)), 2 + rng.integers(0, 2, len(disc)))


PAPER_MOVE_OPPONENTS = ("td", "random", "dodge")  # opponents in the paper's moves, playable in the engine


def paper_move_values(cfg: ExperimentConfig, opp: str, progress: bool = False) -> np.ndarray:
    """(320, 4) move values of a paper-move opponent whose maxima are the moves it draws from, uniformly: the TD
    team's Q table (greedy, random ties), zeros for ``random``, and for ``dodge`` 1 on the two moves of
    :func:`dodge_policy` in each state."""
    if opp == "td":
        return np.asarray(_td_learner(cfg, progress).state_dict()["q"], dtype=np.float64)
    rel = np.arange(N_STATES) // (N_HEADING_BINS * N_DIST_BINS)
    q = np.zeros((N_STATES, 4))
    if opp == "dodge":
        side = (rel == 1) | (rel == 3)
        q[side, :2] = 1.0
        q[~side, 2:] = 1.0
    elif opp != "random":
        raise ValueError(f"{opp!r} is not one of the paper-move opponents {PAPER_MOVE_OPPONENTS}")
    return q


def paper_move_robot(cfg: ExperimentConfig, opp: str) -> ExportedPolicy:  # the engine import kept lazy
    """A paper-move opponent as the exported ``confront.PolicyBot`` plays it in the engine: its move values with
    random ties, the league's decision interval, the paper's controller and scan memory, as in the simulator."""
    from confront.engine.export import ExportedPolicy

    return ExportedPolicy("qtable", q=paper_move_values(cfg, opp), observation=ObservationConfig(),
                          step_turns=cfg.tank.decision_turns, ties="random")


def strafe_policy(space: TankSpace) -> OpponentPolicy:
    """A hand-written stochastic strafer in the tank actions, with the learners' own gun: the body perpendicular
    to the nearest known enemy, full distance on in the direction it moves (reversed with probability 0.2 each
    step), fire power 1 with the last lead of ``space.leads``."""
    turns = np.radians(np.asarray(space.turns_deg))
    dists = np.asarray(space.distances)
    powers = np.asarray(space.fire_powers)
    far = int(np.argmax(dists)), int(np.argmin(dists))
    fire = int(np.argmin(np.abs(powers - 1.0)))
    side = int(np.argmin(np.abs(np.abs(turns) - np.pi / 2)))  # the angle nearest 90 deg (turn_mode "target")

    def act(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        o = OWN_FEATURES
        if space.turn_mode == "target":
            t = np.full(len(disc), side)
        else:
            rel = np.arctan2(feats[:, o + 1], feats[:, o + 2])  # bearing of slot 0 from the heading
            cand = (np.stack([rel + np.pi / 2, rel - np.pi / 2]) + np.pi) % (2 * np.pi) - np.pi
            want = np.where(np.abs(cand[0]) < np.abs(cand[1]), cand[0], cand[1])  # the smaller perpendicular turn
            t = np.argmin(np.abs(turns[None, :] - want[:, None]), axis=1)
        ahead = np.where(rng.random(len(disc)) < 0.8, feats[:, 6] >= 0, feats[:, 6] < 0)  # keep going, or reverse
        d = np.where(ahead, far[0], far[1])
        f = np.where(feats[:, o] > 0, fire, int(np.argmin(powers)))
        zero = np.zeros_like(d)
        return np.ravel_multi_index((d, t, f, zero, np.full_like(d, len(space.leads) - 1)), space.dims)

    return act


class SnapshotPolicy:
    """A frozen copy of the actor (NumPy), sampling its actions: the self-play opponent."""

    def __init__(self, dims: tuple[int, ...]) -> None:
        self.dims = dims
        self.layers: list[tuple[np.ndarray, np.ndarray]] = []

    def load(self, arrays: dict[str, np.ndarray]) -> None:
        """Set the weights from ``PPO.actor_arrays()``."""
        n = sum(1 for k in arrays if k.startswith("w"))
        self.layers = [(np.asarray(arrays[f"w{i}"]), np.asarray(arrays[f"b{i}"])) for i in range(n)]

    def __call__(self, disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        h = feats.astype(np.float64)
        for i, (w, b) in enumerate(self.layers):
            h = h @ w.T + b
            if i < len(self.layers) - 1:
                h = np.tanh(h)
        out = np.zeros(len(h), dtype=np.int64)
        start = 0
        for d in self.dims:
            z = h[:, start:start + d]
            p = np.exp(z - z.max(axis=1, keepdims=True))
            p /= p.sum(axis=1, keepdims=True)
            pick = (rng.random(len(z))[:, None] > np.cumsum(p, axis=1)).sum(axis=1)
            out = out * d + np.minimum(pick, d - 1)
            start += d
        return out


def build_pool(cfg: ExperimentConfig, seed: int, battles: int | None = None, progress: bool = False
               ) -> tuple[PoolEnv, SnapshotPolicy]:
    """The league as a PoolEnv; the self-play snapshot policy its ``self`` entries share."""
    space = tank_space(cfg)
    snap = SnapshotPolicy(space.dims)
    td = None
    entries = []
    for e in cfg.league.opponents:
        scen, _, opp = e.partition(":")
        n = battles or cfg.league.battles_of(e)
        if opp == "td":
            if td is None:
                td = _td_opponent(cfg, progress)
            entries.append(PoolEntry(e, scen, "td", n, policy=td, opponent_actions="paper"))
        elif opp == "random":
            entries.append(PoolEntry(e, scen, "td", n, policy=random_policy, opponent_actions="paper"))
        elif opp == "dodge":
            entries.append(PoolEntry(e, scen, "td", n, policy=dodge_policy, opponent_actions="paper"))
        elif opp == "strafe":
            entries.append(PoolEntry(e, scen, "td", n, policy=strafe_policy(space)))
        elif opp == "self":
            entries.append(PoolEntry(e, scen, "td", n, policy=snap))
        else:
            entries.append(PoolEntry(e, scen, opp, n))
    return PoolEnv(entries, smdp_tank_config(cfg), seed=seed), snap


def _td_learner(cfg: ExperimentConfig, progress: bool) -> Learner:
    """The paper's TD team's learner (trained once per seed and cached, as in the paper's experiments)."""
    from confront.experiments.episodes import td_team

    return td_team(cfg, 4, progress=progress)[0]


def _td_opponent(cfg: ExperimentConfig, progress: bool) -> OpponentPolicy:
    """The paper's TD team, greedy (random ties)."""
    learner = _td_learner(cfg, progress)

    def act(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return learner.act(disc, rng, explore=False)

    return act


# -- models ------------------------------------------------------------------------------------------------------


def _read_npz(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def save_tank_model(folder: Path, ppo: PPO, cfg: ExperimentConfig, meta: dict[str, Any]) -> None:
    """``model.json`` (kind ppo), ``actor.npz`` (w0, b0, ... as (out, in)), ``tank.json`` (actions, view,
    controller), ``ppo.npz`` (the whole learner, to continue training)."""
    folder.mkdir(parents=True, exist_ok=True)
    ck.write_npz(folder / "actor.npz", ppo.actor_arrays())
    ck.write_npz(folder / "ppo.npz", ppo.state_dict())
    from confront.arena.control import ControlConfig

    c = ControlConfig()
    tank = {**asdict(tank_space(cfg)), "step_turns": cfg.tank.decision_turns, "hidden": cfg.ppo.hidden,
            "team_critic": cfg.ppo.team_critic, "radar_overshoot": c.radar_overshoot,
            "aim_tolerance": c.aim_tolerance, "n_features": ppo.n_features, "dims": list(ppo.dims)}
    ck.write_atomic(folder / "tank.json", json.dumps(tank, indent=1, sort_keys=True).encode())
    info = {"format": "confront-model/1", "kind": "ppo", "observation": "tank", "n_actions": ppo.n_actions, **meta}
    ck.write_atomic(folder / "model.json", json.dumps(info, indent=1, sort_keys=True).encode())


def load_tank_model(folder: str | Path, cfg: ExperimentConfig) -> PPO:
    """The PPO learner of a run folder (or its ``model/``)."""
    p = Path(folder)
    if (p / "model").is_dir():
        p = p / "model"
    space = tank_space(cfg)
    ppo = PPO(space.n_features, space.dims, ppo_config(cfg))
    try:
        ppo.load_state_dict(_read_npz(p / "ppo.npz"))
    except (OSError, ValueError, KeyError) as exc:
        raise ck.CheckpointError(f"model {p} cannot be read: {exc}") from None
    return ppo


# -- the loop ----------------------------------------------------------------------------------------------------

class TankTrainer:
    """Rollouts over the pool and PPO updates, one of each per ``advance`` (a trainer of ``train.train_run``);
    all state is data (checkpoints resume exactly)."""

    engine = "sim"
    bar_scalars = {"decisions_per_s": "dps"}
    final_window = 200

    def __init__(self, cfg: ExperimentConfig, progress: bool = False) -> None:
        self.cfg = cfg
        self.pool, self.snap = build_pool(cfg, cfg.train.seed, progress=progress)
        self.ppo = PPO(self.pool.n_features, self.pool.action_dims, ppo_config(cfg), seed=cfg.train.seed)
        self.snapshots: list[dict[str, np.ndarray]] = []
        self.obs = self.pool.reset()
        self.rows: list[dict[str, Any]] = []
        self.updates: list[dict[str, Any]] = []
        self.decisions = 0
        self.elapsed = 0.0
        self.pending: Rollout | None = None  # the last rollout, which the next update() learns from
        self.desc = f"{cfg.name} ppo"
        self._take_snapshot()

    @property
    def rounds_done(self) -> int:
        return len(self.rows)

    def _take_snapshot(self) -> None:
        self.snapshots.append(self.ppo.actor_arrays())
        del self.snapshots[: -self.cfg.league.snapshots]

    def _pick_snapshot(self) -> None:
        self.snap.load(self.snapshots[int(self.pool.rng.integers(len(self.snapshots)))])

    def _critic(self, obs: np.ndarray) -> np.ndarray:
        alive = obs[:, FEATURE_NAMES.index("energy")] > 0  # a dead tank has no energy
        return self.ppo.critic_input(obs, self.pool.group, self.pool.n_groups, alive)

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

    def _collect(self) -> tuple[Rollout, float]:
        """S steps of every battle with the acting policy: the rollout, and the seconds spent in the env."""
        c, pool = self.ppo.config, self.pool
        s, n = c.rollout_steps, pool.n_agents
        crit = self._critic(self.obs)
        buf = Rollout(obs=np.zeros((s, n, self.obs.shape[1]), np.float32),
                      critic=np.zeros((s, n, crit.shape[1]), np.float32),
                      heads=np.zeros((s, n, len(self.ppo.dims)), np.int64), logp=np.zeros((s, n), np.float32),
                      value=np.zeros((s, n), np.float32), reward=np.zeros((s, n)), done=np.zeros((s, n), bool),
                      active=np.zeros((s, n), bool), last_value=np.zeros(n, np.float32))
        t_env = 0.0
        for k in range(s):
            joint, heads, logp = self.ppo.act(self.obs)
            te = time.perf_counter()
            st: PoolStep = pool.step(joint)
            t_env += time.perf_counter() - te
            buf.obs[k], buf.critic[k], buf.heads[k], buf.logp[k] = self.obs, crit, heads, logp
            buf.reward[k], buf.done[k], buf.active[k] = st.reward * c.reward_scale, st.done, st.active
            self.decisions += int(st.active.sum())
            for r in st.rounds:
                self.rows.append({"round": len(self.rows) + 1, **r, "decisions": self.decisions})
            self.obs = st.obs
            crit = self._critic(self.obs)
        # the values of the whole rollout in one product (the weights acted with; cheaper than one per step)
        buf.value[...] = self.ppo.values(buf.critic.reshape(s * n, -1), threads=c.threads).reshape(s, n)
        buf.last_value = self.ppo.values(crit)
        return buf, t_env

    def finish(self, run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]]) -> dict[str, Any]:
        """The model, ``metrics/updates.csv``, the figures; the summary's PPO keys."""
        from confront.experiments.plots import plot_curves, session_plots

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
                                    ylabel="score share", hline=0.5,
                                    title=f"{cfg.name}: share per opponent ({window}-round windows)"))
        return {"learner": "ppo", "scenario": "league", "updates": self.ppo.updates,
                "share_by_opponent_last": share_by_opponent(rows[-min(self.final_window, len(rows)):]),
                "decisions_per_s": self.decisions / max(self.elapsed, 1e-9), "figures": [str(f) for f in figs]}

    def close(self) -> None:
        self.ppo.close()

    # checkpoint state
    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays = {f"pool.{k}": v for k, v in self.pool.state_dict().items()}
        arrays.update({f"ppo.{k}": v for k, v in self.ppo.state_dict().items()})
        for i, snap in enumerate(self.snapshots):
            arrays.update({f"snap{i}.{k}": v for k, v in snap.items()})
        arrays["obs"] = self.obs
        if self.pending is not None:
            arrays.update({f"pending.{k}": v for k, v in asdict(self.pending).items()})
        meta = {"kind": "ppo", "rounds_done": self.rounds_done, "decisions": self.decisions, "rows": self.rows,
                "updates": self.updates, "update_elapsed_s": self.elapsed, "snapshots": len(self.snapshots),
                "pool_rng": ck.rng_state(self.pool.rng)}
        return arrays, meta

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        def sub(prefix: str) -> dict[str, np.ndarray]:
            return {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}

        try:
            if meta.get("kind") != "ppo":
                raise ValueError("not a PPO checkpoint")
            self.pool.load_state_dict(sub("pool."))
            self.ppo.load_state_dict(sub("ppo."))
            self.snapshots = [sub(f"snap{i}.") for i in range(int(meta["snapshots"]))]
            self.obs = np.asarray(arrays["obs"], dtype=np.float32)
            pending = sub("pending.")
            self.pending = Rollout(**pending) if pending else None
            self.rows, self.updates = list(meta["rows"]), list(meta["updates"])
            self.decisions = int(meta["decisions"])
            self.elapsed = float(meta.get("update_elapsed_s", meta.get("elapsed_s", 0.0)))
            self.pool.rng = ck.rng_from_state(meta["pool_rng"])
        except (KeyError, ValueError, TypeError) as exc:
            raise ck.CheckpointError(f"checkpoint does not fit this run's config: {exc}") from None


def share_by_opponent(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Pooled score share per opponent over ``rows``."""
    out: dict[str, list[float]] = {}
    for r in rows:
        o = out.setdefault(r["opponent"], [0.0, 0.0])
        o[0] += r["score_ours"]
        o[1] += r["score_theirs"]
    return {k: v[0] / (v[0] + v[1]) if v[0] + v[1] > 0 else 0.5 for k, v in out.items()}


def share_windows(rows: list[dict[str, Any]], size: int) -> list[tuple[int, float]]:
    """(rounds so far, pooled score share) per consecutive window of ``size`` rounds (a partial last one dropped)."""
    out = []
    for end in range(size, len(rows) + 1, size):
        chunk = rows[end - size:end]
        o = sum(float(r["score_ours"]) for r in chunk)
        t = sum(float(r["score_theirs"]) for r in chunk)
        out.append((end, o / (o + t) if o + t > 0 else 0.5))
    return out


def evaluate_tanks(cfg: ExperimentConfig, ppo: PPO, rounds: int, seed: int = 10_000,
                   opponents: tuple[str, ...] | None = None, battles: int = 16, explore: bool = False
                   ) -> dict[str, dict[str, float]]:
    """Greedy play (sampled with ``explore``) against each league entry for ``rounds`` rounds: share (pooled)
    and win rate per entry."""
    from dataclasses import replace

    league = replace(cfg.league, opponents=opponents or cfg.league.opponents, focus=())
    ecfg = replace(cfg, league=league)
    pool, snap = build_pool(ecfg, seed, battles=battles)
    snap.load(ppo.actor_arrays())
    obs = pool.reset()
    rows: list[dict[str, Any]] = []
    done = {e.name: 0 for e in pool.entries}
    while min(done.values()) < rounds:
        joint, *_ = ppo.act(obs, explore=explore)
        st = pool.step(joint)
        for r in st.rounds:
            name = str(r["opponent"])
            if done[name] < rounds:
                rows.append(r)
                done[name] += 1
        obs = st.obs
    shares = share_by_opponent(rows)
    return {k: {"share": shares[k], "win_rate": float(np.mean([r["won"] for r in rows if r["opponent"] == k])),
                "rounds": done[k]} for k in shares}


def print_tank_summary(summary: dict[str, Any]) -> None:
    """The results table of a PPO run, for the terminal: sessions, then the share per opponent."""
    run = Run(Path(summary["run"]))
    sessions = run.read_table("sessions")
    click.echo(f"\n{summary['name']}: {summary['rounds']} rounds against the league in {summary['wall_time_s']:.1f} s "
               f"({summary['decisions']:,} decisions, {summary['decisions_per_s']:,.0f}/s)")
    if sessions:
        click.echo("\n| session | decisions | score ours | score theirs | score share | win rate |")
        click.echo("|---:|---:|---:|---:|---:|---:|")
        step = max(1, len(sessions) // 10)
        for s in sessions[::step] + ([sessions[-1]] if (len(sessions) - 1) % step else []):
            click.echo(f"| {s['session']} | {int(float(s['decisions'])):,} | {float(s['score_ours']):.0f} | "
                       f"{float(s['score_theirs']):.0f} | {float(s['score_ratio']):.3f} | {float(s['win_rate']):.2f} |")
    click.echo(f"\nscore share over the last {summary['final_window_rounds']} rounds, per opponent:")
    for name, v in sorted(summary["share_by_opponent_last"].items()):
        click.echo(f"  {name:<18} {v:.3f}")
    click.echo(f"all: {summary['final_score_ratio']:.3f} (first session {summary['first_session_ratio']:.3f}, "
               f"last {summary['last_session_ratio']:.3f})")
    click.echo(f"run folder: {summary['run']}  (plots/, metrics/, model/, tb/, summary.json)")


def league_entries(opponents: str | None, cfg: ExperimentConfig) -> tuple[str, ...]:
    """``--opponents`` as league entries: ``SCENARIO:OPPONENT`` kept, a bare name is ``1v1:NAME``."""
    if not opponents:
        return tuple(cfg.league.opponents)
    names = [o.strip() for o in opponents.split(",") if o.strip()]
    return tuple(n if ":" in n else f"1v1:{n}" for n in names)


def evaluate_tank_cli(run: Path, opponents: str | None, rounds: int, seed: int, play: Play = "sampled"
                      ) -> dict[str, dict[str, float]]:
    """Shares of a PPO run per league entry in the simulator, printed as a table; ``play``: ``"sampled"``
    draws each head from its softmax, ``"greedy"`` takes its first maximum."""
    if play not in ("sampled", "greedy"):
        raise ValueError(f"play must be 'sampled' or 'greedy', got {play!r}")
    from dataclasses import replace

    from confront.experiments.spec import config_from_dict, load_toml

    cfg = config_from_dict(load_toml(run / "config.toml"))
    entries = league_entries(opponents, cfg)
    try:
        cfg = replace(cfg, league=replace(cfg.league, opponents=entries, focus=()))
    except ValueError as exc:
        raise click.UsageError(str(exc)) from None
    ppo = load_tank_model(run, cfg)
    res = evaluate_tanks(cfg, ppo, rounds, seed=seed, explore=play == "sampled")
    click.echo(f"\n{run}: {play} policy, {rounds} rounds per opponent (simulator, seed {seed})\n")
    click.echo("| opponent | rounds | score share | win rate |\n|---|---:|---:|---:|")
    for name in entries:
        r = res[name]
        click.echo(f"| {name} | {r['rounds']} | {r['share']:.3f} | {r['win_rate']:.2f} |")
    return res


def evaluate_tank_engine_cli(run: Path, opponents: str | None, rounds: int, seed: int,
                             seeds: int = 1, play: Play = "sampled", visible: bool = False) -> dict[str, list[float]]:
    """The exported TankBot (a jar, no Python, playing ``play``) in the real engine against each scripted league
    entry, ``seeds`` battles of ``rounds`` rounds (engine seeds ``seed``, ``seed + 1``, ...): our score ratio
    per battle. ``visible``: each battle in Robocode's battle window."""
    from confront.arena.bots import BOT_NAMES
    from confront.arena.scenarios import SAMPLE_TEAMS
    from confront.engine.tank_export import evaluate_tank_policy, load_tank_policy
    from confront.experiments.spec import config_from_dict, load_toml

    cfg = config_from_dict(load_toml(run / "config.toml"))
    policy = load_tank_policy(run, play)
    out: dict[str, list[float]] = {}
    click.echo(f"\n{run}: the exported TankBot ({play}) in Robocode, {rounds} rounds x {seeds} battle(s) per "
               "opponent\n")
    click.echo("| opponent | battles | score ratio (robocode) |\n|---|---:|---:|")
    for entry in league_entries(opponents, cfg):
        scen, _, opp = entry.partition(":")
        if opp not in BOT_NAMES and opp not in SAMPLE_TEAMS:
            click.echo(f"| {entry} | - | simulator only |")
            continue
        out[entry] = [evaluate_tank_policy(policy, scen, opp, rounds=rounds, seed=seed + k, visible=visible)[1]
                      for k in range(seeds)]
        click.echo(f"| {entry} | {seeds} | {' / '.join(f'{v:.3f}' for v in out[entry])} |")
    return out
