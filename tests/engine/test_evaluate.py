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
from confront.train.factory import train_run
from confront.train.paper_model import load_model
from confront.train.spec import load_experiment


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


def test_sim_evaluate_keeps_each_battles_first_rounds(tmp_path: Path) -> None:
    from collections import Counter

    cfg = load_experiment("demo", ["arena.scenario=1v1", "opponent.kind=Walls", "learner.kind=ssaq",
                                   "train.rounds=4", "train.session_rounds=4", "train.checkpoint_every=4",
                                   "train.replay=false", "arena.battles=4"])
    run = tmp_path / "run"
    train_run(cfg, run, progress=False)
    learner, _ = load_model(run)
    cfg = _run_config(run)
    six = sim_evaluate(cfg, learner, "Walls", 6, 5, battles=4)
    ten = sim_evaluate(cfg, learner, "Walls", 10, 5, battles=4)
    # 6 rounds over 4 battles: 2, 2, 1, 1 whatever their lengths; 10: 3, 3, 2, 2
    assert Counter(r["battle"] for r in six) == {0: 2, 1: 2, 2: 1, 3: 1}
    assert Counter(r["battle"] for r in ten) == {0: 3, 1: 3, 2: 2, 3: 2}
    assert [r["round"] for r in six] == [1, 2, 3, 4, 5, 6]
    # the same seed replays the same battles: the shorter run is a prefix of each battle's rounds
    for b in range(4):
        short = [(r["turns"], r["score_ours"]) for r in six if r["battle"] == b]
        long = [(r["turns"], r["score_ours"]) for r in ten if r["battle"] == b]
        assert long[:len(short)] == short
    with pytest.raises(ValueError, match="rounds"):
        sim_evaluate(cfg, learner, "Walls", 0, 5)


@pytest.mark.engine
def test_engine_bridge_mode_plays_the_exported_robots_battle(install) -> None:
    """The Python twin asked every T turns, the controller in Java: the same battle as the compiled robot."""
    import numpy as np

    from confront.engine.evaluate import evaluate_policy
    from confront.engine.export import ExportedPolicy

    policy = ExportedPolicy("qtable", q=np.random.default_rng(4).normal(size=(320, 4)), step_turns=10)
    exported, r_export = evaluate_policy(policy, "1v1", "SittingDuck", rounds=1, seed=1, mode="export")
    bridged, r_bridge = evaluate_policy(policy, "1v1", "SittingDuck", rounds=1, seed=1, mode="bridge")
    ours = next(c for c in bridged.contestants if c.name.startswith("confront.BridgeBot"))
    ref = next(c for c in exported.contestants if c.name.startswith("confront.PolicyBot"))
    assert ours.bullet_dmg > 0 and ours.firsts == 1  # it aims with the robot's own controller and wins
    # identical seeded battle (no skipped turn expected at the bridge's 100 ms per turn on a 1-round battle)
    assert (ours.total, ours.bullet_dmg, ours.survival) == (ref.total, ref.bullet_dmg, ref.survival)
    assert r_bridge == pytest.approx(r_export)
