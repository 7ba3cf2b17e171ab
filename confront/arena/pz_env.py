"""PettingZoo ``ParallelEnv`` for a team: ``confront.parallel_env(scenario="4v4", opponents="SpinBot")``.

Agents ``tank_0 .. tank_{n-1}`` are team 0's robots of one battle. Spaces, actions and rewards are those
of :mod:`confront.arena.gym_env` per agent: ``view="paper"`` (Dict of discrete state and features; 4 moves or
4 x 3 with fire power; the sum of the T per-turn Eq. 35 rewards against each tank's own target) or ``"tank"``
(the tank view Box(62), MultiDiscrete action heads, the team's score margin over the T turns: the same
reward for every living team-mate). An agent
terminates when its tank dies; an episode is one round (all agents end when the round is decided, or are
truncated at ``max_turns``). ``infos[agent]``: the per-turn ``rewards`` (T,) and the tank's ``score``
parts this round; at the round end also ``team_score`` (teams x 6). Opponents: a bot name, ``"td"``
(learning tanks acting by ``other_policy``, uniformly random without one), or one name per robot.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from pettingzoo import ParallelEnv

from .gym_env import AgentDriver, OtherPolicy, action_indices, agent_obs, make_config, make_spaces
from .render import draw_frame
from .scenarios import Scenario, get_scenario
from .smdp import Reward, SMDPConfig
from .state import SCORE_PARTS
from .tank import TankSpace

__all__ = ["TeamParallelEnv", "parallel_env"]


class TeamParallelEnv(ParallelEnv):
    """Team 0 of one battle as PettingZoo parallel agents."""

    metadata = {"render_modes": ["rgb_array"], "name": "confront_team_v0", "is_parallelizable": True}

    def __init__(self, scenario: Scenario | str = "4v4", opponents: Any = None, turns_per_step: int | None = None,
                 fire_power_actions: bool = False, config: SMDPConfig | None = None,
                 other_policy: OtherPolicy | None = None, render_mode: str | None = None, seed: int = 0,
                 order: str = "engine", view: str = "paper", tank: TankSpace | None = None,
                 reward: Reward | None = None) -> None:
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        sc = get_scenario(scenario) if isinstance(scenario, str) else scenario
        cfg = make_config(turns_per_step, fire_power_actions, config, view, tank, reward)
        self.config = cfg
        n = sc.teams[0]
        self._driver = AgentDriver(sc, 1, seed, opponents, cfg, list(range(n)), other_policy, order)
        self.possible_agents = [f"tank_{i}" for i in range(n)]
        self.agents: list[str] = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self._obs_space, _ = make_spaces(cfg)
        self._act_spaces = {a: make_spaces(cfg)[1] for a in self.possible_agents}
        self.render_mode = render_mode
        self._np_random, _ = seeding.np_random(seed)
        self._actions = np.zeros((1, n), dtype=np.int64)

    def observation_space(self, agent: str) -> spaces.Space:
        """Dict(state=Discrete(320), features=Box(F,)), or the tank view's Box(62,)."""
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
        """Discrete(4) or Discrete(12), or the tank actions' MultiDiscrete."""
        return self._act_spaces[agent]

    def _obs(self, disc: np.ndarray, feats: np.ndarray, agents: list[str]) -> dict[str, Any]:
        return {a: agent_obs(self.config, disc[0, self._index[a]], feats[0, self._index[a]]) for a in agents}

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Start a new round (a new battle, reseeded, when ``seed`` is given)."""
        env = self._driver.env
        if seed is not None:
            self._np_random, _ = seeding.np_random(seed)
            disc, feats = env.reset(seed=seed)
        else:
            disc, feats = env.restart(np.ones(1, dtype=bool))
        self.agents = list(self.possible_agents)
        return self._obs(disc, feats, self.agents), {a: {} for a in self.agents}

    def step(self, actions: dict[str, Any]) -> tuple[dict[str, Any], dict[str, float], dict[str, bool],
                                                     dict[str, bool], dict[str, Any]]:
        """Hold every live agent's action for T turns; ``actions`` must name every live agent (a missing one is a
        ValueError, not a made-up action)."""
        self._actions[:] = 0
        for a, v in actions.items():
            if a not in self._index:
                raise ValueError(f"unknown agent {str(a)[:60]!r}")
            try:
                self._actions[0, self._index[a]] = action_indices(self.config, v, 1)[0]
            except ValueError as err:
                raise ValueError(f"action of {a}: {err}") from None
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(f"actions lack the live agents {', '.join(missing)}: give one action per agent of "
                             "env.agents")
        drv = self._driver
        res = drv.env.step(drv.full_actions(self._actions, self._np_random))
        live = self.agents
        obs = self._obs(res.discrete, res.features, live)
        score = drv.env.arena.state.score[0]
        trunc = bool(res.truncated[0])
        rewards = {a: float(res.rewards[0, self._index[a]].sum()) for a in live}
        terminated = {a: bool(res.terminated[0, self._index[a]]) and not trunc for a in live}
        truncated = dict.fromkeys(live, trunc)
        infos = {a: {"rewards": res.rewards[0, self._index[a]].copy(), "score": score[self._index[a]].copy(),
                     "score_parts": SCORE_PARTS} for a in live}
        if res.round_done[0]:
            ts = drv.team_score()[0]
            for a in live:
                infos[a]["team_score"] = ts
        self.agents = [a for a in live if not (terminated[a] or truncated[a])]
        return obs, rewards, terminated, truncated, infos

    def render(self) -> np.ndarray | None:
        """An RGB frame (rgb_array mode)."""
        if self.render_mode != "rgb_array":
            return None
        sc = self._driver.env.scenario
        return draw_frame(self._driver.frame(0), sc.width, sc.height)

    def close(self) -> None:
        """Nothing to release."""

    def state(self) -> np.ndarray:
        """Global state: every robot's features, flattened."""
        _, _, feats = self._driver.env.observe()
        return feats[0].ravel()


def parallel_env(scenario: Scenario | str = "4v4", opponents: Any = None, **kwargs: Any) -> TeamParallelEnv:
    """A team's PettingZoo ParallelEnv (see :class:`TeamParallelEnv`)."""
    return TeamParallelEnv(scenario=scenario, opponents=opponents, **kwargs)
