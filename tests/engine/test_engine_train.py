"""Training in the real engine: per-round rows from the runner's scores, config checks, a short live run."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from confront import checkpoint as ck
from confront.checkpoint import CheckpointError
from confront.learning.tabular import TabularParams, TabularQ
from confront.results import parse_results_text
from confront.train import paper_engine
from confront.train.engine_logs import ENGINE_PARTS, round_rows
from confront.train.factory import train_run
from confront.train.league import td_learner
from confront.train.paper_model import load_model, save_model
from confront.train.spec import load_experiment


def _robot(contestant: int, alive: bool, **parts: float) -> dict[str, Any]:
    score = {k: 0.0 for k in ENGINE_PARTS.values()}
    score.update(parts)
    score["total"] = sum(v for k, v in score.items() if k != "total")
    return {"contestant": contestant, "alive": alive, "score": score}


def test_round_rows_by_hand() -> None:
    scores = [
        # after round 1: our two tanks survive, theirs dies: 2 x 50 survival + 2 x 10 bonus, 60 + 12 bullets
        {"round": 0, "turns": 700, "robots": [
            _robot(0, True, survival=50.0, surv_bonus=10.0, bullet_dmg=60.0, bullet_bonus=12.0),
            _robot(0, True, survival=50.0, surv_bonus=10.0, ram_dmg=2.4),
            _robot(1, False, bullet_dmg=30.0)]},
        # after round 2 (battle totals): both sides still have a robot alive (undecided); bullets 4 and 16
        {"round": 1, "turns": 900, "robots": [
            _robot(0, True, survival=50.0, surv_bonus=10.0, bullet_dmg=64.0, bullet_bonus=12.0),
            _robot(0, False, survival=50.0, surv_bonus=10.0, ram_dmg=2.4),
            _robot(1, True, bullet_dmg=46.0)]},
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
    assert (r2["score_ours"], r2["score_theirs"]) == pytest.approx((4.0, 16.0))
    assert r2["score_ratio"] == pytest.approx(0.2) and r2["defensive_ours"] == 0.0
    with pytest.raises(ValueError, match="contestant 3"):
        round_rows(scores, ours=3)
    with pytest.raises(ValueError, match="2 robots, the round before 3"):
        round_rows([scores[0], {**scores[1], "robots": scores[1]["robots"][:2]}])


@pytest.mark.parametrize(("override", "error", "match"), [
    ("arena.scenario=big.toml", ValueError, "arena.scenario"),
    ("arena.fire_power_actions=true", ValueError, "fire_power_actions"),
    ("opponent.kind=NoSuchBot", ValueError, "opponent.kind"),
    ("transfer.source=no/such/run", FileNotFoundError, "no trained model"),
])
def test_bad_config_is_refused_before_anything_runs(tmp_path: Path, override: str, error: type[Exception],
                                                    match: str) -> None:
    with pytest.raises(error, match=match):  # a scenario file or robot that does not exist: already on load
        cfg = load_experiment("demo", ["train.rounds=2", "train.session_rounds=1", override])
        train_run(cfg, tmp_path / "run", progress=False, engine="robocode")
    assert not (tmp_path / "run").exists()


@pytest.mark.engine
def test_learner_trains_in_engine_into_a_run_folder(install, tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    rounds = 3
    cfg = load_experiment("demo", ["arena.scenario=1v1", "opponent.kind=SittingDuck", "learner.kind=ssaq",
                                   f"train.rounds={rounds}", "train.session_rounds=1", "arena.decision_turns=4",
                                   "train.seed=3", "train.checkpoint_every=2"])
    out = tmp_path / "run"
    # the run is interrupted while its second battle starts: the first battle's checkpoint survives
    real, calls = paper_engine.run_bridged_battle, []

    def interrupted(*args: object, **kwargs: object) -> object:
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(paper_engine, "run_bridged_battle", interrupted)
    with pytest.raises(KeyboardInterrupt):
        train_run(cfg, out, progress=False, engine="robocode")
    monkeypatch.setattr(paper_engine, "run_bridged_battle", real)
    with open(out / "metrics" / "rounds.csv") as f:
        first = list(csv.DictReader(f))
    assert [int(r["round"]) for r in first] == [1, 2] and not (out / "summary.json").exists()
    _, meta = ck.load(ck.latest(out / "checkpoints"))
    assert meta["rounds_done"] == 2 and meta["battles"] == 1 and meta["updates"] > 0

    summary = train_run(None, out, progress=False, resume=True, engine="robocode")
    with open(out / "metrics" / "rounds.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == rounds and [int(r["round"]) for r in rows] == [1, 2, 3]
    assert rows[:2] == first and [int(r["battle"]) for r in rows] == [0, 0, 1]
    assert summary["battles"] == 2 and summary["updates"] > meta["updates"]
    # per-round score parts add up to the engine's own totals of each battle (its results file rounds half up)
    for battle, mine in ((0, rows[:2]), (1, rows[2:])):
        res = parse_results_text((out / "engine" / f"battle-{battle:03d}" / "results.txt").read_text())
        ours = next(c for c in res.contestants if c.name.startswith("confront.BridgeBot"))
        duck = next(c for c in res.contestants if c.name == "sample.SittingDuck")
        for side, row in (("ours", ours), ("theirs", duck)):
            for part, key in ENGINE_PARTS.items():
                assert sum(float(r[f"{part}_{side}"]) for r in mine) == pytest.approx(getattr(row, key), abs=0.5)
            assert sum(float(r[f"score_{side}"]) for r in mine) == pytest.approx(row.total, abs=0.5)
        assert ours.total > 0  # it hit the duck
    assert summary["rounds"] == rounds and summary["sessions"] == rounds
    sim_keys = {"name", "run", "scenario", "rounds", "sessions", "decisions", "final_score_ratio",
                "final_window_rounds", "win_rate_last", "score_ours", "score_theirs", "learner", "wall_time_s",
                "figures", "replay", "n_actions", "n_features"}  # train_run's summary (simulator)
    assert sim_keys <= summary.keys() and {"skipped_turns", "bridge_failures"} <= summary.keys()
    assert summary["score_ours"] == pytest.approx(sum(float(r["score_ours"]) for r in rows))
    # a robot whose Python answer is late on a loaded machine falls back for the rest of its round: reported,
    # not fatal, so only protocol errors are ruled out here
    assert summary["bridge_errors"] == [] and all("bridge-failed" in f for f in summary["bridge_failures"])
    assert summary["updates"] > 20 and summary["learner"]["updates"] == summary["updates"]
    # one round trip per decision: every T = 4 turns (turns 1, 5, 9, ... of each round), not every turn
    turns = sum(int(r["turns"]) for r in rows)
    assert summary["decisions"] <= turns / 4 + rounds and summary["updates"] >= summary["decisions"] - rounds
    assert json.loads((out / "summary.json").read_text())["updates"] == summary["updates"]
    learner, info = load_model(out)
    assert info["engine"] == "robocode" and learner.step == summary["updates"]
    assert np.ptp(learner.state_dict()["q"]) > 0  # the saved Q table moved away from its constant start
    assert (out / "config.toml").exists() and (out / "metrics" / "sessions.csv").exists()


def test_engine_resume_refuses_a_simulator_checkpoint(tmp_path: Path) -> None:
    cfg = load_experiment("demo", ["arena.scenario=1v1", "opponent.kind=SittingDuck", "learner.kind=ssaq",
                                   "train.rounds=4", "train.session_rounds=1", "train.checkpoint_every=2",
                                   "train.replay=false", "arena.battles=1"])
    train_run(cfg, tmp_path / "run", progress=False)
    (tmp_path / "run" / "summary.json").unlink()  # as a run killed after its last checkpoint
    with pytest.raises(CheckpointError, match="--engine sim"):
        train_run(None, tmp_path / "run", progress=False, resume=True, engine="robocode")


@pytest.mark.engine
def test_team_trains_against_exported_td_team_with_transfer(install, tmp_path: Path) -> None:
    base = load_experiment("demo", ["arena.scenario=4v4", "learner.kind=ssaq", "train.rounds=1",
                                    "train.session_rounds=1", "arena.decision_turns=10"])
    td = td_learner(base, 4)
    td.q[:] = np.random.default_rng(5).normal(size=td.q.shape)
    save_model(tmp_path / "td", td, {})
    src = TabularQ(TabularParams(n_states=320, n_actions=4))
    src.q[:] = 0.0
    src.q[:, 2] = 1.0  # the source always turns right while moving
    save_model(tmp_path / "src" / "model", src, {})
    cfg = load_experiment("demo", ["arena.scenario=4v4", "learner.kind=ssaq", "train.rounds=1",
                                   "train.session_rounds=1", "arena.decision_turns=10", "opponent.kind=td",
                                   f"opponent.model={tmp_path / 'td'}", f"transfer.source={tmp_path / 'src'}",
                                   "transfer.epsilon0=1.0", "transfer.floor=1.0", "transfer.init_from_source=false"])
    summary = train_run(cfg, tmp_path / "run", progress=False, engine="robocode")
    with open(tmp_path / "run" / "metrics" / "rounds.csv") as f:
        (row,) = list(csv.DictReader(f))
    assert int(row["alive_ours"]) <= 4 and int(row["alive_theirs"]) <= 4
    assert int(row["alive_ours"]) + int(row["alive_theirs"]) >= 1
    res = parse_results_text((tmp_path / "run" / "engine" / "battle-000" / "results.txt").read_text())
    for side, name in (("ours", "Ours"), ("theirs", "Them")):
        team = next(c for c in res.contestants if name in c.name)
        assert float(row[f"score_{side}"]) == pytest.approx(team.total, abs=0.5)
    assert summary["td_model"] == str(tmp_path / "td") and summary["transfer_source"] == str(tmp_path / "src")
    assert summary["decisions"] > 4 * 10 and summary["updates"] >= summary["decisions"] - 4
    assert summary["bridge_errors"] == []
    # eps = 1: the four tanks only ever took the source's move 2, so only that column of the saved table learned
    learner, _ = load_model(tmp_path / "run")
    q0 = TabularQ(TabularParams(n_states=320, n_actions=4)).q
    changed = (learner.q != q0).any(axis=0)
    assert changed.tolist() == [False, False, True, False]
