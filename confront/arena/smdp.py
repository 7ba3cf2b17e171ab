"""The batched multi-agent SMDP team environment over :class:`confront.arena.core.Arena` (paper §2.2, §6.1).

``TeamBattleEnv(scenario, n_battles, seed, opponents)`` runs B battles of one scenario. Every robot is
either a *learning tank* (driven by the caller's actions: the paper's four macro moves, optionally x 3
fire powers, each held for T turns; its gun and radar follow :mod:`confront.arena.control`'s fixed
controller) or a *scripted bot* (:mod:`confront.arena.bots`, commands every turn). Team 0 is always
learning; the other teams follow ``opponents`` (``"td"`` = learning tanks whose actions the caller also
supplies, e.g. a TD team; a bot name = that sample robot).

``step(actions)`` takes (B, R) ints (ignored for scripted and dead robots), runs T turns and returns a
:class:`StepResult`: observations after the step (discrete state (B, R), features (B, R, F), target
(B, R)), per-turn rewards (B, R, T) of Eq. 35 against each turn's target, ``terminated`` (B, R): the
robot is dead or its round is over, ``round_done`` (B,) and ``truncated`` (B,) (round stopped by
``max_turns`` rather than decided). Rounds that end are reset individually at the end of the step
(``auto_reset``); the returned observations are then the new round's first ones, the terminal ones are
in ``final_discrete`` / ``final_features``, and ``round_end`` carries the ended rounds' score parts.

Default T = 10 turns: the paper gives no value; a 45-degree turn takes 5 turns at rest and a
100 px move about 16, so 10 turns lets each macro move show its effect while keeping decisions frequent.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .bots import BOT_NAMES, ScriptedBots
from .control import N_MOVES, ControlConfig, gun_radar_commands, move_commands, set_adjustments
from .core import Arena
from .observe import ObservationConfig, field_diagonal, gather_target, observe, reward_eq35, select_targets
from .replay import Replay, new_replay, record_frame
from .scenarios import Scenario, get_scenario
from .state import SCORE_PARTS

__all__ = ["SMDPConfig", "TeamBattleEnv", "StepResult", "RoundEnd", "resolve_drivers", "LEARNER"]

LEARNER = "td"  # opponents value meaning "learning tanks driven by the caller"


@dataclass(frozen=True)
class SMDPConfig:
    """SMDP step length, action set, observation and controller settings."""

    turns_per_step: int = 10  # T
    fire_power_actions: bool = False  # actions = 4 moves x len(fire_powers) powers
    fire_powers: tuple[float, ...] = (1.0, 2.0, 3.0)
    auto_reset: bool = True
    observation: ObservationConfig = field(default_factory=ObservationConfig)
    control: ControlConfig = field(default_factory=ControlConfig)

    def __post_init__(self) -> None:
        if not isinstance(self.turns_per_step, int) or self.turns_per_step < 1:
            raise ValueError(f"turns_per_step must be an integer >= 1, got {self.turns_per_step!r}")
        if not self.fire_powers or any(not 0.1 <= p <= 3.0 for p in self.fire_powers):
            raise ValueError(f"fire_powers must be non-empty values in [0.1, 3], got {self.fire_powers!r}")

    @property
    def n_actions(self) -> int:
        """4 moves, or 4 moves x fire powers; action a = power_index * 4 + move."""
        return N_MOVES * (len(self.fire_powers) if self.fire_power_actions else 1)


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
    """Per-robot driver: None = learning tank, or a bot name. Team 0 always learns.

    ``opponents``: None = the scenario's default; one name for every robot of the other teams; or one name
    per robot of the other teams (in robot order). ``"td"`` means learning tanks.
    """
    others = scenario.n_robots - scenario.teams[0]
    if opponents is None:
        opponents = scenario.opponents
    names = [opponents] * others if isinstance(opponents, str) else list(opponents)
    if len(names) != others:
        raise ValueError(f"opponents has {len(names)} entries, the other teams have {others} robots")
    for n in names:
        if n != LEARNER and n not in BOT_NAMES:
            raise ValueError(f"unknown opponent {n!r}; use {LEARNER!r} or one of {', '.join(BOT_NAMES)}")
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
    ) -> None:
        self.scenario = get_scenario(scenario) if isinstance(scenario, str) else scenario
        self.config = config or SMDPConfig()
        self.arena = Arena(self.scenario, n_battles, seed=seed, order=order)
        self.drivers = resolve_drivers(self.scenario, opponents)
        self.learner = np.array([d is None for d in self.drivers])
        self.team = np.asarray(self.scenario.team_ids(), dtype=np.int64)
        self.bots = ScriptedBots(self.arena, self.drivers) if not self.learner.all() else None
        set_adjustments(self.arena, self.learner)
        self.field = (float(self.scenario.width), float(self.scenario.height))
        self.max_distance = self.config.observation.max_distance or field_diagonal(*self.field)
        self._cmd = self.arena.idle_commands()
        self._powers = np.asarray(self.config.fire_powers, dtype=np.float64)
        self._last: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._recording: tuple[Replay, int] | None = None

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
        """Feature vector length F."""
        return self.config.observation.n_features

    @property
    def turns_per_step(self) -> int:
        """T."""
        return self.config.turns_per_step

    # ------------------------------------------------------------------ observations
    def observe(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(target, discrete, features) of the current state for every robot."""
        s = self.arena.state
        return observe(s.x, s.y, s.heading, s.energy, s.alive, self.team, self.field, self.config.observation)

    def reset(self, seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Start new battles (totals cleared; reseeded when ``seed`` is given): (discrete, features)."""
        # a new battle has fresh robots: no boxes left from the last round constrain the placement
        self.arena.state.box_x[...] = np.nan
        self.arena.state.box_y[...] = np.nan
        if seed is not None:
            self.arena.seed(seed)
        self.arena.new_battle()
        if self.bots is not None:
            self.bots.reset()
            self.bots._round[:] = self.arena.state.round
        target, disc, feats = self.observe()
        self._last = (target, disc, feats)
        return disc, feats

    def restart(self, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Start a new round in the masked battles (B,) now; the unfinished round scores nothing more."""
        m = np.asarray(mask, dtype=bool)
        if m.any():
            self.arena.reset(m)  # scripted bots clear their memory on the new round themselves
        target, disc, feats = self.observe()
        self._last = (target, disc, feats)
        return disc, feats

    def start_recording(self, battle: int = 0, names: list[str] | None = None) -> Replay:
        """Record battle ``battle`` turn by turn into a new :class:`Replay` (until stop_recording)."""
        if not 0 <= battle < self.n_battles:
            raise ValueError(f"battle must be in 0..{self.n_battles - 1}, got {battle}")
        if names is None:
            names = [f"{d or 'learner'}.{i}" for i, d in enumerate(self.drivers)]
        rep = new_replay(self.arena, names)
        record_frame(rep, self.arena, battle)
        self._recording = (rep, battle)
        return rep

    def stop_recording(self) -> Replay | None:
        """Stop recording; the replay recorded so far."""
        rec, self._recording = self._recording, None
        return None if rec is None else rec[0]

    # ------------------------------------------------------------------ stepping
    def _check_actions(self, actions: np.ndarray) -> np.ndarray:
        a = np.asarray(actions)
        if a.shape != (self.n_battles, self.n_robots):
            raise ValueError(f"actions must have shape ({self.n_battles}, {self.n_robots}), got {a.shape}")
        if not np.issubdtype(a.dtype, np.integer):
            raise ValueError(f"actions must be integers, got dtype {a.dtype}")
        la = a[:, self.learner]
        if la.size and (la.min() < 0 or la.max() >= self.n_actions):
            raise ValueError(f"actions must be in 0..{self.n_actions - 1}, got [{la.min()}, {la.max()}]")
        return np.where(self.learner[None, :], a, 0).astype(np.int64)

    def step(self, actions: np.ndarray) -> StepResult:
        """Hold each learning tank's action for T turns; return observations, (B, R, T) rewards, ends."""
        a = self._check_actions(actions)
        s, cfg, cmd, L = self.arena.state, self.config, self._cmd, self.learner
        T = cfg.turns_per_step
        dist, turn = move_commands(a % N_MOVES, cfg.control)
        power = self._powers[a // N_MOVES] if cfg.fire_power_actions else None
        active = s.alive & L[None, :] & ~s.done[:, None]
        rewards = np.zeros((self.n_battles, self.n_robots, T))
        guard = cfg.observation.reward_guard
        cmd[..., :4] = np.nan
        cmd[..., 4] = 0.0
        # moves are written once at the start of the SMDP step (set* semantics), then run for T turns
        cmd[:, L, 0] = dist[:, L]
        cmd[:, L, 1] = turn[:, L]
        for t in range(T):
            if t == 1:
                cmd[:, L, :2] = np.nan
            live = s.alive & ~s.done[:, None]
            target = select_targets(s.x, s.y, s.energy, s.alive, self.team, cfg.observation.target)
            gun_radar_commands(self.arena, cmd, cfg.control, target=target, robots=L)
            if power is not None:
                cmd[:, L, 4] = np.where(cmd[:, L, 4] > 0, power[:, L], 0.0)
            if self.bots is not None:
                self.bots.commands(cmd)
            own_prev = s.energy.copy()
            tgt_prev = gather_target(own_prev, target)
            self.arena.step(cmd)
            r = reward_eq35(own_prev, s.energy, tgt_prev, gather_target(s.energy, target), guard)
            rewards[:, :, t] = np.where(live & (target >= 0), r, 0.0)
            if self._recording is not None:
                record_frame(self._recording[0], self.arena, self._recording[1])
            if s.done.all():
                break
        return self._finish(rewards, active)

    def _finish(self, rewards: np.ndarray, active: np.ndarray) -> StepResult:
        s = self.arena.state
        target, disc, feats = self.observe()
        round_done = s.done.copy()
        truncated = round_done & ~s.decided
        terminated = ~s.alive | round_done[:, None]
        res = StepResult(disc, feats, target, rewards, terminated, round_done, truncated, active)
        res.info = {"score": s.score.copy(), "score_total": s.score_total.copy(), "round": s.round.copy(),
                    "time": s.time.copy(), "score_parts": SCORE_PARTS}
        if round_done.any():
            res.round_end = RoundEnd(round_done, s.score.copy(), s.placements.copy(), s.time.copy(),
                                     s.decided.copy(), s.alive.copy())
            if self.config.auto_reset:
                res.final_discrete, res.final_features = disc.copy(), feats.copy()
                self.arena.reset(round_done)  # scripted bots clear their memory on the new round themselves
                target, disc, feats = self.observe()
                res.discrete, res.features, res.target = disc, feats, target
        self._last = (res.target, res.discrete, res.features)
        return res

    # ------------------------------------------------------------------ checkpoints
    def state_dict(self) -> dict[str, np.ndarray]:
        """Arena arrays plus the scripted bots' memory (data only)."""
        d = {f"arena.{k}": v for k, v in self.arena.state_dict().items()}
        if self.bots is not None:
            d["bots.mem"] = self.bots.mem.copy()
            d["bots.round"] = self.bots._round.copy()
        return d

    def load_state_dict(self, d: dict[str, np.ndarray]) -> None:
        """Restore what :meth:`state_dict` wrote."""
        self.arena.load_state_dict({k[6:]: v for k, v in d.items() if k.startswith("arena.")})
        if self.bots is not None:
            for key in ("bots.mem", "bots.round"):
                if key not in d:
                    raise ValueError(f"state dict lacks {key!r}")
            self.bots.mem[...] = d["bots.mem"]
            self.bots._round[...] = d["bots.round"]
        self._last = self.observe()

    def team_ids(self) -> np.ndarray:
        """(R,) team of each robot."""
        return self.team.copy()
