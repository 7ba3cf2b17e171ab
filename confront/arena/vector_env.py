"""A Gymnasium VectorEnv of ``confront/Battle-v0`` over the batched arena (one Arena of N battles, not N envs).

Each sub-environment is one battle seen from robot 0, with the same spaces (``view="paper"`` or ``"tank"``),
reward and episode ends as :class:`confront.arena.gym_env.BattleEnv`; actions are (N,) ints, or (N, 5) head
indices with the tank view. Autoreset is ``SAME_STEP``: a sub-environment whose episode
ended starts its next round inside the same ``step``; the returned observation is the new round's, the
terminal one is in ``info["final_obs"]`` (with ``info["_final_obs"]`` the mask), and ``info["team_score"]``
holds the ended rounds' team score parts (rows where the mask is set).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv

from .gym_env import AgentDriver, OtherPolicy, action_indices, agent_obs, make_config, make_spaces
from .scenarios import Scenario
from .smdp import Reward, SMDPConfig
from .state import SCORE_PARTS
from .tank import TankSpace

__all__ = ["BattleVectorEnv"]


class BattleVectorEnv(VectorEnv):
    """N battles of one scenario, robot 0 of each driven by the caller."""

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, num_envs: int = 8, scenario: Scenario | str = "1v1", opponents: Any = None,
                 turns_per_step: int | None = None, fire_power_actions: bool = False,
                 config: SMDPConfig | None = None, other_policy: OtherPolicy | None = None, seed: int = 0,
                 order: str = "engine", render_mode: str | None = None, view: str = "paper",
                 tank: TankSpace | None = None, reward: Reward | None = None) -> None:
        if num_envs < 1:
            raise ValueError(f"num_envs must be >= 1, got {num_envs}")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        cfg = make_config(turns_per_step, fire_power_actions, config, view, tank, reward)
        self._driver = AgentDriver(scenario, num_envs, seed, opponents, cfg, [0], other_policy, order)
        self.num_envs = num_envs
        self.render_mode = render_mode
        self.config = cfg
        self.single_observation_space, self.single_action_space = make_spaces(cfg)
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space, num_envs)
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, num_envs)
        self._np_random, _ = gym.utils.seeding.np_random(seed)

    def _obs(self, disc: np.ndarray, feats: np.ndarray) -> dict[str, np.ndarray] | np.ndarray:
        return agent_obs(self.config, disc[:, 0], feats[:, 0])

    def reset(self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, np.ndarray] | np.ndarray, dict[str, Any]]:
        """New battles in every sub-environment (reseeded when ``seed`` is given)."""
        if isinstance(seed, list):
            seed = seed[0]
        if seed is not None:
            self._np_random, _ = gym.utils.seeding.np_random(seed)
            disc, feats = self._driver.env.reset(seed=seed)
        else:
            disc, feats = self._driver.env.restart(np.ones(self.num_envs, dtype=bool))
        return self._obs(disc, feats), {}

    def step(self, actions: Any) -> tuple[dict[str, np.ndarray] | np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, Any]]:
        """Hold each sub-environment's action for T turns; ended episodes restart at once."""
        a = action_indices(self.config, actions, self.num_envs).reshape(self.num_envs, 1)
        drv = self._driver
        res = drv.env.step(drv.full_actions(a, self.np_random))
        rewards = res.rewards[:, 0].sum(axis=1)
        truncated = res.truncated.copy()
        terminated = res.terminated[:, 0] & ~truncated
        ended = terminated | truncated
        info: dict[str, Any] = {"score": drv.env.arena.state.score[:, 0].copy(), "score_parts": SCORE_PARTS}
        obs = self._obs(res.discrete, res.features)
        if ended.any():
            final = np.empty(self.num_envs, dtype=object)
            for i in np.flatnonzero(ended):
                final[i] = agent_obs(self.config, res.discrete[i, 0], res.features[i, 0])
            info["final_obs"] = final
            info["_final_obs"] = ended
            info["team_score"] = drv.team_score()
            info["_team_score"] = ended
            obs = self._obs(*drv.env.restart(ended))
        return obs, rewards, terminated, truncated, info

    def render(self) -> tuple[np.ndarray, ...] | None:
        """RGB frames of every battle (rgb_array mode)."""
        if self.render_mode != "rgb_array":
            return None
        from .render import draw_frame

        sc = self._driver.env.scenario
        return tuple(draw_frame(self._driver.frame(b), sc.width, sc.height) for b in range(self.num_envs))
