"""PPO tanks trained in the real engine: rewards from the runner's score log and episode packing by hand, the
logged decisions against the Python twin, unsupported league entries, and a short resumed training run."""

from __future__ import annotations

import csv
import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from confront import checkpoint as ck
from confront.arena.control import ControlConfig
from confront.arena.tank import TankSpace
from confront.config import ConfigError
from confront.engine.battle import scenario_battle
from confront.engine.runner import EngineOptions, run_battle
from confront.engine.tank_export import TANK_ROBOT, TankPolicy, export_tank_robot, robot_view
from confront.learning.ppo import PPO
from confront.train import ppo_engine
from confront.train.engine_logs import ScoreLog, read_decisions, read_scores
from confront.train.factory import train_run
from confront.train.ppo_engine import episode_rewards, pack_episodes
from confront.train.ppo_model import load_tank_model, tank_space
from confront.train.spec import load_experiment


def test_rewards_from_the_score_log_by_hand(tmp_path: Path) -> None:
    # robots: ours 0 and 1 (contestant 0), theirs 2 (contestant 1); lines only where something changed
    (tmp_path / "scores.txt").write_text(
        "0 1 111 0.0 0.0 0.0\n"
        "0 7 111 4.0 0.0 0.0\n"       # robot 0 hits: +4
        "0 9 011 4.0 0.0 16.0\n"      # robot 0 dies, theirs gets 16 (bullet) ...
        "0 12 011 4.0 0.0 66.0\n"     # ... and 50 more at 12 (turns between lines: the line before)
        "0 14 010 4.0 90.0 66.0\n"    # theirs dies: robot 1 gets 50 survival + 10 bonus + 30 (bullet, kill bonus)
        "1 1 111 0.0 0.0 0.0\n")
    logs = read_scores(tmp_path / "scores.txt", 3)
    log = logs[0]
    ours = np.array([True, True, False])
    contestant = np.array([0, 0, 1])
    assert log.decided(contestant) == 14 and logs[1].decided(contestant) is None
    assert [log.margin(t, ours) for t in (0, 1, 6, 7, 8, 9, 11, 12, 13, 14, 200)] == \
        [0.0, 0.0, 0.0, 4.0, 4.0, -12.0, -12.0, -62.0, -62.0, 28.0, 28.0]
    m = lambda t: log.margin(t, ours)  # noqa: E731
    # robot 1 alive at the end: decisions 0, 5, 10 (and 15, after the deciding turn 14: dropped)
    np.testing.assert_array_equal(episode_rewards([0, 5, 10, 15], m, 14, True, 5),
                                  [m(5) - m(0), m(10) - m(5), m(14) - m(10)])
    assert list(episode_rewards([0, 5, 10, 15], m, 14, True, 5)) == [0.0, -12.0, 40.0]
    # robot 0 died at turn 9: its last step (from 5) runs T = 5 turns, to 10
    assert list(episode_rewards([0, 5], m, 14, False, 5)) == [0.0, -12.0]
    # decision turns delayed (8 instead of 5): the windows follow the turns the robot decided in
    assert list(episode_rewards([0, 8, 10], m, 14, True, 5)) == [4.0, -16.0, 40.0]
    # the last window ends at the deciding turn even when the step would be longer
    assert list(episode_rewards([0, 10], m, 12, False, 5)) == [-12.0, -50.0]
    assert len(episode_rewards([14, 19], m, 14, True, 5)) == 0
    # a round's rewards add up to its margin at the deciding turn (robot 1, alive at the end)
    assert episode_rewards([0, 5, 10], m, 14, True, 5).sum() == m(14)
    with pytest.raises(ValueError, match="3 robots"):
        (tmp_path / "bad.txt").write_text("0 1 11 0.0 0.0\n")
        read_scores(tmp_path / "bad.txt", 3)


def test_pack_episodes_by_hand() -> None:
    index, active, done = pack_episodes([3, 1, 0, 2])
    assert index.tolist() == [[0, 3, -1, 4], [1, -1, -1, 5], [2, -1, -1, -1]]
    assert active.tolist() == [[True, True, False, True], [True, False, False, True], [True, False, False, False]]
    assert done.tolist() == [[False, True, False, False], [False, False, False, True], [True, False, False, False]]
    index, active, done = pack_episodes([])
    assert index.shape == active.shape == done.shape == (0, 0)


def test_score_log_before_its_first_line() -> None:
    log = ScoreLog(np.array([3]), np.array([[True, False]]), np.array([[5.0, 0.0]]))
    ours = np.array([True, False])
    assert log.at(2) == -1 and log.margin(2, ours) == 0.0 and log.margin(3, ours) == 5.0
    assert log.decided(np.array([0, 1])) == 3


