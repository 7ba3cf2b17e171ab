"""PPO tanks with rollout workers on Ray: :class:`RayTankTrainer` (``confront train --address HOST:PORT|auto``).

    driver (the learner, ``TankTrainer.update``): PPO update on the last rollout -> acting weights (numpy)
      -> W :class:`RolloutWorker` actors (one CPU each): its share of every entry's battles (a PoolEnv) and a PPO
         copy that only acts -> S steps -> its rollout (S, n_w, ...), agents active per step (S,), rounds ended
      -> the driver: one Rollout of the workers' side by side along the agents (N = sum n_w), rows in (step,
         worker) order -> the next update learns from it (the schedule of ``ppo.overlap`` is kept: with it the
         workers act on the weights before the update, which runs meanwhile on the driver)

- Split: entry e's B_e battles (``league.battles_of``) go B_e // W to each worker, the B_e % W left over one each
  to the next workers in turn (over all entries, so W workers share W battles one each); a worker never holds
  zero battles (ConfigError).
- Seeds: worker 0 plays with ``train.seed`` (its pool and its acting stream), so one worker is the local path
  exactly (rows, updates, model bit-identical); worker w > 0 with ``SeedSequence([train.seed, w])``'s first word
  (:func:`worker_seed`).
- Self-play: the driver keeps the snapshots; each worker draws the one it plays per rollout with its pool's
  generator. Prioritised sampling (``league.prioritise``): the driver computes every entry's recent share over
  all rows; each worker draws the PFSP mask over the whole league with its generator and plays its own entries
  (one worker: the local draw; W: each entry still plays with its probability p_e).
- A worker that dies (its actor killed, its node lost: ``RayActorError``) is started again from its seed (new
  battles; the rounds it was playing are lost) and collects the same rollout with the same weights: no update is
  lost. ``summary.json`` counts ``rollout_worker_restarts``.
- Checkpoints stay data only: the learner's arrays as the local path's, each worker's pool, observations and
  generators (``worker{w}.*``), meta ``rollout_workers``. ``--resume RUN --address ...`` continues exactly (the
  worker count is the checkpoint's); resuming a Ray run without ``--address``, or a local run with it, is refused.

Every update sends the weights (and the snapshots) to every worker and gathers S x N observations, critic
inputs and heads: about ``S N (12 F + 8 H + 18)`` bytes a rollout with the team critic (the whole league: 25 MB).
One learner: the update does not scale with W (docs/learning.md, "Scale-out on Ray").
"""

from __future__ import annotations

import socket
import time
from dataclasses import asdict
from typing import Any

import click
import numpy as np
import ray
import torch

from confront import checkpoint as ck
from confront.arena.pool import OpponentPolicy
from confront.config import ConfigError
from confront.learning.ppo import PPO, Rollout
from confront.runs import Run
from confront.train.league import build_pool, pfsp_playing, recent_shares, td_policy
from confront.train.ppo_model import skill_logits, tank_space
from confront.train.ppo_sim import TankTrainer, _sub, collect_rollout
from confront.train.spec import ExperimentConfig

__all__ = ["RolloutWorker", "RayTankTrainer", "split_league", "worker_seed", "connect", "MAX_RESTARTS"]

MAX_RESTARTS = 3  # starts of one worker in a row for one rollout before the run gives up


def worker_seed(seed: int, w: int) -> int:
    """Rollout worker ``w``'s seed: ``seed`` for worker 0 (the local path's), below 2**31 for the others."""
    return seed if w == 0 else int(np.random.SeedSequence([seed, w]).generate_state(1)[0] >> 1)


def split_league(cfg: ExperimentConfig, workers: int) -> list[dict[str, int]]:
    """Each worker's entries and battles (see the module docstring); ConfigError if a worker would get none."""
    parts: list[dict[str, int]] = [{} for _ in range(workers)]
    turn = 0  # the worker the next left-over battle goes to
    for e in cfg.league.opponents:
        b = cfg.league.battles_of(e)
        for w in range(workers):
            n = b // workers + int((w - turn) % workers < b % workers)
            if n:
                parts[w][e] = n
        turn = (turn + b % workers) % workers
    idle = sum(1 for p in parts if not p)
    if idle:
        total = sum(cfg.league.battles_of(e) for e in cfg.league.opponents)
        raise ConfigError(f"--workers {workers}: the league has {total} battles, so {idle} worker(s) would have "
                          "none: use fewer workers or more league.battles")
    return parts


