"""The batched multi-agent SMDP team environment over :class:`confront.arena.core.Arena` (paper §2.2, §6.1).

``TeamBattleEnv(scenario, n_battles, seed, opponents)`` runs B battles of one scenario. Every robot is
either a *learning tank* (driven by the caller's actions: the paper's four macro moves, optionally x 3
fire powers, each held for T turns; its gun and radar follow :mod:`confront.arena.control`'s fixed
controller) or a *scripted bot* (:mod:`confront.arena.bots`, commands every turn) or a *technique robot*
(:mod:`confront.arena.tech`: RamHeadOn, ..., SurfAS, RiskGF, a decision every turn). Team 0 is always
learning; the other teams follow ``opponents`` (``"td"`` = learning tanks whose actions the caller also
supplies, e.g. a TD team; a bot name = that sample robot or technique robot).

Battles: the technique robots keep memory per round and per battle (GuessFactor visit counts, where enemy
bullets hit them, virtual-gun hit rates), as a Java robot keeps static fields. A battle is
``config.rounds_per_battle`` rounds (35: RoboRumble's battle) of a battle row: its memory survives its rounds'
ends (``auto_reset``, ``restart``) and is cleared when the row's next battle starts, or at ``reset``.

``step(actions)`` takes (B, R) ints (ignored for scripted and dead robots), runs T turns and returns a
:class:`StepResult`: observations after the step (discrete state (B, R), features (B, R, F), target
(B, R)), per-turn rewards (B, R, T) of Eq. 35 against each turn's target, ``terminated`` (B, R): the
robot is dead or its round is over, ``round_done`` (B,) and ``truncated`` (B,) (round stopped by
``max_turns`` rather than decided). Rounds that end are reset individually at the end of the step
(``auto_reset``); the returned observations are then the new round's first ones, the terminal ones are
in ``final_discrete`` / ``final_features``, and ``round_end`` carries the ended rounds' score parts.
``info``: ``score`` (B, R, 6) this round's parts so far, ``score_total`` (B, R, 6) over decided rounds,
``score_parts`` (their names, Robocode's order).

Speed: one compiled kernel runs the T turns (controller, scripted bots, technique robots, the arena's turn,
rewards) and
the observations; with 8+ battles and several numba threads, battle ranges run on a thread pool.
Observations equal :func:`confront.arena.observe.observe`'s; the controller equals
:func:`confront.arena.control.gun_radar_commands` (tested).

What a robot knows (``observation.sensing``, default ``"scanned"``): the env keeps, per robot, each
enemy's position and energy at its last radar scan this round (``memory`` (B, 3, R, R), filled from the
arena's scan events after every turn; known while the enemy lives and ``scan_time`` >= 0). Targets, the
state, the features, the rewards' target and the gun/radar controller all use it, as the exported
PolicyBot does in the real engine. So a round's first decision (turn 1, before any scan) sees no target,
in both.

Default T = 10 turns: the paper gives no value; a 45-degree turn takes 5 turns at rest and a
100 px move about 16, so 10 turns lets each macro move show its effect while keeping decisions frequent.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Literal

import numba
import numpy as np

from .bots import BOT_NAMES, BotState, ScriptedBots
from .control import N_MOVES, ControlConfig, move_commands, set_adjustments
from .core import Arena, run_parallel
from .kernel_cache import entry
from .observe import SENSING, TARGET_RULES, ObservationConfig, field_diagonal, observe, team_rows
from .replay import Replay, new_replay, record_frame
from .scenarios import SAMPLE_TEAMS, Scenario, get_scenario, opponent_members
from .smdp_kernel import Brains, Outputs, Senses, Tanks, Views, prepare_actions, smdp_turns
from .state import SCORE_PARTS
from .tank import KNOWLEDGE_FEATURES, MEMORY_ROWS, TankSpace, action_table, tank_view_kernel
from .tech import TECH_ROBOTS, TechBots, knowledge_kernel, no_tech_state

Reward = Literal["eq35", "score"]  # Eq. 35 per turn, or the change of the team's score margin

__all__ = ["SMDPConfig", "TeamBattleEnv", "StepResult", "RoundEnd", "resolve_drivers", "LEARNER", "REWARDS",
           "kernel_pool", "call_kernel"]

LEARNER = "td"  # opponents value meaning "learning tanks driven by the caller"
REWARDS = {"eq35": 0, "score": 1}  # per-turn reward: Eq. 35 against the target, or the team's score margin


@dataclass(frozen=True)
class SMDPConfig:
    """SMDP step length, action set, observation and controller settings."""

    turns_per_step: int = 10  # T
    fire_power_actions: bool = False  # actions = 4 moves x len(fire_powers) powers
    fire_powers: tuple[float, ...] = (1.0, 2.0, 3.0)
    auto_reset: bool = True
    observation: ObservationConfig = field(default_factory=ObservationConfig)
    control: ControlConfig = field(default_factory=ControlConfig)
    reward: Reward = "eq35"
    tank: TankSpace | None = None  # the tank view and tank actions (confront.arena.tank) instead of the paper's
    rounds_per_battle: int = 35  # rounds of one battle: the technique robots' battle memory lives that long

    def __post_init__(self) -> None:
        if not isinstance(self.turns_per_step, int) or self.turns_per_step < 1:
            raise ValueError(f"turns_per_step must be an integer >= 1, got {self.turns_per_step!r}")
        if isinstance(self.rounds_per_battle, bool) or not isinstance(self.rounds_per_battle, int) \
                or self.rounds_per_battle < 1:
            raise ValueError(f"rounds_per_battle must be an integer >= 1, got {self.rounds_per_battle!r}")
        if not self.fire_powers or any(not 0.1 <= p <= 3.0 for p in self.fire_powers):
            raise ValueError(f"fire_powers must be non-empty values in [0.1, 3], got {self.fire_powers!r}")
        if self.reward not in REWARDS:
            raise ValueError(f"reward must be one of {', '.join(REWARDS)}, got {self.reward!r}")
        if self.tank is not None and self.observation.sensing != "scanned":
            raise ValueError("the tank view needs sensing='scanned' (what a real robot knows)")

    @property
    def paper_actions(self) -> int:
        """4 moves, or 4 moves x fire powers; action a = power_index * 4 + move."""
        return N_MOVES * (len(self.fire_powers) if self.fire_power_actions else 1)

    @property
    def n_actions(self) -> int:
        """Actions of a learning tank: the tank actions' joint count, or the paper's."""
        return self.tank.n_actions if self.tank is not None else self.paper_actions


@dataclass
class RoundEnd:
    """Rounds that ended in a step (rows where ``mask``): this round's score parts and placements."""

    mask: np.ndarray  # (B,) bool
    score: np.ndarray  # (B, R, 6) in SCORE_PARTS order
    placements: np.ndarray  # (B, R, 3)
    turns: np.ndarray  # (B,) turns played in the round
    decided: np.ndarray  # (B,) at most one team left (False: stopped by max_turns)
    alive: np.ndarray  # (B, R) robots alive at the end

    def team_scores(self, team: np.ndarray, n_teams: int) -> np.ndarray:
        """(B, T, 6) score parts per team."""
        out = np.zeros((self.score.shape[0], n_teams, self.score.shape[2]))
        for k in range(n_teams):
            out[:, k] = self.score[:, team == k].sum(axis=1)
        return out