@pytest.mark.parametrize("entry", ["1v1:self", "4v4:strafe"])
def test_league_entries_the_engine_cannot_play_are_refused(tmp_path: Path, entry: str) -> None:
    cfg = load_experiment("tanks-engine", [f"league.opponents=['1v1:SpinBot', '{entry}']", "train.rounds=2",
                                           "train.session_rounds=1"])
    with pytest.raises(ConfigError, match=re.escape(repr(entry))):
        train_run(cfg, tmp_path / "run", progress=False, engine="robocode")
    assert not (tmp_path / "run").exists()


def test_init_is_refused_where_it_is_not_used(tmp_path: Path) -> None:
    cfg = load_experiment("tanks-engine", ["train.rounds=2", "train.session_rounds=1", "train.init=somewhere"])
    with pytest.raises(ConfigError, match="engine only"):
        train_run(cfg, tmp_path / "run", progress=False, engine="sim")
    cfg = load_experiment("demo", ["train.rounds=2", "train.session_rounds=1", "train.init=somewhere"])
    with pytest.raises(ConfigError, match="transfer.source"):
        train_run(cfg, tmp_path / "run2", progress=False, engine="sim")


def _policy(seed: int, space: TankSpace, hidden: int = 24) -> TankPolicy:
    rng = np.random.default_rng(seed)
    sizes = [space.n_features, hidden, hidden, sum(space.dims)]
    return TankPolicy(tuple(rng.normal(0, 1.0, size=(o, i)) for i, o in zip(sizes, sizes[1:], strict=False)),
                      tuple(rng.normal(0, 0.5, size=o) for o in sizes[1:]), space, ControlConfig(), 5,
                      play="sampled")


@pytest.mark.engine
def test_logged_decisions_equal_the_python_twin(install, tmp_path: Path) -> None:
    """A 4v4 battle of sampling TankBots (a random actor, read from confront.tank.model) against SpinBots: each
    logged view equals robot_view of what the robot logged it knew, and each action the twin's draw."""
    space = TankSpace()
    policy = _policy(5, space)
    (tmp_path / "policy.txt").write_text(policy.to_text())
    (tmp_path / "log").mkdir()
    # the jar holds another policy (greedy): the property's file must win
    jar = export_tank_robot(replace(_policy(6, space), play="greedy"), tmp_path / "tankbot.jar", install)
    props = (f"-Dconfront.tank.model={tmp_path / 'policy.txt'}", f"-Dconfront.tank.log={tmp_path / 'log'}",
             "-Dconfront.tank.log.detail=true", f"-Dconfront.scores={tmp_path / 'scores.txt'}")
    run = run_battle(scenario_battle("4v4", TANK_ROBOT, "SpinBot", rounds=1),
                     EngineOptions(seed=3, nosecurity=True, extra_jvm_args=props, cpu_constant_ms=100.0),
                     extra_robots=[jar],
                     install=install)
    decisions = read_decisions(tmp_path / "log")
    names = {r["name"] for r in run.summary["robots"] if r["contestant"] == 0}
    assert {d.robot for d in decisions} == names and len(names) == 4
    # one line per decision: a robot's decisions in a round are at turns 0, T, 2T, ... (no turn skipped)
    episodes: dict[tuple[str, int], list[int]] = {}
    for d in decisions:
        episodes.setdefault((d.robot, d.round), []).append(d.turn)
    assert not sum(run.skipped_turns.values())
    assert all(turns == list(range(0, 5 * len(turns), 5)) for turns in episodes.values()) and len(decisions) > 100
    worst, mates, drawn = 0.0, 0, set()
    for d in decisions:
        own, enemies, mate_rows = d.detail
        v, _ = robot_view(own[:6], [int(x) for x in own[6:10]], enemies, mate_rows, own[10], own[11], own[12], space)
        worst = max(worst, float(np.abs(v - d.view).max()))
        assert policy.act(d.view, d.draws) == d.action
        mates += len(mate_rows) > 0
        drawn.add(d.action)
    assert worst <= 1e-15, worst
    assert mates > 0 and len(drawn) > 20  # the mates are seen; the draws spread over the actions
    scores = read_scores(tmp_path / "scores.txt", 8)
    assert set(scores) == {0} and scores[0].turns[0] == 1


def _read_rows(path: Path) -> list[dict[str, str]]:
    with open(path) as f:
        return list(csv.DictReader(f))


SLACK_MS = 1000.0  # the engine's time per turn here: no turn of the bridged tank skipped on a loaded machine (the
# decision count below holds without skips; the default constant skipped one at load 6)


