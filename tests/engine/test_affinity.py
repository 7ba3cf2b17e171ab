"""One CPU per engine process: claims across engine runs, the choice of CPU, and a battle held to one CPU."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import confront.engine.affinity as affinity
from confront.engine.affinity import ONE_CPU_JVM_FLAGS, claimed_cpu, idlest_first
from confront.engine.battle import BattleSpec
from confront.engine.install import EngineInstall
from confront.engine.runner import EngineOptions, java_command, run_battle

needs_affinity = pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="needs sched_setaffinity")


@pytest.fixture
def three_cpus(monkeypatch: pytest.MonkeyPatch) -> None:
    """A process allowed CPUs 4, 5 and 6, all equally idle."""
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {4, 5, 6})
    monkeypatch.setattr(affinity, "_idle_ticks", lambda: {})


@needs_affinity
def test_concurrent_claims_take_different_cpus_until_none_is_left(three_cpus: None, tmp_path) -> None:
    with claimed_cpu(folder=tmp_path) as a, claimed_cpu(folder=tmp_path) as b, claimed_cpu(folder=tmp_path) as c:
        assert sorted([a, b, c]) == [4, 5, 6]
        with claimed_cpu(folder=tmp_path) as d:
            assert d is None  # every CPU is claimed: the engine runs unpinned
    with claimed_cpu(folder=tmp_path) as e:  # the claims ended with their blocks
        assert e == 4


@needs_affinity
def test_no_claim_when_disabled_or_with_one_cpu(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    with claimed_cpu(enabled=False, folder=tmp_path) as cpu:
        assert cpu is None
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {3})
    with claimed_cpu(folder=tmp_path) as cpu:
        assert cpu is None  # nothing to choose: pinning would change nothing
    assert not list(tmp_path.iterdir())


def test_the_idlest_cpu_comes_first(monkeypatch: pytest.MonkeyPatch) -> None:
    samples = iter([{0: 100, 1: 100, 2: 100}, {0: 101, 1: 104, 2: 102}])  # idle ticks before and after
    monkeypatch.setattr(affinity, "_idle_ticks", lambda: next(samples))
    assert idlest_first([0, 1, 2], sample_s=0.0) == [1, 2, 0]


def test_idle_ticks_are_read_per_cpu() -> None:
    if not Path("/proc/stat").is_file():
        pytest.skip("no /proc/stat")
    ticks = affinity._idle_ticks()
    assert set(ticks) >= set(os.sched_getaffinity(0)) and all(v >= 0 for v in ticks.values())


def test_c1_only_when_held_to_one_cpu(tmp_path) -> None:
    install = EngineInstall(jar=tmp_path / "robocode.jar", samples=tmp_path, java="java", javac="javac")
    opts = EngineOptions()
    assert not set(ONE_CPU_JVM_FLAGS) & set(java_command(install, tmp_path, tmp_path, opts))
    assert set(ONE_CPU_JVM_FLAGS) <= set(java_command(install, tmp_path, tmp_path, opts, one_cpu=True))


@pytest.mark.engine
@needs_affinity
def test_a_battle_held_to_one_cpu(install: EngineInstall) -> None:
    """The JVM sees one CPU, the claimed one is reported, and a battle without thread races plays the same."""
    allowed = os.sched_getaffinity(0)
    if len(allowed) < 2:
        pytest.skip("one CPU only: nothing to claim")
    spec = BattleSpec(("SpinBot", "Walls"), rounds=3)
    free = run_battle(spec, EngineOptions(seed=7))
    held = run_battle(spec, EngineOptions(seed=7, one_cpu=True))
    assert free.cpu is None and free.summary["cpus"] == len(allowed)
    if held.cpu is None:  # every CPU claimed by concurrent engine runs (parallel test workers)
        assert held.summary["cpus"] == len(allowed)
    else:
        assert held.cpu in allowed and held.summary["cpus"] == 1
    assert held.round_turns == free.round_turns
    assert held.results == free.results


@needs_affinity
def test_no_claim_without_a_writable_lock_folder(three_cpus: None, tmp_path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    with claimed_cpu(folder=blocker / "cpus") as cpu:  # a folder inside a file cannot be made
        assert cpu is None
