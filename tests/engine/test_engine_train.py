"""Training in the real engine: per-round rows from the runner's scores, config checks, a short live run."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from confront.engine.results import parse_results_text
from confront.engine.train import ENGINE_PARTS, round_rows, train_in_engine
from confront.experiments.spec import load_experiment
from confront.experiments.train import load_model


def _robot(contestant: int, alive: bool, **parts: float) -> dict[str, Any]:
    current = {k: 0.0 for k in ENGINE_PARTS.values()}
    current.update(parts)
    current["total"] = sum(v for k, v in current.items() if k != "total")
    return {"contestant": contestant, "alive": alive, "current": current}


def test_round_rows_by_hand() -> None:
    scores = [
        # round 1: our two tanks survive, theirs dies: we get 2 x 50 survival + 2 x 10 bonus, 60 + 12 bullets
        {"round": 0, "turns": 700, "robots": [
            _robot(0, True, survival=50.0, surv_bonus=10.0, bullet_dmg=60.0, bullet_bonus=12.0),
            _robot(0, True, survival=50.0, surv_bonus=10.0, ram_dmg=2.4),
            _robot(1, False, bullet_dmg=30.0)]},
        # round 2: both sides still have a robot alive (undecided), nobody wins
        {"round": 1, "turns": 900, "robots": [
            _robot(0, True, bullet_dmg=4.0), _robot(0, False), _robot(1, True, bullet_dmg=16.0)]},
    ]
    r1, r2 = round_rows(scores)
    assert r1["round"] == 1 and r2["round"] == 2 and r1["turns"] == 700
    assert r1["score_ours"] == pytest.approx(100 + 20 + 60 + 12 + 2.4)
    assert r1["score_theirs"] == pytest.approx(30.0)
    assert r1["score_ratio"] == pytest.approx(194.4 / 224.4)
    assert r1["defensive_ours"] == pytest.approx(120.0) and r1["defensive_theirs"] == 0.0
    assert r1["survival_ours"] == 100.0 and r1["last_survivor_ours"] == 20.0
    assert r1["bullet_kill_bonus_ours"] == 12.0 and r1["ram_damage_ours"] == pytest.approx(2.4)
    assert r1["decided"] and r1["won"] and (r1["alive_ours"], r1["alive_theirs"]) == (2, 0)
    assert not r2["decided"] and not r2["won"] and (r2["alive_ours"], r2["alive_theirs"]) == (1, 1)
    assert r2["score_ratio"] == pytest.approx(0.2)
    with pytest.raises(ValueError, match="contestant 3"):
        round_rows(scores, ours=3)


@pytest.mark.parametrize(("override", "match"), [
    ("arena.scenario=big.toml", "arena.scenario"),
    ("arena.fire_power_actions=true", "fire_power_actions"),
    ("opponent.kind=NoSuchBot", "opponent.kind"),
    ("transfer.source=runs/x", "transfer.source"),
])
def test_bad_config_is_refused_before_anything_runs(tmp_path: Path, override: str, match: str) -> None:
    cfg = load_experiment("demo", ["train.rounds=2", "train.session_rounds=1", override])
    with pytest.raises(ValueError, match=match):
        train_in_engine(cfg, tmp_path / "run", progress=False)
    assert not (tmp_path / "run").exists()


@pytest.mark.engine
def test_learner_trains_in_engine_into_a_run_folder(install, tmp_path: Path) -> None:
    rounds = 3
    cfg = load_experiment("demo", ["arena.scenario=1v1", "opponent.kind=SittingDuck", "learner.kind=ssaq",
                                   f"train.rounds={rounds}", "train.session_rounds=1", "arena.decision_turns=4",
                                   "train.seed=3"])
    out = tmp_path / "run"
    summary = train_in_engine(cfg, out, progress=False)
    with open(out / "metrics" / "rounds.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == rounds and [int(r["round"]) for r in rows] == [1, 2, 3]
    # per-round score parts add up to the engine's own battle totals (its results file rounds half up)
    res = parse_results_text((out / "engine" / "results.txt").read_text())
    ours = next(c for c in res.contestants if c.name.startswith("confront.BridgeBot"))
    duck = next(c for c in res.contestants if c.name == "sample.SittingDuck")
    for side, row in (("ours", ours), ("theirs", duck)):
        for part, key in ENGINE_PARTS.items():
            assert sum(float(r[f"{part}_{side}"]) for r in rows) == pytest.approx(getattr(row, key), abs=0.5)
        assert sum(float(r[f"score_{side}"]) for r in rows) == pytest.approx(row.total, abs=0.5)
    assert ours.total > 0  # it hit the duck
    assert summary["rounds"] == rounds and summary["sessions"] == rounds
    assert summary["bridge_failures"] == [] and summary["bridge_errors"] == []
    assert summary["updates"] > 20 and summary["learner"]["updates"] == summary["updates"]
    assert json.loads((out / "summary.json").read_text())["updates"] == summary["updates"]
    learner, info = load_model(out)
    assert info["engine"] == "robocode" and learner.step == summary["updates"]
    assert np.ptp(learner.state_dict()["q"]) > 0  # the saved Q table moved away from its constant start
    assert (out / "config.toml").exists() and (out / "metrics" / "sessions.csv").exists()