@pytest.mark.engine
def test_ppo_trains_in_the_engine_and_resumes(install, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    cfg = load_experiment("tanks-engine", ["league.opponents=['1v1:SittingDuck']", "train.rounds=4",
                                           "train.session_rounds=2", "train.checkpoint_every=2", "train.seed=2",
                                           "ppo.hidden=32", "ppo.lr=0.003"])
    out = tmp_path / "run"
    real, battles = ppo_engine.run_battle, []

    def interrupted(*args: object, **kwargs: object) -> object:  # the run is killed while its 2nd battle starts
        if len(battles) == 1:
            raise KeyboardInterrupt
        battles.append(real(*args, **kwargs))
        return battles[-1]

    monkeypatch.setattr(ppo_engine, "run_battle", interrupted)
    with pytest.raises(KeyboardInterrupt):
        train_run(cfg, out, progress=False, engine="robocode", cpu_constant_ms=SLACK_MS)
    first = _read_rows(out / "metrics" / "rounds.csv")
    assert [int(r["round"]) for r in first] == [1, 2] and not (out / "summary.json").exists()
    arrays, meta = ck.load(ck.latest(out / "checkpoints"))
    assert meta["rounds_done"] == 2 and meta["battles"] == 1 and int(arrays["ppo.updates"]) == 1
    (up,) = meta["updates"]
    # the decisions kept are those before each round's deciding turn (the round's turns less the engine's 150
    # after it; our tank survives the duck): turns 0, T, 2T, ... < D, so ceil(D / T) per round
    assert not sum(battles[0].skipped_turns.values())
    assert up["decisions"] == up["battle_decisions"] == sum(-(-(int(r["turns"]) - 150) // 5) for r in first)
    assert up["battle_decisions"] < up["decisions_logged"]  # the robots decide on after the deciding turn
    # 1v1: the rewards of a round add up to its score margin (the runner's round-end totals)
    assert up["reward_points"] == pytest.approx(sum(float(r["score_ours"]) - float(r["score_theirs"])
                                                    for r in first), abs=1e-9)
    assert np.isfinite(up["policy_loss"]) and up["approx_kl"] > 0  # the update moved the policy

    monkeypatch.setattr(ppo_engine, "run_battle", real)
    summary = train_run(None, out, progress=False, resume=True, engine="robocode", cpu_constant_ms=SLACK_MS)
    rows = _read_rows(out / "metrics" / "rounds.csv")
    assert [int(r["round"]) for r in rows] == [1, 2, 3, 4] and rows[:2] == first
    assert [int(r["battle"]) for r in rows] == [0, 0, 1, 1] and {r["opponent"] for r in rows} == {"1v1:SittingDuck"}
    assert summary["rounds"] == 4 and summary["battles"] == 2 and summary["updates"] == 2
    assert summary["engine"] == "robocode" and summary["learner"] == "ppo"
    assert summary["engine_s"] > summary["update_s"] > 0
    updates = _read_rows(out / "metrics" / "updates.csv")
    assert [int(u["update"]) for u in updates] == [1, 2]
    assert int(updates[1]["decisions"]) == summary["decisions"] > int(updates[0]["decisions"])
    for b in (0, 1):
        assert (out / "engine" / f"battle-{b:03d}" / "results.txt").read_text().startswith("Results for 2 rounds")
    # the saved model is the trained one (not the initial weights), in the form evaluate / export read
    trained = load_tank_model(out, cfg)
    fresh = PPO(tank_space(cfg).n_features, tank_space(cfg).dims, cfg.ppo, seed=cfg.train.seed)
    assert any(not np.array_equal(a, fresh.actor_arrays()[k]) for k, a in trained.actor_arrays().items())
    assert json.loads((out / "model" / "model.json").read_text())["kind"] == "ppo"

    # train.init: a new run starts from this one's model
    cfg2 = load_experiment("tanks-engine", ["league.opponents=['1v1:SittingDuck']", "train.rounds=1",
                                            "train.session_rounds=1", "train.checkpoint_every=1", "ppo.hidden=32",
                                            f"train.init={json.dumps(str(out))}"])
    trainer = ppo_engine.EngineTankTrainer(cfg2, None)  # type: ignore[arg-type]  # no battle: no run folder
    try:
        for k, a in trained.state_dict().items():
            if k.startswith("net."):
                np.testing.assert_array_equal(trainer.ppo.state_dict()[k], a)
    finally:
        trainer.close()


@pytest.mark.engine
def test_robot_without_embedded_policy_reads_its_policy_file(install, tmp_path: Path) -> None:
    """``export_tank_robot(embed=False)`` (what engine training plays): no TankData, no property: the jar's own
    tank_policy.txt (readable without the sandbox only, as training runs it)."""
    policy = replace(_policy(7, TankSpace()), play="greedy")
    jar = export_tank_robot(policy, tmp_path / "tankbot.jar", install, embed=False)
    run = run_battle(scenario_battle("1v1", TANK_ROBOT, "SittingDuck", rounds=1),
                     EngineOptions(seed=1, nosecurity=True), extra_robots=[jar], install=install)
    assert not any("tank-load-failed" in r for r in run.summary["robot_reports"])
    ours = next(c for c in run.results.contestants if c.name.startswith("confront.TankBot"))
    assert ours.total > 0
