"""The kernel cache (confront/arena/kernel_cache.py): every cached kernel is stamped with all kernel sources, and
the kernels shipped in confront/arena/prebuilt (scripts/build_kernels.py) match the sources and cover the demo:
with an empty numba cache its league loads its kernels, nothing compiles (docs/arena.md, "First-use compile
time")."""

import importlib
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from numba.core.caching import FunctionCache
from numba.core.dispatcher import Dispatcher

from confront.arena import kernel_cache as kc

PREBUILT = kc.HERE / "prebuilt" / kc.PREBUILT


def test_every_cached_kernel_has_the_kernel_cache() -> None:
    n = 0
    for name in kc.KERNEL_MODULES:
        mod = importlib.import_module(f"confront.arena.{name}")
        for obj in vars(mod).values():
            if isinstance(obj, Dispatcher) and obj.py_func.__module__ == mod.__name__:
                assert isinstance(obj._cache, FunctionCache) and isinstance(obj._cache, kc.KernelCache), obj
                assert obj._cache._cache_file._source_stamp == kc.sources_digest()
                n += 1
    assert n > 50


def test_shipped_kernels_match_the_sources() -> None:
    if not PREBUILT.is_dir():
        pytest.skip(f"no shipped kernels for this platform and these versions ({kc.PREBUILT})")
    meta = json.loads((PREBUILT / "manifest.json").read_text())
    assert meta["sources"] == kc.sources_digest(), "a kernel module changed: run python scripts/build_kernels.py"


def test_shipped_kernels_name_no_paths_of_the_machine_that_built_them() -> None:
    if not PREBUILT.is_dir():
        pytest.skip(f"no shipped kernels for this platform and these versions ({kc.PREBUILT})")
    for f in PREBUILT.iterdir():
        data = f.read_bytes()
        for part in (b"confront/arena/", b"site-packages", b"lib/python3", b"lib-dynload"):
            assert part not in data, (f.name, part)


# the arena kernels numba compiles in a subprocess (each script prints its result as the last line)
COMPILES = textwrap.dedent("""
    import json
    import numpy as np
    from numba.core import event

    compiled = []

    class Compiles(event.Listener):
        def on_start(self, ev):
            f = ev.data["dispatcher"].py_func
            if f.__module__.startswith("confront.arena."):
                compiled.append(f.__qualname__)

        def on_end(self, ev):
            pass

    event.register("numba:compile", Compiles())
""")

def _last_line(script: str, env: dict[str, str]) -> object:
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


SCRIPT = COMPILES + textwrap.dedent("""
    from confront.arena.smdp import TeamBattleEnv
    from confront.train import league
    from confront.train.paper_model import smdp_config
    from confront.train.spec import load_experiment

    cfg = load_experiment("tanks-demo", ())
    # the TD team's pre-training env, then the league with a stand-in for the trained TD team
    env = TeamBattleEnv("4v4", n_battles=2, seed=0, opponents=cfg.opponent.pretrain_against, config=smdp_config(cfg))
    env.reset()
    env.step(np.zeros((2, env.n_robots), dtype=np.int64))
    league.td_policy = lambda cfg, progress: league.random_policy
    pool, _ = league.build_pool(cfg, 0, battles=2)
    pool.reset()
    for _ in range(2):
        pool.step(np.zeros(pool.n_agents, dtype=np.int64))
    print(json.dumps(compiled))
""")


def test_demo_loads_its_kernels_without_compiling(tmp_path: Path) -> None:
    if kc.prebuilt_dir() is None:
        pytest.skip("the shipped kernels do not apply here (platform, numba / Python version, CPU, or sources)")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    env.pop(kc.OFF_ENV, None)
    assert _last_line(SCRIPT, env) == []


