"""Baselines: the SB3 VecEnv adapter against TeamBattleEnv, the ranking table, a tiny end-to-end run."""

from __future__ import annotations

import csv
import tempfile
from pathlib import Path

import numpy as np
import pytest

from confront.arena.scenarios import get_scenario
from confront.arena.smdp import TeamBattleEnv
from confront.experiments.baselines import HAVE_SB3, BaselinesConfig, baselines_outcome, rank_table
from confront.learning.tabular import TabularParams, TabularQ

B = 2  # battles
SHORT = get_scenario("4v4").replace(max_turns=50)  # rounds stop after 50 turns = 5 SMDP steps of 10 turns


def _actions(step: int, n: int) -> np.ndarray:
    """A fixed action sequence: (n,) ints in 0..3."""
    return (np.arange(n) + step) % 4


def _td(n_states: int = 320) -> TabularQ:
    """A TD learner whose greedy action is state % 4 (no ties)."""
    q = TabularQ(TabularParams(n_states=n_states, n_actions=4, exploration="egreedy"), kind="td")
    table = np.zeros((n_states, 4))
    table[np.arange(n_states), np.arange(n_states) % 4] = 1.0
    q.load_state_dict({**q.state_dict(), "q": table})
    return q


def test_config_rejects_bad_values() -> None:
    with pytest.raises(ValueError, match="eval_rounds"):
        BaselinesConfig(eval_rounds=0)
    with pytest.raises(ValueError, match="A2C"):
        BaselinesConfig(sb3=("A2C",))
    with pytest.raises(ValueError, match="opponents"):
        BaselinesConfig(opponents=())
    with pytest.raises(ValueError, match="'Nobody'"):
        BaselinesConfig(opponents=("td", "Nobody"))
    with pytest.raises(ValueError, match="'Oracle'"):
        BaselinesConfig(references=("Oracle",))
    with pytest.raises(ValueError, match="'Sitter'"):
        BaselinesConfig(scripted=("Sitter",))


def test_rank_table_orders_by_first_opponent_and_lists_skipped() -> None:
    rows = [{"method": m, "seed": s, "opponent": o, "score_ratio": v}
            for m, vals in {"A": (0.2, 0.4), "B": (0.6, 0.8)}.items()
            for s, v in enumerate(vals) for o in ("td", "SpinBot")]
    table, stats = rank_table(rows, ("td", "SpinBot"), np.random.default_rng(0), {"DQN (SB3)": "not installed"})
    lines = table.splitlines()
    assert lines[2].startswith("| 1 | B | 0.700 [0.600, 0.800]")  # mean of 0.6, 0.8; bootstrap bounds = the values
    assert lines[3].startswith("| 2 | A | 0.300 [0.200, 0.400]")
    assert lines[4].startswith("| - | DQN (SB3) | skipped: not installed")
    assert stats["A"]["SpinBot"].mean == pytest.approx(0.3)


sb3_only = pytest.mark.skipif(not HAVE_SB3, reason="stable_baselines3 not installed")