@dataclass
class StepResult:
    """What :meth:`TeamBattleEnv.step` returns (see the module docstring)."""

    discrete: np.ndarray  # (B, R) int64
    features: np.ndarray  # (B, R, F) float32
    target: np.ndarray  # (B, R) int64
    rewards: np.ndarray  # (B, R, T) float64
    terminated: np.ndarray  # (B, R) bool
    round_done: np.ndarray  # (B,) bool
    truncated: np.ndarray  # (B,) bool
    active: np.ndarray  # (B, R) bool: a learning tank alive at the start of the step (its transition counts)
    final_discrete: np.ndarray | None = None  # terminal observations of ended rounds (rows where round_done)
    final_features: np.ndarray | None = None
    round_end: RoundEnd | None = None
    info: dict[str, Any] = field(default_factory=dict)


def resolve_drivers(scenario: Scenario, opponents: str | list[str] | tuple[str, ...] | None) -> list[str | None]:
    """Per-robot driver: None = learning tank, or a bot name (a sample robot or a technique robot). Team 0 always
    learns.

    ``opponents``: None = the scenario's default; one name for every robot of the other teams (a sample team,
    ``"MyFirstTeam"``, fills each of them with its leader and droids); or one name per robot of the other teams
    (in robot order). ``"td"`` means learning tanks.
    """
    others = scenario.n_robots - scenario.teams[0]
    if opponents is None:
        opponents = scenario.opponents
    names = opponent_members(scenario, opponents) if isinstance(opponents, str) else list(opponents)
    if len(names) != others:
        raise ValueError(f"opponents has {len(names)} entries, the other teams have {others} robots")
    for n in names:
        if n != LEARNER and n not in BOT_NAMES and n not in TECH_ROBOTS:
            raise ValueError(f"unknown opponent {n!r}; use {LEARNER!r}, one of {', '.join(BOT_NAMES)}, a sample "
                             f"team ({', '.join(SAMPLE_TEAMS)}) or a technique robot ({', '.join(TECH_ROBOTS)})")
    return [None] * scenario.teams[0] + [None if n == LEARNER else n for n in names]