def test_the_shipped_kernels_are_refused_when_they_do_not_match(monkeypatch: pytest.MonkeyPatch) -> None:
    if not PREBUILT.is_dir():
        pytest.skip(f"no shipped kernels for this platform and these versions ({kc.PREBUILT})")
    usable = kc.prebuilt_dir()
    monkeypatch.setattr(kc, "TARGET_FEATURES", (*kc.TARGET_FEATURES, "no-such-feature"))  # a CPU without them
    kc.prebuilt_dir.cache_clear()
    assert kc.prebuilt_dir() is None
    monkeypatch.undo()
    for off in ("0", "false", " Off "):
        monkeypatch.setenv(kc.OFF_ENV, off)
        kc.prebuilt_dir.cache_clear()
        assert kc.prebuilt_dir() is None
    monkeypatch.setenv(kc.OFF_ENV, "1")
    kc.prebuilt_dir.cache_clear()
    assert kc.prebuilt_dir() == usable
    monkeypatch.undo()
    kc.prebuilt_dir.cache_clear()
    monkeypatch.setattr(kc, "sources_digest", lambda: "0" * 64)  # a kernel module edited
    assert kc.prebuilt_dir() is None
    monkeypatch.undo()
    kc.prebuilt_dir.cache_clear()
    monkeypatch.setattr(kc, "PREBUILT", kc.PREBUILT.replace(f"numba-{kc.numba.__version__}", "numba-0.0.0"))
    assert kc.prebuilt_dir() is None  # another numba (or Python, or platform): no folder of that name
    monkeypatch.undo()
    kc.prebuilt_dir.cache_clear()
    assert kc.prebuilt_dir() == usable


RESULTS = COMPILES + textwrap.dedent("""
    import hashlib
    from confront.arena import kernel_cache
    from confront.arena.bots import bot_battle
    from confront.arena.pool import PoolEntry, PoolEnv
    from confront.arena.smdp import SMDPConfig, TeamBattleEnv
    from confront.arena.tank import TankSpace

    h = hashlib.sha256()

    def feed(result):
        for v in vars(result).values():
            h.update(np.ascontiguousarray(v).tobytes() if isinstance(v, np.ndarray) else repr(v).encode())

    parts, placements = bot_battle(["SpinBot", "Walls", "Tracker", "RamFire", "Walls", "Crazy", "Fire", "Corners"],
                                   3, seed=3, n_battles=2)
    h.update(parts.tobytes() + placements.tobytes())
    env = TeamBattleEnv("4v4", n_battles=3, seed=1, opponents="SpinBot", config=SMDPConfig())
    rng = np.random.default_rng(0)
    for a in env.reset():
        h.update(np.ascontiguousarray(a).tobytes())
    for _ in range(20):
        feed(env.step(rng.integers(0, 4, size=(3, env.n_robots))))
    pool = PoolEnv([PoolEntry("1v1/td", "1v1", "td", 2, policy=lambda d, f, r: r.integers(0, 4, size=len(d)),
                              opponent_actions="paper"), PoolEntry("4v4/Walls", "4v4", "Walls", 2)],
                   SMDPConfig(turns_per_step=5, tank=TankSpace(), reward="score"), seed=0)
    pool.reset()
    for _ in range(20):
        feed(pool.step(rng.integers(0, int(np.prod(pool.action_dims)), size=pool.n_agents)))
    print(json.dumps({"hash": h.hexdigest(), "compiled": compiled,
                      "shipped": kernel_cache.prebuilt_dir() is not None}))
""")


def _results(env: dict[str, str]) -> dict:
    return _last_line(RESULTS, env)  # type: ignore[return-value]


def test_shipped_and_compiled_kernels_give_the_same_results(tmp_path: Path) -> None:
    """Seeded battles, team-env and pool steps hash the same with the shipped kernels (an empty numba cache) and
    with kernels numba compiled on this machine (the shipped ones turned off: what a machine they do not fit does)."""
    if kc.prebuilt_dir() is None:
        pytest.skip("the shipped kernels do not apply here (platform, numba / Python version, CPU, or sources)")
    shipped = _results(dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path)))
    compiled = _results({k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"} | {kc.OFF_ENV: "0"})
    assert shipped["shipped"] and shipped["compiled"] == []
    assert not compiled["shipped"]
    assert shipped["hash"] == compiled["hash"]