@sb3_only
def test_vec_env_matches_team_battle_env_on_fixed_actions() -> None:
    pytest.importorskip("stable_baselines3")
    from confront.experiments.baselines import SharedTeamVecEnv

    td = _td()
    vec = SharedTeamVecEnv(SHORT, B, seed=3, opponents="td", td=td)
    raw = TeamBattleEnv(SHORT, n_battles=B, seed=3, opponents="td")
    team = raw.team_ids()
    ours, theirs = np.flatnonzero(team == 0), np.flatnonzero(team != 0)
    assert vec.num_envs == B * 4 and vec.action_space.n == 4
    obs = vec.reset()
    disc, feats = raw.reset()
    assert obs.shape == (8, raw.n_features) and obs.dtype == np.float32
    np.testing.assert_array_equal(obs, feats[:, ours].reshape(8, -1))
    saw_round_end = False
    for step in range(12):
        a = _actions(step, 8)
        full = np.zeros((B, 8), dtype=np.int64)
        full[:, ours] = a.reshape(B, 4)
        full[:, theirs] = (disc[:, theirs] % 4)  # the TD table's greedy action
        res = raw.step(full)
        obs, rewards, dones, infos = vec.step(a)
        expect_r = res.rewards[:, ours].sum(axis=2).reshape(-1)
        np.testing.assert_allclose(rewards, expect_r, rtol=1e-6, atol=1e-4)
        expect_done = (res.terminated[:, ours] | ~res.active[:, ours]).reshape(-1)
        np.testing.assert_array_equal(dones, expect_done)
        np.testing.assert_array_equal(obs, res.features[:, ours].reshape(8, -1))
        assert all(vec.observation_space.contains(o) or not d for o, d in zip(obs, dones, strict=True))
        for k in np.flatnonzero(dones):
            assert "terminal_observation" in infos[k]
        if res.round_end is not None:
            saw_round_end = True
            final = res.final_features[:, ours].reshape(8, -1)
            for k in range(8):
                assert dones[k]
                if not infos[k]["padding"]:
                    np.testing.assert_array_equal(infos[k]["terminal_observation"], final[k])
                # a living tank whose round hit the 50-turn cap is truncated, not terminated
                alive = bool(res.round_end.alive[k // 4, ours[k % 4]])
                assert infos[k]["TimeLimit.truncated"] == (alive and bool(res.truncated[k // 4]) and
                                                           not infos[k]["padding"])
        disc = res.discrete
    assert saw_round_end
    assert vec.rounds_done == 2 * B  # 12 steps of 10 turns: two 50-turn rounds per battle (or earlier ends)


@sb3_only
def test_vec_env_takes_the_tank_view_and_head_actions() -> None:
    from confront.arena.gym_env import make_config
    from confront.experiments.baselines import SharedTeamVecEnv

    cfg = make_config(view="tank")
    vec = SharedTeamVecEnv(SHORT, B, seed=5, opponents="SpinBot", config=cfg)
    raw = TeamBattleEnv(SHORT, n_battles=B, seed=5, opponents="SpinBot", config=cfg)
    ours = np.flatnonzero(raw.team_ids() == 0)
    assert vec.observation_space.shape == (62,) and list(vec.action_space.nvec) == [5, 5, 4, 4, 2]
    _, feats = raw.reset()
    np.testing.assert_array_equal(vec.reset(), feats[:, ours].reshape(8, -1))
    rng = np.random.default_rng(0)
    for _ in range(8):
        heads = np.stack([rng.integers(0, d, 8) for d in (5, 5, 4, 4, 2)], axis=1)
        full = np.zeros((B, 8), dtype=np.int64)
        full[:, ours] = np.ravel_multi_index(tuple(heads.T), (5, 5, 4, 4, 2)).reshape(B, 4)
        res = raw.step(full)
        obs, rewards, _, _ = vec.step(heads)
        np.testing.assert_array_equal(obs, res.features[:, ours].reshape(8, -1))
        np.testing.assert_allclose(rewards, res.rewards[:, ours].sum(axis=2).reshape(-1), rtol=1e-6)
    with pytest.raises(ValueError, match="head indices"):
        vec.step(np.zeros(8, dtype=np.int64))


@sb3_only
def test_vec_env_needs_the_td_learner() -> None:
    from confront.experiments.baselines import SharedTeamVecEnv

    with pytest.raises(ValueError, match="td="):
        SharedTeamVecEnv(SHORT, 1, seed=0, opponents="td")


@sb3_only
def test_sb3_policy_state_round_trip() -> None:
    from stable_baselines3 import PPO

    from confront.experiments.baselines import SB3Policy, SharedTeamVecEnv

    env = SharedTeamVecEnv(SHORT, 1, seed=0, opponents="SpinBot")
    a = SB3Policy(PPO("MlpPolicy", env, n_steps=8, batch_size=8, seed=1, device="cpu"), 4)
    b = SB3Policy(PPO("MlpPolicy", env, n_steps=8, batch_size=8, seed=2, device="cpu"), 4)
    obs = np.random.default_rng(0).uniform(0, 1, (64, env.env.n_features)).astype(np.float32)
    rng = np.random.default_rng(0)
    assert not np.array_equal(a.state_dict()["action_net.weight"], b.state_dict()["action_net.weight"])
    b.load_state_dict(a.state_dict())
    np.testing.assert_array_equal(a.act(obs, rng, explore=False), b.act(obs, rng, explore=False))
    with pytest.raises(ValueError, match="misses key"):
        b.load_state_dict({})


@sb3_only
def test_sb3_export_decides_as_sb3s_deterministic_predict() -> None:
    """The exported MLP (the actor's layers with their tanh, then the action net) takes SB3's deterministic
    action on observations of real battles."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import Logger

    from confront.arena.observe import ObservationConfig
    from confront.experiments.baselines import SB3Policy, SharedTeamVecEnv, sb3_activation, sb3_exported_policy

    env = SharedTeamVecEnv(SHORT, B, seed=4, opponents="SpinBot")
    model = PPO("MlpPolicy", env, n_steps=16, batch_size=32, n_epochs=2, seed=3, device="cpu")
    model.set_logger(Logger(folder=None, output_formats=[]))
    model.learn(total_timesteps=16 * env.num_envs)  # one update: the weights leave their initialisation
    policy = SB3Policy(model, 4)
    exported = sb3_exported_policy(policy.state_dict(), sb3_activation(model), ObservationConfig(), 10)
    assert exported.kind == "mlp" and exported.hidden_activation == "tanh" and len(exported.weights) == 3
    rng = np.random.default_rng(0)
    obs = [env.reset()]
    for _ in range(40):
        obs.append(env.step(policy.act(obs[-1], rng))[0])
    batch = np.concatenate(obs)
    want = policy.act(batch, rng, explore=False)
    np.testing.assert_array_equal([int(np.argmax(exported.values_of(0, f))) for f in batch], want)
    assert len(set(want.tolist())) > 1  # more than one action decided
    with pytest.raises(ValueError, match="action_net.weight"):
        sb3_exported_policy({}, "tanh", ObservationConfig(), 10)


def test_tiny_end_to_end(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CONFRONT_CACHE", str(tmp_path / "cache"))
    cfg = BaselinesConfig(overrides=("opponent.pretrain_rounds=4", "train.replay=false", "arena.battles=2"),
                          eval_rounds=2, scripted=("SpinBot", "Walls"))
    sb3_dirs = set(Path(tempfile.gettempdir()).glob("SB3-*"))
    outcome = baselines_outcome(1, tmp_path / "out", 4, 1, cfg)
    assert set(Path(tempfile.gettempdir()).glob("SB3-*")) == sb3_dirs  # SB3 leaves no log folders behind
    root = tmp_path / "out" / "baselines"
    with (root / "results.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    methods = {r["method"] for r in rows}
    expected = ({"DMNN (FLM)", "Random moves", "DMNN (untrained)", "SpinBot", "Walls"}
                | ({"DQN (SB3)", "PPO (SB3)"} if HAVE_SB3 else set()))
    assert methods == expected
    assert len(rows) == 2 * len(expected)  # every method against the TD team and SpinBot
    for r in rows:
        assert 0.0 <= float(r["score_ratio"]) <= 1.0
        total = float(r["score_ours"]) + float(r["score_theirs"])
        assert float(r["score_ratio"]) == pytest.approx(float(r["score_ours"]) / total)
        if r["method"] in ("SpinBot", "Walls", "Random moves", "DMNN (untrained)"):
            assert int(r["train_rounds"]) == 0
        else:  # the budget; SB3 may overshoot by rounds that end in the same step (at most battles - 1)
            assert 4 <= int(r["train_rounds"]) <= 5
    table = "\n".join(outcome.tables)
    for m in expected:
        assert f"| {m} |" in table
    if not HAVE_SB3:
        assert "skipped: stable_baselines3/torch not installed" in table
    assert outcome.figures and outcome.figures[0].exists()
    assert len(outcome.claims) == 1 and outcome.claims[0].holds is None
    assert outcome.claims[0].ours.startswith("1. ")
    # a second call reuses every cached result (same numbers)
    again = baselines_outcome(1, tmp_path / "out", 4, 1, cfg)
    assert again.tables == outcome.tables


def test_without_sb3_the_table_says_skipped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from confront.experiments import baselines

    monkeypatch.setenv("CONFRONT_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(baselines, "HAVE_SB3", False)  # what a core install (no torch) sees
    cfg = BaselinesConfig(overrides=("opponent.pretrain_rounds=2", "train.replay=false", "arena.battles=2"),
                          eval_rounds=2, scripted=("Walls",), opponents=("SpinBot",))
    outcome = baselines.baselines_outcome(1, tmp_path / "out", 2, 1, cfg)
    table = "\n".join(outcome.tables)
    assert "| DQN (SB3) | skipped: stable_baselines3/torch not installed" in table
    assert "| PPO (SB3) | skipped:" in table
    assert "| DMNN (FLM) |" in table and "| Walls |" in table


@sb3_only
def test_dead_tanks_pad_until_their_round_ends() -> None:
    from confront.experiments.baselines import SharedTeamVecEnv

    vec = SharedTeamVecEnv("4v4", 1, seed=5, opponents="td", td=_td())
    vec.reset()
    padded = 0
    for step in range(400):
        obs, rewards, dones, infos = vec.step(_actions(step, 4))
        for k in range(4):
            if dones[k] and infos[k]["padding"]:
                padded += 1
                assert rewards[k] == 0.0  # a dead tank earns nothing
                assert not infos[k]["TimeLimit.truncated"]
        if vec.rounds_done:
            break
    assert vec.rounds_done == 1
    assert padded > 0 and vec.padding_steps == padded
    assert vec.live_steps + vec.padding_steps == 4 * (step + 1)
