"""A short battle of sample robots in the real engine, checked against the engine's own results file."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from confront.engine.battle import BattleSpec
from confront.engine.install import JVM_FLAGS, EngineInstall
from confront.engine.runner import EngineOptions, run_battle
from confront.results import parse_results_text

pytestmark = pytest.mark.engine


def test_sample_battle_matches_engine_results_file(install: EngineInstall, tmp_path) -> None:
    spec = BattleSpec(("SpinBot", "Walls"), rounds=2)
    wd = tmp_path / "wd"
    run = run_battle(spec, EngineOptions(seed=7, cpu_constant_ms=100.0), workdir=wd)  # generous: no skips under load
    # the engine's own command line, same battle, same seed, same working directory
    battle = tmp_path / "b.battle"
    battle.write_text(spec.battle_file())
    results = tmp_path / "engine-results.txt"
    subprocess.run(
        [install.java, "-Xmx512M", f"-DWORKINGDIRECTORY={wd}", "-DRANDOMSEED=7", *JVM_FLAGS, "-cp",
         str(install.jar), "robocode.Robocode", "-battle", str(battle), "-nodisplay", "-nosound",
         "-results", str(results)],
        check=True, capture_output=True, timeout=120,
    )
    engine = parse_results_text(results.read_text())
    assert run.results_text == results.read_text()
    assert run.results.rounded().contestants == engine.contestants
    res = run.results
    assert res.rounds == 2 and len(run.round_turns) == 2 and sum(run.round_turns) == run.turns
    for row in res.contestants:
        parts = row.survival + row.surv_bonus + row.bullet_dmg + row.bullet_bonus + row.ram_dmg + row.ram_bonus
        assert row.total == pytest.approx(parts)
    assert sum(r.firsts for r in res.contestants) == 2
    assert {r.name for r in res.robots} == {"sample.SpinBot", "sample.Walls"}
    assert run.skipped_turns == {}
    assert run.robot_turns >= run.turns  # both alive for most turns


def _children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text().split()
        out += [int(c) for c in text]
    return out


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
def test_ctrl_c_stops_the_engine(install, tmp_path) -> None:
    code = ("from confront.engine.battle import BattleSpec\n"
            "from confront.engine.runner import run_battle\n"
            "run_battle(BattleSpec(('SpinBot', 'Walls'), rounds=500))\n")
    # Ctrl-C as from a terminal: a shell that started the test run in the background may have left SIGINT
    # ignored, which the child would inherit (then Python installs no KeyboardInterrupt handler)
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    java: list[int] = []
    deadline = time.monotonic() + 60
    while not java and time.monotonic() < deadline:  # wait for the engine process to start
        java = [c for c in _children(proc.pid) if "java" in Path(f"/proc/{c}/cmdline").read_bytes().decode()]
        time.sleep(0.1)
    assert java, "the engine did not start"
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode != 0 and b"KeyboardInterrupt" in err
    for _ in range(50):  # the kill is immediate; give the kernel a moment to reap
        if not Path(f"/proc/{java[0]}").exists():
            break
        time.sleep(0.1)
    assert not Path(f"/proc/{java[0]}").exists()
