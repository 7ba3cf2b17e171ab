"""The scripted robots from Python: ``ScriptedBots`` drives some robots of an :class:`~confront.arena.core.Arena`,
``bot_battle`` plays a battle of them alone.

Usage: ``bots = ScriptedBots(arena, ["SpinBot", None, ...])`` (a name per robot, None = driven by
someone else), then every turn ``bots.commands(cmd)`` fills those robots' rows of ``cmd``; or
``bots.play(turns)`` runs commands, turns and new rounds in compiled code. A new round (``state.round``
changed) clears the per-round memory of that battle's bots by itself.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..core import Arena, thread_pool
from ..kernel_cache import entry
from ..scenarios import Scenario
from .common import M_MATES, M_ROUND_START, M_SIZE, M_STATIC
from .controller import BotState, bots_step, play_range
from .registry import BY_NAME, ROBOTS

__all__ = ["BOT_NAMES", "ADVANCED_BOTS", "ScriptedBots", "bot_kind", "bot_battle", "teammate_masks"]

BOT_NAMES = tuple(r.name for r in ROBOTS)
# AdvancedRobots (TeamRobot included); the others are plain Robots
ADVANCED_BOTS = frozenset(r.name for r in ROBOTS if r.advanced)
# play(): battle chunks per worker thread (a thread on a free core takes more when the other core is busy)
_CHUNKS_PER_THREAD = 4


def teammate_masks(names: list[str | None], teams: list[int]) -> list[int]:
    """Per robot, the robots whose name its ``isTeammate`` accepts (bit j), as the engine names them.

    Battle.createPeers names a robot "class (robot index + 1)" when its class occurs more than once in the
    battle, but lists team members as "class (count of that class so far)": with several robots of one class
    the two disagree, so a leader can take some of its own droids for enemies (MyFirstTeam: the droid at
    battle index 4 is "MyFirstDroid (5)", its team lists "(1)" to "(4)").
    """
    cls = [n or f"?{i}" for i, n in enumerate(names)]
    total = {c: cls.count(c) for c in cls}
    own = [c + (f" ({i + 1})" if total[c] > 1 else "") for i, c in enumerate(cls)]
    listed = [f"{c} ({cls[:i + 1].count(c)})" for i, c in enumerate(cls)]
    masks = []
    for i in range(len(cls)):
        mates = {listed[m] for m in range(len(cls)) if teams[m] == teams[i] and listed[m] != own[i]}
        masks.append(sum(1 << j for j in range(len(cls)) if own[j] == own[i] or own[j] in mates))
    return masks


def bot_kind(name: str | None) -> int:
    """Kind code of a bot name (0 for None)."""
    if name is None:
        return 0
    if name not in BY_NAME:
        raise ValueError(f"unknown bot {name!r}; known: {', '.join(BOT_NAMES)}")
    return BY_NAME[name].kind


class ScriptedBots:
    """Sample-robot behaviour for some robots of an Arena (all battles)."""

    def __init__(self, arena: Arena, names: Sequence[str | None]) -> None:
        if len(names) != arena.n_robots:
            raise ValueError(f"names has {len(names)} entries, the arena has {arena.n_robots} robots")
        self.arena = arena
        self.names = list(names)
        self.kinds = np.array([bot_kind(n) for n in names], dtype=np.int64)
        self._bots = np.flatnonzero(self.kinds != 0)
        own = max((BY_NAME[n].memory for n in self.names if n is not None), default=0)
        self.mem = np.zeros((arena.n_battles, arena.n_robots, M_SIZE + own))
        self.mem[:, :, M_MATES] = teammate_masks(self.names, list(arena.state.team[0]))
        self._apply_flags()
        self._round = arena.state.round.copy()
        self._step_entry: Callable[..., Any] | None = None
        self._play_entry: Callable[..., Any] | None = None
        self._chunk_ranges()
        self.reset()

    def _apply_flags(self) -> None:
        s = self.arena.state
        for i, name in enumerate(self.names):
            if name is None:
                continue
            robot = BY_NAME[name]
            s.is_advanced[:, i] = robot.advanced
            s.adjust_gun_for_body[:, i] = robot.gun_for_body
            droid = robot.droid
            if droid and not s.is_droid[0, i] and (s.time == 0).all():
                s.energy[:, i] += 20.0  # a droid starts with 120 (the round was placed before the flag)
            s.is_droid[:, i] = droid
            s.adjust_radar_for_body[:, i] = False
            s.adjust_radar_for_gun[:, i] = False

    def reset(self, mask: np.ndarray | None = None) -> None:
        """Clear the per-round memory of the masked battles (statics such as Corners' corner stay)."""
        idx = slice(None) if mask is None else np.asarray(mask, dtype=bool)
        keep = self.mem[idx, :, M_STATIC:].copy()
        self.mem[idx] = 0.0
        self.mem[idx, :, M_STATIC:] = keep
        for k, v in M_ROUND_START:
            self.mem[idx, :, k] = v
        self._round[idx] = self.arena.state.round[idx]

    def sync_rounds(self) -> None:
        """Clear the memory of every battle that started a new round since the bots last acted."""
        rnd = self.arena.state.round
        if not np.array_equal(rnd, self._round):
            self.reset(rnd != self._round)

    def state_dict(self) -> dict[str, np.ndarray]:
        """The bots' memory (data only), for checkpoints next to ``Arena.state_dict``."""
        return {"mem": self.mem.copy(), "round": self._round.copy()}

    def load_state_dict(self, d: dict[str, np.ndarray]) -> None:
        """Restore what :meth:`state_dict` wrote."""
        for key, dst in (("mem", self.mem), ("round", self._round)):
            if key not in d:
                raise ValueError(f"bots state dict lacks {key!r}")
            if np.shape(d[key]) != dst.shape:
                raise ValueError(f"bots state {key!r} has shape {np.shape(d[key])}, expected {dst.shape}")
            dst[...] = d[key]

    def commands(self, cmd: np.ndarray) -> np.ndarray:
        """Fill the scripted robots' rows of ``cmd`` (B, R, 5) in place for the next turn."""
        self.sync_rounds()
        cmd[:, self._bots, :4] = np.nan
        cmd[:, self._bots, 4] = 0.0
        if len(self._chunks) > 1:
            workers = self.arena.threads
            futures = [thread_pool(workers).submit(self._run, k, cmd) for k in range(len(self._chunks))]
            for f in futures:
                f.result()
        else:
            self._run(0, cmd)
        return cmd

    def play(self, turns: int, cmd: np.ndarray | None = None) -> int:
        """``turns`` times ``commands(cmd)``, ``arena.step(cmd)``, ``arena.reset(done)``, in compiled code.

        Gives the same states as that loop; battles run in parallel chunks, each its turns in a row. Robots
        without a bot keep their rows of ``cmd`` (default: idle). Returns the robots alive after each turn,
        summed over turns and battles (alive robot-turns).
        """
        if isinstance(turns, bool) or not isinstance(turns, int | np.integer) or turns < 0:
            raise ValueError(f"turns must be a non-negative integer, got {turns!r}")
        a = self.arena
        if cmd is None:
            cmd = a.idle_commands()
        if cmd.shape != (a.n_battles, a.n_robots, 5) or cmd.dtype != np.float64 or not cmd.flags.c_contiguous:
            raise ValueError(f"cmd must be a C-contiguous float64 array of shape ({a.n_battles}, {a.n_robots}, 5)")
        nb, workers = a.n_battles, a.threads
        size = -(-nb // (_CHUNKS_PER_THREAD * workers)) if nb >= 2 * workers and workers > 1 else nb
        bounds = [(lo, min(nb, lo + size)) for lo in range(0, nb, size)]
        args = (self._round, *a.bundles, cmd, a.settings, a.scratch)

        def run(lo: int, hi: int) -> int:
            call = (lo, hi, int(turns), BotState(self.kinds, self.mem, np.zeros(4)), *args)
            if self._play_entry is None:
                self._play_entry = entry(play_range, *call)
            return int(self._play_entry(*call))

        if len(bounds) == 1:
            return run(*bounds[0])
        return sum(f.result() for f in [thread_pool(workers).submit(run, lo, hi) for lo, hi in bounds])

    def _chunk_ranges(self) -> None:
        """bots_step's battle ranges (one per worker thread), each with its own scratch."""
        nb, workers = self.arena.n_battles, self.arena.threads
        size = -(-nb // workers) if nb >= 64 and workers > 1 else nb
        self._chunks = [(lo, min(nb, lo + size), BotState(self.kinds, self.mem, np.zeros(4)))
                        for lo in range(0, nb, size)]
        self._step_entry = None
        self._play_entry = None

    def _run(self, k: int, cmd: np.ndarray) -> None:
        """bots_step on battle range k."""
        lo, hi, bots = self._chunks[k]
        a = self.arena
        robots, _, _, radar, _ = a.bundles
        call = (lo, hi, bots, robots, radar, cmd, float(a.scenario.width), float(a.scenario.height))
        if type(cmd) is not np.ndarray or cmd.dtype != np.float64 or cmd.ndim != 3 or not cmd.flags.c_contiguous \
                or not cmd.flags.writeable:
            bots_step(*call)  # another array type: numba's dispatch (a compile for each new type)
            return
        if self._step_entry is None:
            self._step_entry = entry(bots_step, *call)
        self._step_entry(*call)


def bot_battle(names: list[str], rounds: int, seed: int = 0, n_battles: int = 20, turns_after_end: int = 150,
               scenario: Scenario | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Scripted robots over ``rounds`` rounds (spread over parallel battles); a free-for-all by default.

    ``names``: one bot per robot of ``scenario`` (default: a melee of ``len(names)`` single robots).
    Returns the score parts (R, 6) and placements (R, 3) summed over the rounds, robot order as
    ``names``; the score share of robot i is ``parts[i].sum() / parts.sum()``.
    """
    from ..scenarios import get_scenario

    if rounds < 1:
        raise ValueError(f"rounds must be >= 1, got {rounds}")
    n_battles = min(n_battles, rounds)
    base = scenario if scenario is not None else get_scenario("melee").replace(teams=tuple(1 for _ in names))
    if base.n_robots != len(names):
        raise ValueError(f"scenario {base.name} has {base.n_robots} robots, got {len(names)} names")
    sc = base.replace(turns_after_end=turns_after_end, max_turns=100000)
    arena = Arena(sc, n_battles, seed=seed)
    bots = ScriptedBots(arena, list(names))
    quota = np.full(n_battles, rounds // n_battles)
    quota[: rounds % n_battles] += 1
    played = np.zeros(n_battles, dtype=np.int64)
    cmd = arena.idle_commands()
    s = arena.state
    while (played < quota).any():
        bots.commands(cmd)
        arena.step(cmd)
        done = s.done.copy()
        if done.any():
            played += done
            again = done & (played < quota)
            if again.any():
                arena.reset(again)
    return s.score_total.sum(axis=0), s.placements_total.sum(axis=0)