class TeamBattleEnv:
    """B battles of one scenario as a multi-agent SMDP (all robots' observations and rewards at once)."""

    def __init__(
        self,
        scenario: Scenario | str,
        n_battles: int = 1,
        seed: int = 0,
        opponents: str | list[str] | tuple[str, ...] | None = None,
        config: SMDPConfig | None = None,
        order: str = "engine",
        opponent_actions: Literal["same", "paper"] = "same",
    ) -> None:
        """``opponent_actions``: caller-driven opponents ("td") act in the learners' action space ("same") or
        in the paper's 4 (x powers) macro moves ("paper", e.g. a TD team beside tank-action learners)."""
        self.scenario = get_scenario(scenario) if isinstance(scenario, str) else scenario
        self.config = config or SMDPConfig()
        self.arena = Arena(self.scenario, n_battles, seed=seed, order=order)
        self.drivers = resolve_drivers(self.scenario, opponents)
        self.learner = np.array([d is None for d in self.drivers])
        self.team = np.asarray(self.scenario.team_ids(), dtype=np.int64)
        samples = [d if d in BOT_NAMES else None for d in self.drivers]
        self.bots = ScriptedBots(self.arena, samples) if any(samples) else None
        techs = [d if d in TECH_ROBOTS else None for d in self.drivers]
        self.tech = TechBots(self.arena, techs, self.config.rounds_per_battle) if any(techs) else None
        set_adjustments(self.arena, self.learner)
        self.field = (float(self.scenario.width), float(self.scenario.height))
        self.max_distance = self.config.observation.max_distance or field_diagonal(*self.field)
        self._cmd = self.arena.idle_commands()
        self._powers = np.asarray(self.config.fire_powers, dtype=np.float64)
        self._last: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.recording: tuple[Replay, int] | None = None  # the replay being recorded and its battle
        b, r = self.n_battles, self.n_robots
        if opponent_actions not in ("same", "paper"):
            raise ValueError(f"opponent_actions must be 'same' or 'paper', got {opponent_actions!r}")
        self._move = np.zeros((b, r, 5))  # distance, body turn, 1 = turn relative to the target, lead (LEADS), surf
        self._power = np.zeros((b, r))
        self._chosen = np.full((b, r), -1, dtype=np.int64)  # the step's chosen target robot (-1: by rule)
        tank = self.config.tank
        self._tables, self._space, self._n_act = _action_tables(self.config, self.learner, self.team,
                                                                opponent_actions)
        k = tank.enemy_slots if tank is not None else 1
        self._slots = np.full((b, r, k), -1, dtype=np.int64)  # which robot fills each enemy slot of the view
        self._memory = np.zeros((b, MEMORY_ROWS, r, r))  # each robot at each robot's last scan of it (tank.py)
        self._mates = np.zeros((b, 3, r))  # x, y, energy of every robot one turn ago (team messages, tank.py)
        self._mates_ok = np.zeros(b, dtype=np.bool_)  # False in a round's first turn: no message yet
        self._turn_buf = np.zeros((4, b, r))  # per turn: target, own energy, target energy, live
        self._brain_cmd = np.zeros((b, r, 5))  # the commands the tanks' brains proposed this turn
        c = self.config.control
        ctrl = np.array([c.radar_overshoot, c.aim_tolerance, c.power_near, c.power_mid, c.power_far,
                         c.near_distance, c.far_distance, float(c.fire), float(REWARDS[self.config.reward])])
        self.tanks = Tanks(self.learner, self._move, self._power, self._chosen, ctrl,
                            TARGET_RULES[self.config.observation.target], self.config.observation.reward_guard,
                            SENSING[self.config.observation.sensing])
        self.senses = Senses(self._memory, self._mates, self._mates_ok)
        self.brains = _brains(self.arena, self.config.tank, np.isin(self._space, (0, 1) if opponent_actions == "same"
                                                                      else (0,)), self.team,
                              self.config.rounds_per_battle)
        threads = numba.get_num_threads()
        chunks = threads if b >= _PARALLEL_MIN_BATTLES and threads > 1 else 1
        size = -(-b // chunks)
        self._ranges = [(lo, min(b, lo + size)) for lo in range(0, b, size)]
        # each thread needs its own bots scratch (the bots' ``rem``)
        kinds = self.bots.kinds if self.bots is not None else np.zeros(r, np.int64)
        mem = self.bots.mem if self.bots is not None else np.zeros((b, r, 1))
        self._bot_states = [BotState(kinds, mem, np.zeros(4)) for _ in self._ranges]
        # and its own technique robots' hit scratch
        self._tech_states = [self.tech.kernel_state() if self.tech is not None else no_tech_state(r)
                             for _ in self._ranges]
        # and its own learning tanks' technique brains (tank skills: the knowledge block with tank.knowledge)
        knows = bool(self.config.tank is not None and self.config.tank.knowledge and self.brains is not None)
        self._brain_states = [Brains(self.brains.kernel_state() if self.brains is not None else no_tech_state(r),
                                     self._brain_cmd, knows) for _ in self._ranges]
        self._entry: Callable[..., int] | None = None
        # robots whose tank view is computed (a pool sets its caller-driven robots: nobody reads a bot's view)
        self.view_robots = np.ones(r, dtype=np.bool_)
        # robots whose paper observation (target, discrete state, paper features) is computed; the others get
        # target -1, state 0, features 0 (a pool sets the robots its opponent policies read)
        self.paper_robots = np.ones(r, dtype=np.bool_)
        self._group = 16

    @property
    def battle_group(self) -> int:
        """Battles the kernel steps together, turn by turn (their arrays stay in cache): results do not depend on
        it, speed does (16 was fastest of 4-32 on 256 and 1024 battles)."""
        return self._group

    @battle_group.setter
    def battle_group(self, value: int) -> None:
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
            raise ValueError(f"battle_group must be a positive integer, got {value!r}")
        self._group = int(value)

    # ------------------------------------------------------------------ sizes
    @property
    def n_battles(self) -> int:
        """B."""
        return self.arena.n_battles

    @property
    def n_robots(self) -> int:
        """R."""
        return self.arena.n_robots

    @property
    def n_actions(self) -> int:
        """Actions per learning tank."""
        return self.config.n_actions

    @property
    def n_features(self) -> int:
        """Feature vector length F (the tank view's with tank actions, else the paper's)."""
        tank = self.config.tank
        return tank.n_features if tank is not None else self.config.observation.n_features

    @property
    def action_dims(self) -> tuple[int, ...]:
        """Sizes of the action heads whose mixed-radix product is the joint action (tank actions: 5 heads)."""
        tank = self.config.tank
        return tank.dims if tank is not None else (self.n_actions,)

    @property
    def turns_per_step(self) -> int:
        """T."""
        return self.config.turns_per_step

    @property
    def completed_battles(self) -> np.ndarray:
        """(B,) battles of ``rounds_per_battle`` rounds each battle row has finished since :meth:`reset`."""
        s = self.arena.state
        return (s.round - 1 + s.done) // self.config.rounds_per_battle

    # ------------------------------------------------------------------ observations
    def observe(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(target, discrete, features) of the current state for every robot (features: the tank view with
        tank actions, whose enemy slot maps then go to ``slots``)."""
        shape = (self.n_battles, self.n_robots)
        target, disc = np.empty(shape, np.int64), np.empty(shape, np.int64)
        feats = np.empty(shape + (self.n_features,), np.float32)
        # the same (contiguous) array types as for a step's reset rows: one compiled version of each kernel
        self._observe_rows(np.arange(self.n_battles), target, disc, feats)
        return target, disc, feats

    def _mask_views(self, view: np.ndarray, slots: np.ndarray) -> None:
        """Zero the tank views (no slots) of the robots not in ``view_robots``, as the kernel leaves them."""
        off = ~self.view_robots
        if off.any():
            view[:, off] = 0.0
            slots[:, off] = -1

    def _observe_rows(self, rows: np.ndarray, target: np.ndarray, disc: np.ndarray, feats: np.ndarray) -> None:
        """:meth:`observe` of the battles ``rows`` only, written into those rows of target, disc and feats
        (and of ``slots``)."""
        s = self.arena.state
        x, y, h, e, alive, seen = s.x[rows], s.y[rows], s.heading[rows], s.energy[rows], s.alive[rows], \
            s.scan_time[rows]
        memory = self._memory[rows]
        t, d, f = observe(x, y, h, e, alive, self.team, self.field, self.config.observation, memory, seen)
        off = ~self.paper_robots
        if off.any():  # as the kernel leaves them
            t[:, off], d[:, off], f[:, off] = -1, 0, 0.0
        target[rows], disc[rows] = t, d
        tank = self.config.tank
        if tank is None:
            feats[rows] = f
            return
        view = np.empty(x.shape + (tank.n_features,), np.float32)
        slots = np.empty(x.shape + (tank.enemy_slots,), np.int64)
        tank_view_kernel(x, y, h, s.velocity[rows], e, s.gun_heat[rows], alive, team_rows(self.team, x.shape), memory,
                         seen, s.time[rows].astype(np.float64), self.field[0], self.field[1], tank.enemy_slots,
                         tank.mate_slots, self._mates[rows], self._mates_ok[rows], view, slots)
        if self.brains is not None and tank.knowledge:
            b = self.brains
            knowledge_kernel(b.guns >= 0, b.mem[rows], b.stat[rows], x, y, s.time[rows], tank.n_features -
                             KNOWLEDGE_FEATURES, view)
        self._mask_views(view, slots)
        feats[rows] = view
        self._slots[rows] = slots

    @property
    def slots(self) -> np.ndarray:
        """(B, R, K) robot in each enemy slot of the current tank views (-1 = empty)."""
        return self._slots

    def reset(self, seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Start new battles (totals cleared; reseeded when ``seed`` is given): (discrete, features)."""
        # a new battle has fresh robots: no boxes left from the last round constrain the placement
        self.arena.state.box_x[...] = np.nan
        self.arena.state.box_y[...] = np.nan
        if seed is not None:
            self.arena.seed(seed)
        self.arena.new_battle()
        self._forget(np.ones(self.n_battles, dtype=bool))
        if self.bots is not None:
            self.bots.reset()
        if self.tech is not None:  # a new battle: the technique robots forget it all
            self.tech.new_battles(np.ones(self.n_battles, dtype=bool))
        if self.brains is not None:
            self.brains.new_battles(np.ones(self.n_battles, dtype=bool))
        target, disc, feats = self.observe()
        self._last = (target, disc, feats)
        return disc, feats

    def restart(self, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Start a new round in the masked battles (B,) now; the unfinished round scores nothing more."""
        m = np.asarray(mask, dtype=bool)
        if m.any():
            self.arena.reset(m)  # scripted bots clear their memory on the new round themselves
            self._forget(m)
        target, disc, feats = self.observe()
        self._last = (target, disc, feats)
        return disc, feats

    def _forget(self, mask: np.ndarray) -> None:
        """A new round in the masked battles (B,): no scans remembered, no team message received yet."""
        self._memory[mask] = 0.0
        self._mates_ok[mask] = False
        if self.brains is not None:  # a new round: the brains forget the round (and a new battle's, the battle)
            self.brains.sync_rounds()

    def start_recording(self, battle: int = 0, names: list[str] | None = None) -> Replay:
        """Record battle ``battle`` turn by turn into a new :class:`Replay` (until stop_recording)."""
        if not 0 <= battle < self.n_battles:
            raise ValueError(f"battle must be in 0..{self.n_battles - 1}, got {battle}")
        if names is None:
            names = [f"{d or 'learner'}.{i}" for i, d in enumerate(self.drivers)]
        rep = new_replay(self.arena, names)
        record_frame(rep, self.arena, battle)
        self.recording = (rep, battle)
        return rep

    def stop_recording(self) -> Replay | None:
        """Stop recording; the replay recorded so far."""
        rec, self.recording = self.recording, None
        return None if rec is None else rec[0]

    # ------------------------------------------------------------------ stepping
    def _check_actions(self, actions: np.ndarray) -> np.ndarray:
        """Shape and dtype checks; (B, R) int64 view or copy."""
        a = np.asarray(actions)
        if a.shape != (self.n_battles, self.n_robots):
            raise ValueError(f"actions must have shape ({self.n_battles}, {self.n_robots}), got {a.shape}")
        if a.dtype.kind not in "iu":
            raise ValueError(f"actions must be integers, got dtype {a.dtype}")
        return a if a.dtype == np.int64 else a.astype(np.int64)

    def _sync_bots(self) -> None:
        """Scripted bots clear their memory when their battle started a new round (as ScriptedBots.commands), the
        technique robots their round's memory, and their battle's when its battle started (TechBots.commands)."""
        if self.bots is not None:
            self.bots.sync_rounds()
        if self.tech is not None:
            self.tech.sync_rounds()
        if self.brains is not None:
            self.brains.sync_rounds()

    def step(self, actions: np.ndarray) -> StepResult:
        """Hold each learning tank's action for T turns; return observations, (B, R, T) rewards, ends."""
        rewards, active, obs = self.begin_step(actions)
        if self.recording is None:
            self._run_turns(0, self.config.turns_per_step, rewards, obs)
        else:
            rep, b = self.recording
            for t in range(self.config.turns_per_step):
                if self._run_turns(t, t + 1, rewards, obs) == t:
                    break
                record_frame(rep, self.arena, b)
        return self.finish_step(rewards, active, obs)

    def begin_step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...]]:
        """Checks and the learning tanks' moves for a step: (rewards, active, observation buffers) to fill."""
        a = self._check_actions(actions)
        T = self.config.turns_per_step
        active = np.empty((self.n_battles, self.n_robots), dtype=np.bool_)
        p = self.arena.state.packed
        if prepare_actions(a, self._space, p["rb"], p["bb"], self._tables, self._n_act, self._slots, self._move,
                    self._power, self._chosen, active):
            for space, who in ((0, "learning tanks"), (1, "caller-driven opponents")):
                la = a[:, self._space == space]
                if la.size and (la.min() < 0 or la.max() >= self._n_act[space]):
                    raise ValueError(f"actions of the {who} must be in 0..{self._n_act[space] - 1}, "
                                     f"got [{la.min()}, {la.max()}]")
        rewards = np.zeros((self.n_battles, self.n_robots, T))
        self._sync_bots()
        shape = (self.n_battles, self.n_robots)
        obs = (np.empty(shape, np.int64), np.empty(shape, np.int64),
               np.empty(shape + (self.config.observation.n_features,), np.float32),
               np.empty(shape + (self.n_features if self.config.tank is not None else 1,), np.float32))
        return rewards, active, obs

    def kernel_calls(self, t0: int, t1: int, rewards: np.ndarray, obs: tuple[np.ndarray, ...],
                     whole: bool = False) -> list[tuple[Any, ...]]:
        """Arguments of the compiled kernel (smdp_turns) for turns t0..t1-1, one tuple per battle range (one range
        for all battles with ``whole``); the calls are independent (they release the GIL)."""
        tank = self.config.tank
        k_slots, m_slots = (tank.enemy_slots, tank.mate_slots) if tank is not None else (0, 0)
        target, disc, feats, view = obs
        out = Outputs(self._turn_buf, rewards, target, disc, feats, view, self._slots)
        views = Views(self.max_distance, self.field[0], self.field[1], k_slots, m_slots,
                      np.ascontiguousarray(self.view_robots, dtype=np.bool_),
                      np.ascontiguousarray(self.paper_robots, dtype=np.bool_), self._group)
        a = self.arena
        ranges = [(0, self.n_battles)] if whole else self._ranges
        return [(lo, hi, t0, t1, *a.bundles, self._cmd, a.settings, a.scratch, self._bot_states[k],
                 self.bots is not None, self._tech_states[k], self.tech is not None, self.tanks, self.senses, out,
                 views, self._brain_states[k]) for k, (lo, hi) in enumerate(ranges)]

    def kernel(self, call: tuple[Any, ...]) -> Callable[..., int]:
        """smdp_turns compiled for the types of this env's calls (looked up once: numba's own dispatch would work
        out the types of the bundles at every call)."""
        if self._entry is None:
            self._entry = entry(smdp_turns, *call)
        return self._entry

    def _run_turns(self, t0: int, t1: int, rewards: np.ndarray, obs: tuple[np.ndarray, ...]) -> int:
        """Turns t0..t1-1 of the SMDP step in the compiled kernel (then observations into ``obs``);
        battle ranges run in parallel threads when there are enough battles."""
        calls = self.kernel_calls(t0, t1, rewards, obs)
        fn = self.kernel(calls[0])
        if len(calls) == 1:
            return int(fn(*calls[0]))
        return min(run_parallel(kernel_pool(), call_kernel, [(fn, c) for c in calls], len(calls)))

    def finish_step(self, rewards: np.ndarray, active: np.ndarray, obs: tuple[np.ndarray, ...]) -> StepResult:
        s = self.arena.state.arrays
        target, disc, paper, view = obs
        feats = view if self.config.tank is not None else paper
        round_done = s["done"].copy()
        truncated = round_done & ~s["decided"]
        terminated = ~s["alive"] | round_done[:, None]
        res = StepResult(disc, feats, target, rewards, terminated, round_done, truncated, active)
        res.info = {"score": s["score"].copy(), "score_total": s["score_total"].copy(), "score_parts": SCORE_PARTS}
        if round_done.any():
            st = self.arena.state
            res.round_end = RoundEnd(round_done, st.score.copy(), st.placements.copy(), st.time.copy(),
                                     st.decided.copy(), st.alive.copy())
            if self.config.auto_reset:
                res.final_discrete, res.final_features = disc.copy(), feats.copy()
                self.arena.reset(round_done)  # scripted bots clear their memory on the new round themselves
                self._forget(round_done)
                self._observe_rows(np.flatnonzero(round_done), target, disc, feats)  # the others are unchanged
        self._last = (res.target, res.discrete, res.features)
        return res

    # ------------------------------------------------------------------ checkpoints
    def state_dict(self) -> dict[str, np.ndarray]:
        """Arena arrays, the robots' scan memory and the scripted and technique robots' memory (data only)."""
        d = {f"arena.{k}": v for k, v in self.arena.state_dict().items()}
        d["control.memory"] = self._memory.copy()
        d["control.slots"] = self._slots.copy()
        d["control.mates"], d["control.mates_ok"] = self._mates.copy(), self._mates_ok.copy()
        if self.bots is not None:
            d.update({f"bots.{k}": v for k, v in self.bots.state_dict().items()})
        if self.tech is not None:
            d.update({f"tech.{k}": v for k, v in self.tech.state_dict().items()})
        if self.brains is not None:
            d.update({f"brains.{k}": v for k, v in self.brains.state_dict().items()})
        return d

    def load_state_dict(self, d: dict[str, np.ndarray]) -> None:
        """Restore what :meth:`state_dict` wrote."""
        self.arena.load_state_dict({k[6:]: v for k, v in d.items() if k.startswith("arena.")})
        if "control.memory" not in d:
            raise ValueError("state dict lacks 'control.memory' (saved before the scan memory existed)")
        if d["control.memory"].shape != self._memory.shape:
            raise ValueError(f"control.memory has shape {d['control.memory'].shape}, expected {self._memory.shape}")
        self._memory[...] = d["control.memory"]
        for name, arr in (("slots", self._slots), ("mates", self._mates), ("mates_ok", self._mates_ok)):
            saved = d.get(f"control.{name}")
            if saved is None or saved.shape != arr.shape:
                got = "missing" if saved is None else f"shape {saved.shape}"
                raise ValueError(f"control.{name} is {got}, expected shape {arr.shape}")
            arr[...] = saved
        if self.bots is not None:
            self.bots.load_state_dict({k[5:]: v for k, v in d.items() if k.startswith("bots.")})
        if self.tech is not None:
            self.tech.load_state_dict({k[5:]: v for k, v in d.items() if k.startswith("tech.")})
        if self.brains is not None:
            self.brains.load_state_dict({k[7:]: v for k, v in d.items() if k.startswith("brains.")})
        self._last = self.observe()

    def team_ids(self) -> np.ndarray:
        """(R,) team of each robot."""
        return self.team.copy()


# ---------------------------------------------------------------------- compiled SMDP turns (smdp_kernel)
def _action_tables(cfg: SMDPConfig, learner: np.ndarray, team: np.ndarray, opponent_actions: str
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Action tables (2, A, 7) of (distance, body turn, fire power, target slot, relative turn, lead, surf) rows,
    0 = the learners', 1 = the caller-driven opponents'; each robot's table (R,) (-1: scripted); actions per
    table (2,).
    Fire power 0 = by distance (the paper's controller), -1 = hold fire; slot -1 = the target rule's."""
    dist, turn = move_commands(np.arange(N_MOVES), cfg.control)
    a = np.arange(cfg.paper_actions)
    powers = np.asarray(cfg.fire_powers)[a // N_MOVES] if cfg.fire_power_actions else np.zeros(a.size)
    paper = np.stack([dist[a % N_MOVES], turn[a % N_MOVES], powers, np.full(a.size, -1.0), np.zeros(a.size),
                      np.zeros(a.size), np.zeros(a.size)], axis=1)
    ours = action_table(cfg.tank) if cfg.tank is not None else paper
    theirs = paper if opponent_actions == "paper" else ours
    tables = np.zeros((2, max(len(ours), len(theirs)), 7))
    tables[0, :len(ours)], tables[1, :len(theirs)] = ours, theirs
    space = np.where(learner, np.where(team == 0, 0, 1), -1).astype(np.int64)
    return tables, space, np.array([len(ours), len(theirs)], dtype=np.int64)




def _brains(arena: Arena, tank: TankSpace | None, tank_actions: np.ndarray, team: np.ndarray,
            rounds_per_battle: int) -> TechBots | None:
    """The technique brains of the robots acting in the tank actions (``tank_actions`` (R,)) when the tank has
    skills (tank.py), else None; a brain's team-mates are its team's robots."""
    if tank is None or not tank.skills or not tank_actions.any():
        return None
    mates = [int(sum(1 << j for j in range(len(team)) if team[j] == team[i])) for i in range(len(team))]
    return TechBots(arena, [tank.brain if on else None for on in tank_actions], rounds_per_battle, mates)


_PARALLEL_MIN_BATTLES = 8
_POOL: list[ThreadPoolExecutor] = []


def kernel_pool() -> ThreadPoolExecutor:
    """A shared thread pool (the kernel releases the GIL)."""
    if not _POOL:
        _POOL.append(ThreadPoolExecutor(max(1, numba.get_num_threads())))
    return _POOL[0]


def call_kernel(fn: Callable[..., int], call: tuple[Any, ...]) -> int:
    """``fn(*call)`` (a kernel and its arguments, for a thread pool)."""
    return fn(*call)