def connect(address: str) -> bool:
    """Connect to the Ray cluster at ``address`` (``auto``, ``HOST:PORT`` or ``ray://HOST:PORT``) unless Ray is
    already up in this process; True if this call connected (the caller disconnects). A cluster that is not
    there is a one-line ConnectionError at once (Ray's own client waits 30 s)."""
    if ray.is_initialized():
        return False
    if address != "auto":
        host, _, port = address.removeprefix("ray://").rpartition(":")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise ConfigError(f"--address {address!r}: expected auto, HOST:PORT or ray://HOST:PORT")
        try:
            socket.create_connection((host.strip("[]"), int(port)), timeout=5).close()
        except OSError as exc:
            raise ConnectionError(f"no Ray cluster at --address {address}: {exc.strerror or exc}") from None
    try:
        ray.init(address=address, include_dashboard=False, log_to_driver=False)
    except (ConnectionError, RuntimeError, ValueError) as exc:
        raise ConnectionError(f"no Ray cluster at --address {address}: {' '.join(str(exc).split())[:200]}") from None
    return True


def _free_cpus(want: int, wait_s: float = 15.0) -> float:
    """The cluster's free CPUs, once ``want`` are free or after ``wait_s`` seconds (actors just killed, say by a
    trainer closed before, give theirs back a moment later)."""
    end = time.monotonic() + wait_s
    while (cpus := ray.available_resources().get("CPU", 0)) < want and time.monotonic() < end:
        time.sleep(0.2)
    return cpus


