"""Watching battles in Robocode's own window (``EngineOptions.visible``, ``--watch``): the window shows while the
battle plays, the battle is the headless one, and without a display or the engine the user gets one line."""

from __future__ import annotations

import json
import threading
import time
from dataclasses import replace
from pathlib import Path

import pytest
from click.testing import CliRunner

from confront.cli.main import cli
from confront.engine.battle import scenario_battle
from confront.engine.install import EngineInstall
from confront.engine.runner import EngineOptions, run_battle


def _lit_pixels(display: str) -> int:
    """How many pixels of the virtual screen are not black (Xvfb's empty screen is all black)."""
    from PIL import ImageGrab

    gray = ImageGrab.grab(xdisplay=display).convert("L")
    return sum(gray.point(lambda v: 255 if v > 0 else 0).histogram()[1:])


def _turns(trace: Path) -> list[dict]:
    """The trace's per-turn states (positions, headings, energies, bullets)."""
    lines = [json.loads(line) for line in trace.read_text().splitlines()]
    return [ln for ln in lines if ln["type"] == "turn"]


@pytest.mark.xdist_group("display")  # one virtual display at a time
def test_visible_battle_shows_the_window_and_plays_the_headless_battle(install: EngineInstall, display: str,
                                                                        monkeypatch: pytest.MonkeyPatch,
                                                                        tmp_path: Path) -> None:
    spec = replace(scenario_battle("1v1", "Fire", "SpinBot", rounds=1), max_turns=120)  # 4 s at 30 TPS
    headless = run_battle(spec, EngineOptions(seed=1), install=install, trace=tmp_path / "headless.jsonl")
    monkeypatch.setenv("DISPLAY", display)
    assert _lit_pixels(display) == 0
    lit: list[int] = []

    def watch() -> None:  # what a person would see while the battle plays
        while not done.is_set():
            lit.append(_lit_pixels(display))
            time.sleep(0.3)

    done = threading.Event()
    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        t0 = time.perf_counter()
        shown = run_battle(spec, EngineOptions(seed=1, visible=True), install=install, trace=tmp_path / "shown.jsonl")
        wall = time.perf_counter() - t0
    finally:
        done.set()
        watcher.join()
    assert max(lit) > 100_000  # a window of Robocode's size (913 x 665 here) was drawn
    assert wall > 120 / 60  # at display speed (30 TPS by default), not as fast as it can
    assert shown.stopped_at_turn == headless.stopped_at_turn == 120
    turns = _turns(tmp_path / "headless.jsonl")
    energies = [[r["energy"] for r in t["robots"]] for t in (turns[0], turns[-1])]
    assert len(turns) >= 119 and energies[1] != energies[0]  # bullets have hit by then
    assert _turns(tmp_path / "shown.jsonl") == turns  # the same battle, turn by turn


def test_watch_needs_the_engine_and_a_display(monkeypatch: pytest.MonkeyPatch) -> None:
    runner = CliRunner()
    res = runner.invoke(cli, ["battle", "--watch", "--rounds", "1"])
    assert res.exit_code == 2
    assert "--watch shows Robocode's own battle window: use it with --engine robocode" in res.output
    monkeypatch.delenv("DISPLAY", raising=False)
    res = runner.invoke(cli, ["battle", "--engine", "robocode", "--watch", "--robots", "SpinBot,Walls"])
    assert res.exit_code == 2
    assert "--watch needs a display, and DISPLAY is not set" in res.output
    with pytest.raises(ValueError, match="a visible battle needs a display"):
        run_battle(scenario_battle("1v1", "SpinBot", "Walls", rounds=1), EngineOptions(visible=True))
