"""confront: fuzzy RL and curriculum transfer for teams of Robocode tanks.

``gymnasium.make("confront/Battle-v0", scenario=..., opponents=...)`` for one tank,
``confront.parallel_env(scenario="4v4", opponents=...)`` for a team (PettingZoo).
"""

import os as _os
from typing import Any

# OpenMP workers (torch's update threads) sleep as soon as they wait instead of spinning, unless the user set a
# policy: on a machine whose cores are taken, spinning workers made PPO training 2.2x slower (docs/learning.md).
# It must be set before torch loads its OpenMP runtime, hence here, first.
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import gymnasium as _gym  # noqa: E402

__version__ = "0.1.0"

if "confront/Battle-v0" not in _gym.registry:
    _gym.register(id="confront/Battle-v0", entry_point="confront.arena.gym_env:BattleEnv")


def parallel_env(scenario: str = "4v4", opponents: Any = None, **kwargs: Any) -> Any:
    """A PettingZoo ParallelEnv of a team (see :mod:`confront.arena.pz_env`)."""
    from confront.arena.pz_env import parallel_env as _parallel_env

    return _parallel_env(scenario=scenario, opponents=opponents, **kwargs)
