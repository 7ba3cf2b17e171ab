"""The compiled kernels a PoolEnv step needs are compiled once each (one array type per kernel): every extra
signature is a second compile of the same function (docs/arena.md, "First compile"). Callees loaded with a
cached caller show 0; with an empty numba cache the test checks every kernel listed."""

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import numpy as np
    from confront.arena import observe, smdp_kernel, tank
    from confront.arena.bots import controller, registry
    from confront.arena import kernels as K
    from confront.arena.pool import PoolEntry, PoolEnv
    from confront.arena.smdp import SMDPConfig
    from confront.arena.tank import TankSpace

    config = SMDPConfig(turns_per_step=2, tank=TankSpace(), reward="score")
    entries = [PoolEntry("1v1/SpinBot", "1v1", "SpinBot", 3), PoolEntry("4v4/Walls", "4v4", "Walls", 2),
               PoolEntry("1v1/td", "1v1", "td", 2, policy=lambda d, f, rng: rng.integers(0, 4, size=len(d)),
                         opponent_actions="paper"), PoolEntry("1v1/SurfGF", "1v1", "SurfGF", 2)]
    pool = PoolEnv(entries, config, seed=0)
    pool.reset()
    rng = np.random.default_rng(0)
    for _ in range(3):
        pool.step(rng.integers(0, int(np.prod(pool.action_dims)), size=pool.n_agents))
    for f in (K.step_range, K._step_battle, controller.bots_step, controller.battle_step, controller.dispatch,
              registry.act, smdp_kernel.smdp_turns, observe.observe_kernel, observe.perceive_row, observe.target_of,
              tank.tank_view_kernel, tank.tank_view_row):
        print(f.py_func.__name__, len(f.signatures))
""")


def test_pool_kernels_compiled_once() -> None:
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True).stdout
    counts = dict(line.split() for line in out.strip().splitlines())
    # 0: loaded from numba's cache or the shipped kernels (kernel_cache.py), which hold a caller with its callees
    assert counts["smdp_turns"] == "1" and all(n in ("0", "1") for n in counts.values()), counts
