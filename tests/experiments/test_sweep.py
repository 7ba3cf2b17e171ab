"""A sweep on a local Ray runtime completes, aggregates, and resumes without re-running finished trials."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from confront.config import ConfigError
from confront.experiments.sweep import read_grid, run_sweep

ray = pytest.importorskip("ray")

GRID = """
experiment = "demo"
seeds = 1
[set]
"train.rounds" = 8
"train.session_rounds" = 4
"train.replay" = false
"arena.battles" = 4
"opponent.pretrain_rounds" = 4
[grid]
"learner.awm" = [true, false]
"""


def test_grid_validation(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(GRID.replace("[true, false]", "[true, 3]"))
    with pytest.raises(ConfigError, match="learner.awm = 3 has the wrong type"):
        read_grid(bad)
    base, trials = read_grid(_grid(tmp_path))
    assert base == "demo" and [t.name for t in trials] == ["awm=true-s0", "awm=false-s0"]


def _grid(tmp_path: Path) -> Path:
    g = tmp_path / "grid.toml"
    g.write_text(GRID)
    return g


def test_sweep_runs_and_resumes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CONFRONT_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "sweep"
    try:
        rows = run_sweep(_grid(tmp_path), out, num_cpus=2)
        assert sorted(r["point"] for r in rows) == ["awm=false", "awm=true"]
        assert all(0.0 <= r["final_score_ratio"] <= 1.0 for r in rows)
        kept = out / "trials" / "awm=true-s0" / "summary.json"
        redo = out / "trials" / "awm=false-s0" / "summary.json"
        first = json.loads(redo.read_text())
        stamp = kept.stat().st_mtime_ns
        redo.unlink()  # as if the sweep had been interrupted before this trial finished
        rows2 = run_sweep(_grid(tmp_path), out, num_cpus=2)
        assert kept.stat().st_mtime_ns == stamp  # finished trial not re-run
        assert json.loads(redo.read_text())["final_score_ratio"] == first["final_score_ratio"]
        assert rows2 == rows
        assert "final score ratio" in (out / "results.md").read_text()
    finally:
        ray.shutdown()


PPO_GRID = """
experiment = "tanks-demo"
seeds = 1
[set]
"train.rounds" = 24
"train.session_rounds" = 8
"train.checkpoint_every" = 8
"league.opponents" = ["1v1:SittingDuck", "4v4:SpinBot"]
"league.battles" = 2
"ppo.rollout_steps" = 8
[grid]
"ppo.lr" = [0.001, 0.003]
"""


def test_sweep_trains_ppo_tanks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The recommended learner goes through the same sweep: PPO trial folders with models, resumable."""
    monkeypatch.setenv("CONFRONT_CACHE", str(tmp_path / "cache"))
    g = tmp_path / "grid.toml"
    g.write_text(PPO_GRID)
    out = tmp_path / "sweep"
    try:
        rows = run_sweep(g, out, num_cpus=2)
        assert sorted(r["point"] for r in rows) == ["lr=0.001", "lr=0.003"]
        for name in ("lr=0.001-s0", "lr=0.003-s0"):
            trial = out / "trials" / name
            summary = json.loads((trial / "summary.json").read_text())
            assert summary["learner"] == "ppo" and summary["rounds"] >= 24
            assert json.loads((trial / "model" / "model.json").read_text())["kind"] == "ppo"
            assert (trial / "model" / "actor.npz").is_file()
            assert any((trial / "checkpoints").glob("round-*"))  # league snapshots and learner as data
        fast = json.loads((out / "trials" / "lr=0.003-s0" / "summary.json").read_text())
        assert 0.0 <= fast["final_score_ratio"] <= 1.0
    finally:
        ray.shutdown()
