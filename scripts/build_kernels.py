"""Build ``confront/arena/prebuilt/<PREBUILT>/``: numba's cache files of the arena kernels Python calls, compiled
ahead of time for the x86-64-v3 CPU level, which :class:`confront.arena.kernel_cache.KernelCache` loads when
numba's own cache misses (a fresh machine then loads the kernels instead of compiling them; docs/arena.md,
"First-use compile time").

Run it after changing a kernel module (``kernel_cache.KERNEL_MODULES``): the files are keyed by a digest of
their sources, and ``tests/arena/test_prebuilt_kernels.py`` fails until it is rebuilt. It runs the
workloads below twice in fresh processes (``NUMBA_CPU_NAME=x86-64-v3``, one empty ``NUMBA_CACHE_DIR``): the
kernels the second run loads from the cache the first one filled (those Python calls, which hold their callees)
are copied (a few CPU-minutes; about 3.1 MB). The vectorized ufuncs of observe.py are not among them: they
compile at import (well under a second; their callees are shipped).

Usage: python scripts/build_kernels.py
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def workload() -> None:
    """Run the usual entry points once; print the cache file bases of the kernels loaded from numba's cache (in
    the second run, with the cache the first one filled: the kernels Python calls, which hold their callees)."""
    import numpy as np
    from numba.core import compiler
    from numba.core.dispatcher import Dispatcher

    reduce = compiler.CompileResult._reduce

    def reduce_without_listing(self: compiler.CompileResult) -> tuple:
        """numba's cache entry without the typed-IR listing (``inspect_types``), which names this machine's paths
        (source files, numpy's and Python's install folders); the code does not use it."""
        out = reduce(self)
        return (*out[:6], "", *out[7:])

    compiler.CompileResult._reduce = reduce_without_listing

    from confront.arena import control
    from confront.arena.bots import ScriptedBots, bot_battle
    from confront.arena.core import Arena
    from confront.arena.gym_env import BattleEnv
    from confront.arena.observe import ObservationConfig
    from confront.arena.pool import PoolEntry, PoolEnv
    from confront.arena.pz_env import parallel_env
    from confront.arena.scenarios import get_scenario
    from confront.arena.smdp import SMDPConfig, TeamBattleEnv
    from confront.arena.tank import MEMORY_ROWS, TankSpace
    from confront.arena.vector_env import BattleVectorEnv

    rng = np.random.default_rng(0)

    def paper(disc: np.ndarray, feats: np.ndarray, r: np.random.Generator) -> np.ndarray:
        return r.integers(0, 4, size=len(disc))

    # the PPO tanks' league (confront demo, confront train -c tanks): tank view, score reward, paper-move opponents
    tank = SMDPConfig(turns_per_step=5, tank=TankSpace(), reward="score",
                      observation=ObservationConfig(sensing="scanned"))
    pool = PoolEnv([PoolEntry("1v1:dodge", "1v1", "td", 2, policy=paper, opponent_actions="paper"),
                    PoolEntry("4v4:td", "4v4", "td", 2, policy=paper, opponent_actions="paper"),
                    PoolEntry("1v1:SpinBot", "1v1", "SpinBot", 2), PoolEntry("4v4:Walls", "4v4", "Walls", 2),
                    PoolEntry("1v1:SurfVG", "1v1", "SurfVG", 2), PoolEntry("4v4:OrbitGF", "4v4", "OrbitGF", 2),
                    PoolEntry("4v4:self", "4v4", "td", 2, policy=lambda d, f, r: r.integers(0, 4, size=len(d)))],
                   tank, seed=0)
    pool.reset()
    for _ in range(3):
        pool.step(rng.integers(0, int(np.prod(pool.action_dims)), size=pool.n_agents))
    # the paper's learners (TD team pre-training, confront reproduce): paper state and moves, Eq. 35
    for opp in ("SpinBot", "td"):
        env = TeamBattleEnv("4v4", n_battles=4, seed=0, opponents=opp, config=SMDPConfig())
        env.reset()
        for _ in range(3):
            env.step(rng.integers(0, env.config.n_actions, size=(env.n_battles, env.n_robots)))
    # the tank's skills (confront.arena.tank): the technique brain in the SMDP step, the knowledge block on reset
    skills = TankSpace(leads=("none", "gf"), surf=True, knowledge=True)
    env = TeamBattleEnv("1v1", n_battles=2, seed=0, opponents="SpinBot",
                        config=SMDPConfig(turns_per_step=5, tank=skills, reward="score"))
    env.reset()
    for _ in range(3):
        env.step(rng.integers(0, env.config.n_actions, size=(env.n_battles, env.n_robots)))
    # the arena alone, scripted battles, the Gymnasium / PettingZoo envs
    arena = Arena("4v4", 4, seed=0)
    arena.step(arena.idle_commands())
    arena.reset(np.ones(4, dtype=bool))
    bots = ScriptedBots(arena, ["SpinBot", "Walls", "Tracker", "RamFire", "Crazy", "Fire", "Corners", "TrackFire"])
    bots.play(3)
    bots.commands(arena.idle_commands())
    bot_battle(["Tracker", "RamFire"], 2, seed=0, n_battles=2)
    from confront.arena.tech import tech_battle  # the technique robots (confront battle --robots SurfGF,...)

    tech_battle(["SurfGF", "SpinBot"], 1, seed=0, scenario=get_scenario("1v1"))
    cmd = arena.idle_commands()  # the Python controller (control.py) with and without scan memory
    memory = np.zeros((arena.n_battles, MEMORY_ROWS, arena.n_robots, arena.n_robots))
    control.remember(memory, arena)
    control.gun_radar_commands(arena, cmd, memory=memory)
    control.gun_radar_commands(arena, cmd)
    env = BattleEnv(scenario="1v1", opponents="SpinBot")
    env.reset(seed=0)
    env.step(0)
    venv = BattleVectorEnv(num_envs=2)
    venv.reset(seed=0)
    venv.step(np.zeros(2, dtype=np.int64))
    penv = parallel_env("4v4", opponents="SpinBot")
    penv.reset(seed=0)
    penv.step({a: 0 for a in penv.agents})
    # the Python twins of the exported robots in the engine (confront evaluate --engine robocode, confront export)
    from confront.engine import tank_export
    from confront.engine.bridge import Observation, Scan
    from confront.engine.export import ExportedPolicy

    me = Observation("me", (), 0, 1, 400.0, 300.0, 1.0, 0.0, 0.0, 0.0, 100.0, 0.0, 1, 0.0, 800.0, 600.0,
                     (Scan("e", 0, False, 0.0, 230.0, 0.0, 0.0, 50.0, 500.0, 400.0),))
    ExportedPolicy("qtable", q=np.zeros((320, 4)))(me)
    row = (500.0, 400.0, 50.0, 0.5, 4.0, 0.0, 0.0, 0.01)
    tank_export.robot_view((400.0, 300.0, 1.0, 0.0, 100.0, 0.0), (1, 1, 0, 0), [row], [], 5.0, 800.0, 600.0,
                           TankSpace())
    tank_export.robot_control(control.ControlConfig(), "circular", 400.0, 300.0, 0.0, 0.0, 0.0, 100.0, [row], 0, 2.0,
                              5.0, 800.0, 600.0)
    tank_export.turn_rate(row, 0.7, 9.0)
    kernels = [obj for name, mod in list(sys.modules.items()) if name.startswith("confront.arena.")
               for obj in vars(mod).values() if isinstance(obj, Dispatcher) and obj.py_func.__module__ == name]
    loaded = {k._cache._impl.filename_base for k in kernels if sum(k._cache_hits.values())}
    print(json.dumps({"kernels": sorted({k._cache._impl.filename_base for k in kernels}), "loaded": sorted(loaded)}))


def main() -> None:
    if sys.argv[1:] == ["--workload"]:
        workload()
        return
    sys.path.insert(0, str(ROOT))
    from confront.arena import kernel_cache as kc

    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, NUMBA_CPU_NAME=kc.TARGET_CPU, NUMBA_CPU_FEATURES="", NUMBA_CACHE_DIR=tmp,
                   **{kc.OFF_ENV: "0"}, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
        def run() -> dict:
            out = subprocess.run([sys.executable, __file__, "--workload"], env=env, check=True, capture_output=True,
                                 text=True, cwd=ROOT).stdout
            return json.loads(out.strip().splitlines()[-1])

        kernels = run()["kernels"]  # compiles everything
        for p in Path(tmp).rglob("*.nb[ic]"):  # the vectorized ufuncs' caches: rebuilt at import, from the kernels
            if not p.name.startswith(tuple(b + "." for b in kernels)):
                p.unlink()
        bases = run()["loaded"]
        dest = kc.HERE / "prebuilt" / kc.PREBUILT
        if dest.parent.is_dir():
            shutil.rmtree(dest.parent)
        dest.mkdir(parents=True)
        for base in bases:  # each kernel's index (base.nbi) and data files (base.N.nbc)
            for f in Path(tmp).rglob(f"{base}.*"):
                if re.fullmatch(re.escape(base) + r"\.(nbi|\d+\.nbc)", f.name):
                    shutil.copyfile(f, dest / f.name)
        manifest = {"sources": kc.sources_digest(), "numba": kc.numba.__version__, "python": sys.version.split()[0],
                    "platform": f"{sys.platform}-{kc.platform.machine()}", "cpu": kc.TARGET_CPU, "kernels": bases,
                    "built_by": "scripts/build_kernels.py"}
        (dest / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    size = sum(f.stat().st_size for f in dest.iterdir())
    print(f"{dest.relative_to(ROOT)}: {len(bases)} kernels, {size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
