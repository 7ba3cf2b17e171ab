"""Gymnasium environment ``confront/Battle-v0``: one learning tank (robot 0) against opponents.

``gymnasium.make("confront/Battle-v0", scenario="1v1", opponents="SpinBot", turns_per_step=10)``; ``view="tank"``
gives the spaces the recommended learner (PPO tanks) trains on.

- ``view="paper"`` (default), the paper's model:
  - Observation: ``Dict(state=Discrete(320), features=Box(F,))`` - the paper's discrete state and the
    continuous features of :mod:`confront.arena.observe` (sin/cos relative angle, sin/cos heading,
    distance/diagonal, own and target energy / 100, optionally x/W, y/H).
  - Action: ``Discrete(4)`` (forward, backward, clockwise, anticlockwise) or ``Discrete(12)`` with
    ``fire_power_actions=True`` (action = power_index * 4 + move, powers 1, 2, 3), held for T = 10 turns.
  - Reward: the sum of the T per-turn Eq. 35 rewards.
- ``view="tank"``, what a real robot knows and chooses (:mod:`confront.arena.tank`, ``tank=TankSpace(...)``):
  - Observation: ``Box(62,)`` float32, the tank view (own state, the 4 nearest scanned enemies, 3 team-mates;
    the table in tank.py's docstring, names in ``tank.feature_names``).
  - Action: ``MultiDiscrete([5, 5, 4, 4, 2])``: move distance, body angle to the target's bearing, fire power or
    hold, target slot, gun lead; held for T = 5 turns.
  - Reward: Robocode's score, the change of the team's score margin (ours minus theirs) over the T turns, in
    score points (``reward="eq35"`` for the paper's); a round's rewards add up to its score margin.
- ``info["rewards"]`` has the T per-turn values. Episode: one round. ``terminated`` when the tank dies or the
  round is decided, ``truncated`` when the round reaches ``max_turns``. ``info["score"]``: the tank's score
  parts this round (Robocode's six, in ``info["score_parts"]`` order); at the end also ``info["team_score"]``
  (teams x 6).
- Other learning tanks (team-mates, ``opponents="td"``) act by ``other_policy(discrete, features, rng)``
  returning (B, R) actions (joint action indices); without one they pick uniformly random actions.
- ``render_mode="rgb_array"`` draws the battle with :mod:`confront.arena.render`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from .observe import N_STATES, ObservationConfig
from .render import FrameData, draw_frame
from .scenarios import Scenario, get_scenario
from .smdp import Reward, SMDPConfig, StepResult, TeamBattleEnv
from .state import SCORE_PARTS
from .tank import TankSpace, feature_names

__all__ = ["BattleEnv", "AgentDriver", "make_observation_space", "make_config", "make_spaces", "agent_obs",
           "action_indices", "tank_observation_space", "OtherPolicy", "ENV_ID", "VIEWS"]

ENV_ID = "confront/Battle-v0"
VIEWS = {"paper": 10, "tank": 5}  # what a tank sees and chooses -> its default T (turns per step)
OtherPolicy = Callable[[np.ndarray, np.ndarray, np.random.Generator], np.ndarray]


def make_config(turns_per_step: int | None = None, fire_power_actions: bool = False,
                config: SMDPConfig | None = None, view: str = "paper", tank: TankSpace | None = None,
                reward: Reward | None = None, **kwargs: Any) -> SMDPConfig:
    """An SMDPConfig from keyword arguments (or the one given): ``view="paper"`` (the paper's state and moves,
    Eq. 35 rewards, T = 10) or ``"tank"`` (the tank view and actions, ``tank`` or ``TankSpace()``, the score
    margin as reward, scanned sensing, T = 5: what the recommended learner trains on)."""
    if config is not None:
        return config
    if view not in VIEWS:
        raise ValueError(f"view must be one of {', '.join(VIEWS)}, got {view!r}")
    t = VIEWS[view] if turns_per_step is None else turns_per_step
    if view == "paper":
        if tank is not None:
            raise ValueError("tank= describes the tank view's actions and slots: pass view='tank' with it")
        return SMDPConfig(turns_per_step=t, fire_power_actions=fire_power_actions, reward=reward or "eq35", **kwargs)
    if fire_power_actions:
        raise ValueError("fire_power_actions is for the paper's view: the tank actions have a fire-power head")
    kwargs.setdefault("observation", ObservationConfig(sensing="scanned"))
    return SMDPConfig(turns_per_step=t, tank=tank or TankSpace(), reward=reward or "score", **kwargs)


def make_observation_space(n_features: int) -> spaces.Dict:
    """Dict of the discrete state and the feature vector (energy / 100 bounded by 10: 1000 energy)."""
    low = np.array([-1, -1, -1, -1, 0, 0, 0, 0, 0][:n_features], dtype=np.float32)
    high = np.array([1, 1, 1, 1, 1, 10, 10, 1, 1][:n_features], dtype=np.float32)
    return spaces.Dict({"state": spaces.Discrete(N_STATES), "features": spaces.Box(low, high, dtype=np.float32)})


def tank_observation_space(space: TankSpace) -> spaces.Box:
    """Box of the tank view (float32): energies / 100 bounded by 10 (1000 energy), sines, cosines and velocities
    by +-1, everything else (wall distances, heat, fractions, distances, ages, drops, flags) by [0, 1]."""
    names = feature_names(space.enemy_slots, space.mate_slots)
    signed = ("heading", "bearing", "velocity", "lateral", "advancing")  # sin_/cos_heading, *_bearing, ...
    low = np.array([-1.0 if n.split("_")[-1] in signed else 0.0 for n in names], dtype=np.float32)
    high = np.array([10.0 if n.endswith("energy") else 1.0 for n in names], dtype=np.float32)
    return spaces.Box(low, high, dtype=np.float32)


def make_spaces(cfg: SMDPConfig) -> tuple[spaces.Space, spaces.Space]:
    """(observation space, action space) of one learning tank: the paper's Dict and Discrete, or the tank view's
    Box and MultiDiscrete (one entry per action head)."""
    if cfg.tank is None:
        return make_observation_space(cfg.observation.n_features), spaces.Discrete(cfg.n_actions)
    return tank_observation_space(cfg.tank), spaces.MultiDiscrete(np.array(cfg.tank.dims, dtype=np.int64))


def agent_obs(cfg: SMDPConfig, disc: Any, feats: np.ndarray) -> dict[str, Any] | np.ndarray:
    """What the spaces of :func:`make_spaces` hold for the rows given (one tank: ``disc`` a scalar, ``feats``
    (F,); or several): a copy of the tank view, or the paper's Dict of state and features."""
    if cfg.tank is not None:
        return np.array(feats, copy=True)
    return {"state": int(disc) if np.ndim(disc) == 0 else np.array(disc, copy=True), "features": feats.copy()}


