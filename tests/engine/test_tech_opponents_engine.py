"""The technique robots as opponents of the PPO tanks in Robocode (confront.tech.*, from the technique jar every
working directory holds)."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from confront.train.factory import train_run
from confront.train.spec import load_experiment


@pytest.mark.engine
def test_ppo_tanks_train_against_a_technique_robot_in_the_engine(install, tmp_path: Path) -> None:
    cfg = load_experiment("tanks-engine", ["league.opponents=['1v1:OrbitLinear']", "train.rounds=2",
                                           "train.session_rounds=2", "train.checkpoint_every=2", "ppo.hidden=32"])
    summary = train_run(cfg, tmp_path / "run", progress=False, engine="robocode")
    assert summary["rounds"] == 2
    with open(tmp_path / "run" / "metrics" / "rounds.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert {r["opponent"] for r in rows} == {"1v1:OrbitLinear"}
    assert sum(float(r["score_theirs"]) for r in rows) > 0  # it fought back
    results = (tmp_path / "run" / "engine" / "battle-000" / "results.txt").read_text()
    assert "confront.tech.OrbitLinear" in results, results
