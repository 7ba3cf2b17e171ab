"""``confront evaluate``: the simulator column and its spread over seeds (the engine half: test_export.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from confront.experiments.evaluate import (
    _run_config,
    disjoint_seeds,
    evaluate_cli,
    results_from_rows,
    sim_evaluate,
    sim_ratios,
)
from confront.experiments.spec import load_experiment
from confront.experiments.train import load_model, train_run


def test_evaluate_table_has_the_simulator_ratio_and_its_seed_range(tmp_path: Path, capsys) -> None:
    cfg = load_experiment("demo", ["arena.scenario=1v1", "opponent.kind=SpinBot", "learner.kind=ssaq",
                                   "train.rounds=8", "train.session_rounds=4", "train.checkpoint_every=8",
                                   "train.replay=false", "arena.battles=4"])
    run = tmp_path / "run"
    train_run(cfg, run, progress=False)
    evaluate_cli(run, "sim", "SpinBot,Walls", rounds=6, seed=3, sim_seeds=3)
    table = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("| SpinBot |") or
             ln.startswith("| Walls |")]
    assert len(table) == 2
    learner, _ = load_model(run)
    cfg = _run_config(run)
    for line, name in zip(table, ("SpinBot", "Walls"), strict=True):
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows = sim_evaluate(cfg, learner, name, 6, 3)
        ratio = results_from_rows(rows, ("ours", name)).score_ratio("ours")
        assert cells[1] == "6" and cells[2] == f"{ratio:.3f}"
        spread = sim_ratios(cfg, learner, name, 6, [3, 9, 15])
        assert spread[0] == ratio  # the same seed repeats exactly
        assert cells[3] == f"{min(spread):.3f}-{max(spread):.3f}"
        assert cells[4] == "" and cells[5] == ""  # no engine column without --engine robocode
    # battle b of seed s is seeded s + b: 6 rounds run in 6 battles, so the runs start 6 seeds apart
    assert disjoint_seeds(3, 3, rounds=6) == [3, 9, 15]
    assert disjoint_seeds(1, 4, rounds=100) == [1, 17, 33, 49]
    with pytest.raises(ValueError, match="sim_seeds"):
        evaluate_cli(run, "sim", "SpinBot", rounds=2, seed=0, sim_seeds=0)