def action_indices(cfg: SMDPConfig, actions: Any, n: int) -> np.ndarray:
    """(n,) joint action indices from ``n`` actions of the space :func:`make_spaces` gives: integers (paper), or
    (n, heads) head indices (tank view, ``np.ravel_multi_index`` over ``tank.dims``); a clear ValueError else."""
    if cfg.tank is None and n == 1 and isinstance(actions, int | np.integer) and not isinstance(actions, bool) \
            and 0 <= actions < cfg.n_actions:  # the single env's usual call, without array work
        return np.array([actions], dtype=np.int64)
    a = np.asarray(actions)
    whole = a.dtype.kind in "iufb" and bool(np.all(np.isfinite(a))) and bool(np.all(a == np.round(a)))
    if cfg.tank is None:
        if not whole or a.size != n or a.min() < 0 or a.max() >= cfg.n_actions:
            raise ValueError(f"action must be in 0..{cfg.n_actions - 1}, got {actions!r}")
        return a.reshape(n).astype(np.int64)
    dims = cfg.tank.dims
    if not whole or a.shape not in ((n, len(dims)), (len(dims),) if n == 1 else ()) or (a < 0).any() \
            or (a >= np.array(dims)).any():
        raise ValueError(f"a tank action is {len(dims)} head indices below {list(dims)} (distance, turn, fire, "
                         f"target slot, lead), for each of {n}; got {actions!r}")
    return np.asarray(np.ravel_multi_index(tuple(a.reshape(n, len(dims)).astype(np.int64).T), dims), dtype=np.int64)


