"""The batched Robocode 1.9.3.9 simulator: ``Arena(scenario, n_battles, seed)``.

Usage::

    arena = Arena("4v4", n_battles=256, seed=1)      # every battle starts its first round
    cmd = np.full((256, 8, 5), np.nan); cmd[..., 4] = 0.0
    arena.step(cmd)                                  # one Robocode turn in every battle not done
    arena.reset(arena.state.done)                    # next round where the round is over

``arena.state.*`` are live views: ``reset`` clears ``done``, so copy a mask you still need afterwards.

Commands ``(B, R, 5)`` float64, loaded at the start of the turn like an AdvancedRobot's ``set*``
calls: 0 move distance (px, + ahead), 1 body turn, 2 gun turn, 3 radar turn (radians, + clockwise),
4 fire power (0 = no fire; clamped to [0.1, 3] and to the energy; refused while the gun is hot).
NaN in 0-3 keeps the robot's remaining value. A disabled robot (energy 0) cannot set move/body.

State: ``arena.state.<name>`` (NumPy views, battle axis first; B battles, R robots, K bullet slots).

Per battle ``(B,)``: ``rng`` (java.util.Random 48-bit state), ``time`` (turn in the round, 0 at the
start), ``round`` (rounds started), ``inactive_turns``, ``inactivity_energy``, ``decided`` (at most
one team left), ``end_timer`` (turns run since decided, the deciding turn counts 1), ``done``
(round over: decided and ``turns_after_end`` more turns run, or ``max_turns`` reached),
``n_bullets`` (entries in the bullet list).

Per robot ``(B, R)``: ``x``, ``y`` (centre; y up), ``heading``, ``gun_heading``, ``radar_heading``
(radians in [0, 2pi), 0 = north, clockwise), ``velocity``, ``energy``, ``gun_heat``, ``box_x``,
``box_y`` (centre of the collision box; differs from x, y after an at-fault ram, as in Robocode),
``alive`` (false once dead; a disabled robot is alive with energy 0), remaining command values
``distance_remaining``, ``body_turn_remaining``, ``gun_turn_remaining``, ``radar_turn_remaining``,
settings ``max_velocity``, ``max_turn_rate``, ``fire_assist`` (angle for a plain Robot's assisted
shot this turn, NaN = none; consumed at load), ``scan_request`` (a ``scan()`` call: the radar scans
this turn even if nothing moved; consumed at load), flags ``team`` (int), ``is_advanced`` (wall damage),
``is_leader`` (200 energy, its death costs team-mates 30), ``is_droid`` (120 energy, no radar),
``adjust_gun_for_body``, ``adjust_radar_for_body``, ``adjust_radar_for_gun``; internal
``overdriving``, ``in_collision`` (at fault last turn: no body turn), ``turned_radar_with_gun``,
``winner``.

Events of the last turn ``(B, R)``: ``ev_hit_wall`` / ``ev_hit_wall_bearing``, ``ev_hit_robot``
(index of the robot hit, -1 none) / ``ev_hit_robot_bearing`` / ``ev_at_fault``,
``ev_hit_by_bullet`` (count) / ``ev_hit_by_bullet_bearing`` / ``ev_hit_by_bullet_heading`` (the last bullet's
own heading, as HitByBulletEvent.getHeading() reports it); every bullet's in the engine's bullet order:
``ev_hit_by_bullets`` (rows, at most ``HIT_BY_BULLET_SLOTS``) / ``ev_hit_by_bullet_{k}_bearing`` /
``ev_hit_by_bullet_{k}_heading``; ``ev_bullet_hit`` (count),
``ev_bullet_missed`` (count), ``ev_fired``, ``ev_died``.

Radar ``(B, R, R)``: ``scanned[b, i, j]`` robot i's radar swept robot j this turn (Robocode's
ScannedRobotEvent; its data equals the true end-of-turn state of j, so readers use ``x[b, j]`` etc.),
``scan_time[b, i, j]`` the turn of the last such scan this round (-1 never), ``scan_order[b, i]`` robot i's
robot list of its last scan in the engine's random order (``performScan(getRobotsAtRandom())``: the order its
ScannedRobotEvents were queued in; index order where fewer than two robots were scanned).

Scores: ``score`` ``(B, R, 6)`` this round and ``score_total`` summed over decided rounds (copied at
the deciding turn, as Robocode does), parts in :data:`confront.arena.state.SCORE_PARTS` order
(survival, last_survivor, bullet_damage, bullet_kill_bonus, ram_damage, ram_kill_bonus);
``damage_ledger[b, i, j]`` damage i did to j this round (bullets + 0.6 per ram, for kill bonuses);
``placements`` / ``placements_total`` ``(B, R, 3)`` 1sts, 2nds, 3rds.

Bullets ``(B, K)``: Robocode's bullet list, slots ``b_list[b, :n_bullets]`` in list order:
``b_x``, ``b_y``, ``b_last_x``, ``b_last_y``, ``b_heading``, ``b_power``, ``b_vx``, ``b_vy`` (step per
turn), ``b_owner``,
``b_victim``, ``b_state`` (0 free, 1 fired, 2 moving, 3 hit robot, 4 hit bullet, 5 hit wall,
6 robot explosion), ``b_frame``, ``b_has_line``.

Seeds: battle b's generator is ``new java.util.Random(seed + b)``, used for start positions and,
with ``order="engine"``, every random processing order exactly as the engine draws them.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from functools import cache
from numbers import Integral
from typing import Any

import numpy as np

from confront.config import ConfigError

from . import kernels as K
from .kernel_cache import entry
from .rules import java_next_double, java_seed
from .scenarios import Scenario, get_scenario
from .state import FIELDS, HIT_BY_BULLET_SLOTS, ArenaState, allocate

__all__ = ["Arena", "ORDER_MODES", "thread_pool", "run_parallel", "default_threads"]

ORDER_MODES = {"engine": 0, "shuffle": 1, "fixed": 2}
_PARALLEL_MIN_BATTLES = 16


@cache
def thread_pool(workers: int) -> ThreadPoolExecutor:
    """Shared worker threads for the GIL-free kernel."""
    return ThreadPoolExecutor(max_workers=workers, thread_name_prefix="arena")


def run_parallel(executor: ThreadPoolExecutor, fn: Callable[..., Any], calls: Sequence[tuple[Any, ...]],
                 workers: int) -> list[Any]:
    """``[fn(*c) for c in calls]``, run by this thread and up to ``workers - 1`` of the executor's threads,
    each taking the next call from the one list (``fn`` must release the GIL, as the compiled kernels do):
    one hand-over per use, and the calling thread works instead of waiting."""
    out: list[Any] = [None] * len(calls)
    order = itertools.count()

    def drain() -> None:
        while (i := next(order)) < len(calls):
            out[i] = fn(*calls[i])

    helpers = [executor.submit(drain) for _ in range(min(workers, len(calls)) - 1)]
    try:
        drain()
    finally:
        for f in helpers:
            f.result()
    return out


MAX_BATTLES = 1 << 16  # battles of one Arena


def _whole(name: str, value: Any, lo: int, hi: int) -> int:
    """``value`` as an int if it is a whole number (not a bool, not 2.5) in [lo, hi]; a ValueError naming it else."""
    if isinstance(value, bool) or not isinstance(value, Integral) or not lo <= int(value) <= hi:
        raise ValueError(f"{name} must be a whole number from {lo} to {hi}, got {str(value)[:40]}")
    return int(value)


def default_threads() -> int:
    """Threads for batched steps: CONFRONT_THREADS, else the CPUs this process may use."""
    env = os.environ.get("CONFRONT_THREADS")
    if env is not None:
        if not env.isascii() or not env.isdigit() or not 1 <= int(env) <= 4096:
            raise ConfigError(f"CONFRONT_THREADS must be a whole number from 1 to 4096, got {env[:40]!r}")
        return int(env)
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


class Arena:
    """Many independent Robocode battles of one scenario, advanced together one turn per ``step``."""

    def __init__(self, scenario: Scenario | str, n_battles: int = 1, seed: int = 0, order: str = "engine",
                 threads: int | None = None) -> None:
        if isinstance(scenario, str):
            scenario = get_scenario(scenario)
        if order not in ORDER_MODES:
            raise ValueError(f"order must be one of {sorted(ORDER_MODES)}, got {order!r}")
        self.scenario = scenario
        self.order = order
        self.threads = default_threads() if threads is None else _whole("threads", threads, 1, 4096)
        self.state: ArenaState = allocate(scenario, _whole("n_battles", n_battles, 1, MAX_BATTLES))
        b, r = self.n_battles, self.n_robots
        self.params = np.array([scenario.width, scenario.height, scenario.gun_cooling_rate,
                                scenario.inactivity_time, scenario.max_turns, scenario.turns_after_end,
                                ORDER_MODES[order]], dtype=np.float64)
        if scenario.initial_positions is not None:
            fixed = np.array(scenario.initial_positions, dtype=np.float64)
            fixed[:, 2] = np.radians(fixed[:, 2])
            self.settings = K.Settings(self.params, fixed, True)
        else:
            self.settings = K.Settings(self.params, np.zeros((r, 3)), False)
        width = max(r, self.state.n_bullet_slots) + 1
        self.scratch = K.Scratch(np.zeros((b, 6, width), dtype=np.int32), np.zeros((b, 9, r), dtype=np.float64))
        self.scratch.floats[:, [K.TRIG_RADAR, K.TRIG_BODY]] = np.nan  # no sin/cos kept yet (kernels._sin_cos)
        # the kernels' state: robots, battles, bullets, radar, scores (views of ``state``'s packed arrays)
        self.bundles = self.state.bundles()
        self._step_entry: Callable[..., Any] | None = None
        self._reset_entry: Callable[..., Any] | None = None
        self.seed(seed)
        self.reset()

    @property
    def n_battles(self) -> int:
        return self.state.n_battles

    @property
    def n_robots(self) -> int:
        return self.state.n_robots

    def seed(self, seed: int) -> None:
        """Seed every battle's java.util.Random with ``seed + b`` (a Java long) and start the battles."""
        seed = _whole("seed", seed, -(2**63), 2**63 - self.n_battles)
        self.state.rng[:] = [java_seed(seed + b) for b in range(self.n_battles)]
        self._battle_start(np.arange(self.n_battles))

    def _battle_start(self, idx: np.ndarray) -> None:
        """The engine draws 3 doubles per entry of a fixed initial-positions string (Battle.computeInitialPositions)."""
        if not self.settings.has_fixed:
            return
        for b in idx:
            r = int(self.state.rng[b])
            for _ in range(3 * self.n_robots):
                r, _d = java_next_double(r)
            self.state.rng[b] = r

    def _mask(self, mask: np.ndarray | None) -> np.ndarray:
        if mask is None:
            return np.arange(self.n_battles)
        m = np.asarray(mask)
        if m.dtype != np.bool_ or m.shape != (self.n_battles,):
            raise ValueError(f"mask must be a bool array of shape ({self.n_battles},), got {m.dtype} {m.shape}")
        return np.flatnonzero(m)

    def reset(self, mask: np.ndarray | None = None) -> None:
        """Start a new round in the masked battles (all if None); totals carry over."""
        idx = self._mask(mask).astype(np.int64)
        if idx.size:
            args = (idx, *self.bundles, self.settings)
            if self._reset_entry is None:
                self._reset_entry = entry(K.reset_many, *args)
            self._reset_entry(*args)

    def new_battle(self, mask: np.ndarray | None = None) -> None:
        """Clear the masked battles' totals and round counters, then start a round."""
        idx = self._mask(mask)
        s = self.state
        for name in ("score_total", "placements_total", "round", "inactivity_energy"):
            s.arrays[name][idx] = 0
        self._battle_start(idx)
        self.reset(mask)

    def step(self, commands: np.ndarray) -> None:
        """Advance every battle that is not done by one turn."""
        cmd = commands if type(commands) is np.ndarray and commands.dtype == np.float64 else \
            np.asarray(commands, dtype=np.float64)
        if cmd.shape != (self.n_battles, self.n_robots, 5):
            raise ValueError(f"commands must have shape ({self.n_battles}, {self.n_robots}, 5), got {cmd.shape}")
        if not cmd.flags.c_contiguous:
            cmd = np.ascontiguousarray(cmd)
        if not np.isfinite(cmd[..., 4].sum()):
            raise ValueError("commands[..., 4] (fire power) must be finite; use 0 for no fire")
        args = (*self.bundles, cmd, self.settings, self.scratch)
        b, workers = self.n_battles, self.threads
        if self._step_entry is None:
            self._step_entry = entry(K.step_range, 0, b, *args)
        if b >= _PARALLEL_MIN_BATTLES and workers > 1:
            size = -(-b // workers)
            run_parallel(thread_pool(workers), self._step_entry,
                         [(lo, min(b, lo + size), *args) for lo in range(0, b, size)], workers)
        else:
            self._step_entry(0, b, *args)

    def idle_commands(self) -> np.ndarray:
        """Commands that keep every remaining value and do not fire."""
        cmd = np.full((self.n_battles, self.n_robots, 5), math.nan)
        cmd[..., 4] = 0.0
        return cmd

    def state_dict(self) -> dict[str, np.ndarray]:
        """Copies of every state array by name (data only; includes the generators' states)."""
        return {name: np.array(self.state.arrays[name], copy=True) for name in FIELDS}

    def load_state_dict(self, d: dict[str, np.ndarray]) -> None:
        """Restore the arrays written by :meth:`state_dict` (same scenario and battle count).

        A dict saved before ``ev_hit_by_bullet_heading`` existed gets it as the arena rebuilt it then
        (bearing + body heading - pi); one saved before the per-bullet rows (``ev_hit_by_bullets``) gets one
        row, the last bullet's, as the bots read it then (one HitByBulletEvent a turn)."""
        if "ev_hit_by_bullet_heading" not in d and "ev_hit_by_bullet_bearing" in d and "heading" in d:
            d = dict(d, ev_hit_by_bullet_heading=np.asarray(d["ev_hit_by_bullet_bearing"]) + np.asarray(d["heading"])
                     - math.pi)
        if "ev_hit_by_bullets" not in d and "ev_hit_by_bullet" in d and "ev_hit_by_bullet_heading" in d:
            count = np.asarray(d["ev_hit_by_bullet"])
            rows = {"ev_hit_by_bullets": np.minimum(count, 1).astype(np.float64)}
            for k in range(HIT_BY_BULLET_SLOTS):
                for f in ("bearing", "heading"):
                    last = np.asarray(d[f"ev_hit_by_bullet_{f}"], dtype=np.float64)
                    rows[f"ev_hit_by_bullet_{k}_{f}"] = last.copy() if k == 0 else np.zeros_like(last)
            d = dict(d, **rows)
        if "scan_order" not in d and "scanned" in d:  # saved before scan_order: the scans in index order
            d = dict(d, scan_order=np.broadcast_to(np.arange(self.n_robots, dtype=np.int32),
                                                   np.asarray(d["scanned"]).shape))
        for name in FIELDS:
            if name not in d:
                raise ValueError(f"state dict lacks {name!r}")
            dst = self.state.arrays[name]
            src = np.asarray(d[name])
            if src.shape != dst.shape:
                raise ValueError(f"state {name!r} has shape {src.shape}, expected {dst.shape}")
            dst[...] = src
