"""confront: fuzzy RL and curriculum transfer for teams of Robocode tanks.

``gymnasium.make("confront/Battle-v0", scenario=..., opponents=...)`` for one tank,
``confront.parallel_env(scenario="4v4", opponents=...)`` for a team (PettingZoo).
"""

import os as _os
from typing import Any

# torch's OpenMP workers (the PPO update's second thread, libgomp) spin 3000 times, a few microseconds, before
# they sleep, unless the user chose a wait policy: libgomp's default spins ~300k times, and beside busy cores that
# made training 4-6x slower; never spinning cost ~30% on an idle machine (docs/learning.md). Set before torch loads.
if "OMP_WAIT_POLICY" not in _os.environ:
    _os.environ.setdefault("GOMP_SPINCOUNT", "3000")
# NumPy's OpenBLAS workers likewise busy-wait 2^28 cycles (about 0.1 s) after each product; the self-play
# opponent's and the paper learners' small products then kept a core spinning beside the simulator's threads:
# 2^4 cycles instead made PPO training on the whole league 1.5x faster (docs/learning.md). Set before NumPy
# loads.
_os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", "4")

import gymnasium as _gym  # noqa: E402

__version__ = "0.1.0"

if "confront/Battle-v0" not in _gym.registry:
    _gym.register(id="confront/Battle-v0", entry_point="confront.arena.gym_env:BattleEnv")


def parallel_env(scenario: str = "4v4", opponents: Any = None, **kwargs: Any) -> Any:
    """A PettingZoo ParallelEnv of a team (see :mod:`confront.arena.pz_env`)."""
    from confront.arena.pz_env import parallel_env as _parallel_env

    return _parallel_env(scenario=scenario, opponents=opponents, **kwargs)