class RolloutWorker:
    """One Ray actor: its part of the league (``part``: entry -> battles) and a PPO copy that acts."""

    def __init__(self, cfg: ExperimentConfig, part: dict[str, int], seed: int, td: OpponentPolicy | None) -> None:
        self.cfg = cfg
        self.pool, self.snap = build_pool(cfg, seed, part=part, td=td)
        self.ppo = PPO(self.pool.n_features, self.pool.action_dims, cfg.ppo, seed=seed)  # acts on the driver's weights
        self.obs = self.pool.reset()
        names = list(cfg.league.opponents)
        self.mine = np.array([names.index(e.name) for e in self.pool.entries])

    def shape(self) -> tuple[int, tuple[int, ...], int]:
        """(features, action dims, agents) of its pool."""
        return self.pool.n_features, tuple(self.pool.action_dims), self.pool.n_agents

    def rollout(self, weights: dict[str, np.ndarray], snapshots: list[dict[str, np.ndarray]],
                shares: np.ndarray | None) -> dict[str, Any]:
        """One rollout acting with ``weights`` (the network's state dict): a snapshot drawn for the self-play
        battles, with ``shares`` (every league entry's recent share) the PFSP draw; see ``collect_rollout``."""
        self.snap.load(snapshots[int(self.pool.rng.integers(len(snapshots)))])  # as TankTrainer._pick_snapshot
        self.ppo.acting.load_state_dict({k: torch.from_numpy(np.array(v)) for k, v in weights.items()})
        playing = None
        if shares is not None:
            lc = self.cfg.league
            playing = pfsp_playing(shares, self.pool.rng, lc.play_fraction, lc.play_floor, lc.pfsp_power)[self.mine]
        buf, self.obs, active, ended, t_env = collect_rollout(self.ppo, self.pool, self.obs, playing)
        return {"rollout": asdict(buf), "active": active, "ended": ended, "env_s": t_env}

    def peak_rss_bytes(self) -> int:
        """This process's peak resident memory (Linux: ru_maxrss in KiB)."""
        import resource

        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024

    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Its pool, observations and acting stream (arrays), its pool generator (meta)."""
        arrays = {f"pool.{k}": v for k, v in self.pool.state_dict().items()}
        arrays["obs"] = self.obs
        arrays["act_gen"] = self.ppo.act_gen.get_state().numpy().copy()
        return arrays, {"pool_rng": ck.rng_state(self.pool.rng)}

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        """Restore :meth:`state`."""
        self.pool.load_state_dict(_sub(arrays, "pool."))
        self.obs = np.asarray(arrays["obs"], dtype=np.float32)
        self.ppo.act_gen.set_state(torch.from_numpy(np.array(arrays["act_gen"], dtype=np.uint8)))
        self.pool.rng = ck.rng_from_state(meta["pool_rng"])


class RayTankTrainer(TankTrainer):
    """:class:`~confront.train.ppo_sim.TankTrainer` whose rollouts W Ray actors collect (module docstring)."""

    def __init__(self, cfg: ExperimentConfig, address: str, workers: int = 1, progress: bool = False) -> None:
        self.parts = split_league(cfg, workers)
        self.address = address
        self._own_ray = connect(address)
        self.workers: list[Any] = []
        try:
            cpus = _free_cpus(workers)
            if cpus < workers:  # the actors would wait for CPUs for ever
                raise ConfigError(f"the Ray cluster at {address} has {cpus:g} free CPUs: --workers {workers} needs "
                                  "one each")
            self.cfg = cfg
            # the TD team made (pre-trained, or read from its cache) here once, and sent to the workers
            self._td = td_policy(cfg, progress) if any(e.endswith(":td") for e in cfg.league.opponents) else None
            self._actor = ray.remote(num_cpus=1, max_restarts=0)(RolloutWorker)
            self.workers = [self._start(w) for w in range(workers)]
            shapes = ray.get([w.shape.remote() for w in self.workers])
        except BaseException:
            self.close()
            raise
        n_features, dims = shapes[0][0], shapes[0][1]
        self.n_agents = sum(s[2] for s in shapes)  # the pools' agents, all workers
        self.ppo = PPO(n_features, dims, cfg.ppo, seed=cfg.train.seed,
                       init_logits=skill_logits(tank_space(cfg), cfg.tank.skill_prior))
        self.names = list(cfg.league.opponents)
        self.snapshots: list[dict[str, np.ndarray]] = []
        self.rows: list[dict[str, Any]] = []
        self.updates: list[dict[str, Any]] = []
        self.decisions = 0
        self.elapsed = 0.0
        self.pending: Rollout | None = None
        self.restarts = 0
        self.desc = f"{cfg.name} ppo x{workers}"
        self._take_snapshot()

    def _start(self, w: int) -> Any:
        return self._actor.remote(self.cfg, self.parts[w], worker_seed(self.cfg.train.seed, w), self._td)

    def _pick_snapshot(self) -> None:
        """Each worker draws its own (:meth:`RolloutWorker.rollout`)."""

    def _call(self, method: str, *args: Any) -> list[Any]:
        """``method(*args)`` on every worker, waited for; a worker that died is started again (its seed, new
        battles) and called again, up to MAX_RESTARTS times in a row."""
        refs = [getattr(w, method).remote(*args) for w in self.workers]
        out = []
        for w in range(len(refs)):
            for attempt in range(MAX_RESTARTS + 1):
                try:
                    out.append(ray.get(refs[w]))
                    break
                except ray.exceptions.RayActorError as exc:
                    if attempt == MAX_RESTARTS:
                        raise RuntimeError(f"rollout worker {w} died {attempt + 1} times in a row: "
                                           f"{' '.join(str(exc).split())[:200]}") from None
                    self.restarts += 1
                    click.echo(f"\nnote: rollout worker {w} died ({type(exc).__name__}); starting it again "
                               f"(restart {self.restarts})", err=True)
                    try:
                        ray.kill(self.workers[w])
                    except Exception:  # noqa: BLE001 - it is gone already
                        pass
                    self.workers[w] = self._start(w)
                    refs[w] = getattr(self.workers[w], method).remote(*args)
        return out

    def _collect(self) -> tuple[Rollout, float]:
        """The workers' rollouts with the acting weights, side by side; the slowest worker's env seconds."""
        lc = self.cfg.league
        shares = recent_shares(self.rows, self.names, lc.share_window) if lc.prioritise else None
        weights = ray.put({k: v.detach().numpy().copy() for k, v in self.ppo.acting.state_dict().items()})
        results = self._call("rollout", weights, ray.put(self.snapshots), shares)
        parts = [r["rollout"] for r in results]
        buf = Rollout(**{k: np.concatenate([p[k] for p in parts], axis=0 if k == "last_value" else 1)
                         for k in parts[0]})
        active = np.sum([r["active"] for r in results], axis=0)
        ended = [[row for r in results for row in r["ended"][k]] for k in range(len(active))]
        self._record(active, ended)
        return buf, max(float(r["env_s"]) for r in results)

    def finish(self, run: Run, rows: list[dict[str, Any]], sessions: list[dict[str, Any]]) -> dict[str, Any]:
        out = super().finish(run, rows, sessions)
        out.update(rollout_workers=len(self.workers), rollout_worker_restarts=self.restarts)
        return out

    def close(self) -> None:
        for w in self.workers:
            try:
                ray.kill(w)
            except Exception:  # noqa: BLE001 - gone already
                pass
        self.workers = []
        if hasattr(self, "ppo"):
            self.ppo.close()
        if self._own_ray:
            ray.shutdown()
            self._own_ray = False

    # checkpoint state
    def state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays, meta = self._learner_state()
        for w, (a, m) in enumerate(self._call("state")):
            arrays.update({f"worker{w}.{k}": v for k, v in a.items()})
            meta[f"worker{w}.pool_rng"] = m["pool_rng"]
        meta.update(rollout_workers=len(self.workers), rollout_worker_restarts=self.restarts)
        return arrays, meta

    def load(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        held = meta.get("rollout_workers", 0)
        if held != len(self.workers):
            raise ck.CheckpointError(
                f"this run was trained with {held} rollout workers: resume it with --workers {held}" if held else
                "this run was trained without --address: resume it without --address")
        try:
            self._load_learner(arrays, meta)
            ray.get([w.load.remote(_sub(arrays, f"worker{k}."), {"pool_rng": meta[f"worker{k}.pool_rng"]})
                     for k, w in enumerate(self.workers)])
            self.restarts = int(meta.get("rollout_worker_restarts", 0))
        except (KeyError, ValueError, TypeError, ck.CheckpointError) as exc:
            raise ck.CheckpointError(f"checkpoint does not fit this run's config: {exc}") from None