class AgentDriver:
    """A TeamBattleEnv seen from some agents (robot indices); other learning tanks act by a policy."""

    def __init__(self, scenario: Scenario | str, n_battles: int, seed: int, opponents: Any,
                 config: SMDPConfig, agents: list[int] | None, other_policy: OtherPolicy | None,
                 order: str = "engine") -> None:
        sc = get_scenario(scenario) if isinstance(scenario, str) else scenario
        self.env = TeamBattleEnv(sc, n_battles, seed=seed, opponents=opponents,
                                 config=dataclasses.replace(config, auto_reset=False), order=order)
        self.agents = np.asarray([0] if agents is None else agents, dtype=np.int64)
        if not self.env.learner[self.agents].all():
            raise ValueError(f"agents {self.agents.tolist()} must be learning tanks (team 0 or 'td' opponents)")
        self.others = np.flatnonzero(self.env.learner & ~np.isin(np.arange(self.env.n_robots), self.agents))
        self.other_policy = other_policy
        self._full = np.zeros((n_battles, self.env.n_robots), dtype=np.int64)

    def full_actions(self, agent_actions: np.ndarray | int, rng: np.random.Generator) -> np.ndarray:
        """(B, R) actions: the agents' (B, n_agents) (or one int for all) plus the other learning tanks'."""
        a = self._full
        if self.others.size:
            if self.other_policy is None:
                a[:, self.others] = rng.integers(0, self.env.n_actions, size=(a.shape[0], self.others.size))
            else:
                disc, feats = self.env._last[1], self.env._last[2]  # type: ignore[index]
                a[:, self.others] = np.asarray(self.other_policy(disc, feats, rng))[:, self.others]
        a[:, self.agents] = agent_actions
        return a

    def team_score(self) -> np.ndarray:
        """(B, teams, 6) this round's score parts per team."""
        s = self.env.arena.state
        team = self.env.team
        return np.stack([s.score[:, team == k].sum(axis=1) for k in range(self.env.scenario.n_teams)], axis=1)

    def frame(self, b: int = 0) -> FrameData:
        """What battle b shows now."""
        s = self.env.arena.state
        k = int(s.n_bullets[b])
        slots = s.b_list[b, :k]
        live = np.isin(s.b_state[b, slots], (1, 2))
        sl = slots[live]
        bullets = np.stack([s.b_x[b, sl], s.b_y[b, sl], s.b_power[b, sl]], axis=-1)
        return FrameData(s.x[b], s.y[b], s.heading[b], s.gun_heading[b], s.radar_heading[b], s.energy[b],
                         s.alive[b], self.env.team, bullets, s.score[b].sum(axis=-1),
                         f"round {int(s.round[b])}  turn {int(s.time[b])}")


class BattleEnv(gym.Env):
    """One learning tank against opponents in the batched arena (a batch of one)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, scenario: Scenario | str = "1v1", opponents: Any = None, turns_per_step: int | None = None,
                 fire_power_actions: bool = False, config: SMDPConfig | None = None,
                 other_policy: OtherPolicy | None = None, render_mode: str | None = None,
                 render_scale: float = 0.5, seed: int = 0, order: str = "engine", view: str = "paper",
                 tank: TankSpace | None = None, reward: Reward | None = None) -> None:
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        cfg = make_config(turns_per_step, fire_power_actions, config, view, tank, reward)
        sc = get_scenario(scenario) if isinstance(scenario, str) else scenario
        self._driver = AgentDriver(sc, 1, seed, opponents, cfg, [0], other_policy, order)
        self.render_mode = render_mode
        self.render_scale = render_scale
        self.config = cfg
        self.observation_space, self.action_space = make_spaces(cfg)

    @property
    def team_env(self) -> TeamBattleEnv:
        """The underlying batched SMDP environment."""
        return self._driver.env

    def _obs(self, disc: np.ndarray, feats: np.ndarray) -> dict[str, Any] | np.ndarray:
        return agent_obs(self.config, disc[0, 0], feats[0, 0])

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, Any] | np.ndarray, dict[str, Any]]:
        """Start a new round (a new battle, reseeded, when ``seed`` is given)."""
        super().reset(seed=seed)
        env = self._driver.env
        if seed is not None:
            disc, feats = env.reset(seed=seed)
        else:
            disc, feats = env.restart(np.ones(1, dtype=bool))
        return self._obs(disc, feats), {"score_parts": SCORE_PARTS}

    def step(self, action: Any) -> tuple[dict[str, Any] | np.ndarray, float, bool, bool, dict[str, Any]]:
        """Hold the action for T turns."""
        a = int(action_indices(self.config, action, 1)[0])
        drv = self._driver
        res: StepResult = drv.env.step(drv.full_actions(a, self.np_random))
        rewards = res.rewards[0, 0]
        terminated = bool(res.terminated[0, 0] and not res.truncated[0])
        truncated = bool(res.truncated[0])
        info: dict[str, Any] = {"rewards": rewards, "score": drv.env.arena.state.score[0, 0].copy(),
                                "score_parts": SCORE_PARTS}
        if terminated or truncated:
            info["team_score"] = drv.team_score()[0]
        return self._obs(res.discrete, res.features), float(rewards.sum()), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """An RGB frame (rgb_array mode)."""
        if self.render_mode != "rgb_array":
            return None
        sc = self._driver.env.scenario
        return draw_frame(self._driver.frame(0), sc.width, sc.height, self.render_scale)


def register() -> None:
    """Register ``confront/Battle-v0`` with Gymnasium (idempotent)."""
    if ENV_ID not in gym.registry:
        gym.register(id=ENV_ID, entry_point="confront.arena.gym_env:BattleEnv")


register()
