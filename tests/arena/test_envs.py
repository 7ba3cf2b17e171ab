"""Gymnasium env, vector env and PettingZoo env: official checkers plus value checks."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test, parallel_seed_test

from confront.arena import gym_env  # noqa: F401 - registers confront/Battle-v0
from confront.arena.pz_env import parallel_env
from confront.arena.vector_env import BattleVectorEnv


def test_gym_check_env_and_registration() -> None:
    env = gym.make("confront/Battle-v0", scenario="1v1", opponents="SpinBot")
    check_env(env.unwrapped, skip_render_check=True)
    env12 = gym.make("confront/Battle-v0", scenario="4v4", opponents="Walls", fire_power_actions=True)
    check_env(env12.unwrapped, skip_render_check=True)
    assert env12.action_space.n == 12


def test_gym_episode_reward_is_sum_of_turn_rewards_and_ends_with_scores() -> None:
    env = gym.make("confront/Battle-v0", scenario="1v1", opponents="SpinBot", turns_per_step=7)
    obs, _ = env.reset(seed=4)
    assert 0 <= obs["state"] < 320 and obs["features"].shape == (7,)
    for _ in range(2000):
        obs, r, term, trunc, info = env.step(0)
        assert info["rewards"].shape == (7,)
        assert r == pytest.approx(float(info["rewards"].sum()))
        if term or trunc:
            break
    assert term or trunc
    ts = info["team_score"]
    assert ts.shape == (2, 6)
    # one tank died: the survivor's team got 50 survival and 10 last-survivor bonus (1 enemy)
    assert sorted(ts[:, 0].tolist()) == [0.0, 50.0]
    assert sorted(ts[:, 1].tolist()) == [0.0, 10.0]


def test_gym_reset_seed_repeats() -> None:
    env = gym.make("confront/Battle-v0", scenario="1v1", opponents="Crazy")
    o1, _ = env.reset(seed=11)
    r1 = [env.step(a)[1] for a in (0, 2, 1, 3, 0)]
    o2, _ = env.reset(seed=11)
    r2 = [env.step(a)[1] for a in (0, 2, 1, 3, 0)]
    assert o1["state"] == o2["state"] and r1 == r2


def test_gym_render_shows_tanks() -> None:
    env = gym.make("confront/Battle-v0", scenario="1v1", opponents="SittingDuck", render_mode="rgb_array")
    env.reset(seed=0)
    img = env.render()
    assert img.shape == (300, 400, 3) and img.dtype == np.uint8
    s = env.unwrapped.team_env.arena.state
    for r, colour in ((0, (66, 135, 245)), (1, (230, 70, 60))):
        # 8 px behind the centre along the body heading (= gun heading at the start): body colour
        h = s.heading[0, r]
        x, y = s.x[0, r] - 8 * np.sin(h), s.y[0, r] - 8 * np.cos(h)
        px = img[int((600 - y) * 0.5), int(x * 0.5)]
        assert tuple(px) == colour


def test_vector_env_batches_natively() -> None:
    v = BattleVectorEnv(6, "1v1", "SpinBot", turns_per_step=5, seed=3)
    assert v.unwrapped._driver.env.n_battles == 6
    obs, _ = v.reset(seed=3)
    assert obs["state"].shape == (6,) and obs["features"].shape == (6, 7)
    ended = 0
    for _ in range(600):
        obs, r, term, trunc, info = v.step(np.zeros(6, dtype=np.int64))
        assert r.shape == term.shape == trunc.shape == (6,)
        if "final_obs" in info:
            m = info["_final_obs"]
            ended += int(m.sum())
            assert all(info["final_obs"][i] is not None for i in np.flatnonzero(m))
            # the ended battles restarted this step: full energy in the new round's observation
            assert np.all(obs["features"][m, 5] == 1.0)
        if ended >= 2:
            break
    assert ended >= 2


def test_vector_env_matches_single_env() -> None:
    v = BattleVectorEnv(1, "1v1", "Walls", seed=9)
    e = gym.make("confront/Battle-v0", scenario="1v1", opponents="Walls")
    ov, _ = v.reset(seed=9)
    oe, _ = e.reset(seed=9)
    for a in (0, 1, 2, 3, 0, 0):
        ov, rv, *_ = v.step(np.array([a]))
        oe, re, *_ = e.step(a)
        assert int(ov["state"][0]) == oe["state"] and rv[0] == pytest.approx(re)


def test_pettingzoo_api_and_seed() -> None:
    parallel_api_test(parallel_env(scenario="4v4", opponents="SpinBot"), num_cycles=100)
    parallel_api_test(parallel_env(scenario="4v4"), num_cycles=60)  # td opponents acting at random
    parallel_seed_test(lambda: parallel_env(scenario="4v4", opponents="td"), num_cycles=60)


def test_pettingzoo_agents_and_bad_action() -> None:
    env = parallel_env(scenario="4v6", opponents="SittingDuck")
    obs, _ = env.reset(seed=1)
    assert env.agents == ["tank_0", "tank_1", "tank_2", "tank_3"] and set(obs) == set(env.agents)
    with pytest.raises(ValueError, match="tank_0"):
        env.step({"tank_0": 7})
    with pytest.raises(ValueError, match="unknown agent"):
        env.step({"tank_9": 0})


def test_other_policy_drives_td_opponents() -> None:
    calls = []

    def policy(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        calls.append((disc.shape, feats.shape))
        return np.full(disc.shape, 1)  # every other learning tank backs off

    v = BattleVectorEnv(3, "1v1", "td", other_policy=policy, seed=1, order="fixed")
    v.reset(seed=1)
    team = v._driver.env
    y0 = team.arena.state.distance_remaining.copy()
    v.step(np.zeros(3, dtype=np.int64))
    assert calls == [((3, 2), (3, 2, 7))]
    assert np.all(y0 == 0)
    # robot 0 was told "forward" (100 px), robot 1 "backward" (-100 px): the rest of each move remains
    rem = team.arena.state.distance_remaining
    assert np.all(rem[:, 0] > 0) and np.all(rem[:, 1] < 0)
    assert team.arena.order == "fixed"


# -- the tank view (view="tank"): what the recommended learner trains on, through the standard APIs ----------


def test_tank_view_gym_spaces_values_and_score_margin_reward() -> None:
    from confront.arena.tank import FEATURE_NAMES

    env = gym.make("confront/Battle-v0", scenario="1v1", opponents="SpinBot", view="tank")
    check_env(env.unwrapped, skip_render_check=True)
    assert env.observation_space.shape == (62,) and env.observation_space.dtype == np.float32
    assert list(env.action_space.nvec) == [5, 5, 4, 4, 2]
    lo, hi = env.observation_space.low, env.observation_space.high
    assert (lo[FEATURE_NAMES.index("velocity")], hi[FEATURE_NAMES.index("energy")]) == (-1.0, 10.0)
    assert (lo[FEATURE_NAMES.index("enemy0_lateral")], lo[FEATURE_NAMES.index("enemy0_distance")]) == (-1.0, 0.0)
    obs, _ = env.reset(seed=4)
    s = env.unwrapped.team_env.arena.state
    w, h = env.unwrapped.team_env.scenario.width, env.unwrapped.team_env.scenario.height
    assert obs[0] == pytest.approx(s.x[0, 0] / w) and obs[3] == pytest.approx((h - s.y[0, 0]) / h)
    assert obs[4] == pytest.approx(np.sin(s.heading[0, 0]), abs=1e-6) and obs[7] == pytest.approx(1.0)
    assert obs[9] == 1.0 and obs[11] == 0.0  # the enemy lives, but no scan yet in a round's first turn

    # a round's rewards add up to its score margin (ours minus theirs), also when the tank loses
    for opp, action in (("SittingDuck", [4, 2, 3, 0, 1]), ("Tracker", [2, 2, 0, 0, 0])):
        e = gym.make("confront/Battle-v0", scenario="1v1", opponents=opp, view="tank")
        e.reset(seed=1)
        total, done, info = 0.0, False, {}
        while not done:
            _, r, term, trunc, info = e.step(np.array(action))
            total += r
            done = term or trunc
        team = info["team_score"].sum(axis=1)
        assert total == pytest.approx(team[0] - team[1], abs=1e-9)
        assert (total > 100) if opp == "SittingDuck" else (total < 0)  # holding fire against Tracker loses


def test_tank_actions_decode_to_the_action_table_and_bad_ones_fail() -> None:
    from confront.arena.gym_env import action_indices, make_config
    from confront.arena.tank import LEADS, TankSpace, action_table

    space = TankSpace()
    cfg = make_config(view="tank")
    assert cfg.turns_per_step == 5 and cfg.reward == "score" and cfg.observation.sensing == "scanned"
    heads = np.array([[4, 0, 2, 3, 1], [0, 4, 0, 0, 0], [2, 2, 3, 1, 1]])
    table = action_table(space)[action_indices(cfg, heads, 3)]
    for (d, t, f, k, lead), row in zip(heads, table, strict=True):
        power = space.fire_powers[f]
        assert tuple(row) == (space.distances[d], np.radians(space.turns_deg[t]), power if power > 0 else -1.0,
                              k, 1.0, LEADS[space.leads[lead]], 0.0)
    for bad in ([1, 2, 3], [5, 0, 0, 0, 0], [0, 0, 0, 0, -1], [0.5, 0, 0, 0, 0], 3, "a"):
        with pytest.raises(ValueError, match="head indices"):
            action_indices(cfg, bad, 1)
    with pytest.raises(ValueError, match="view must be"):
        make_config(view="scanned")
    with pytest.raises(ValueError, match="view='tank'"):
        make_config(tank=space)
    with pytest.raises(ValueError, match="fire-power head"):
        make_config(view="tank", fire_power_actions=True)


def test_tank_view_vector_env_matches_single_env_and_restarts() -> None:
    v = BattleVectorEnv(1, "1v1", "Walls", seed=9, view="tank")
    e = gym.make("confront/Battle-v0", scenario="1v1", opponents="Walls", view="tank")
    ov, _ = v.reset(seed=9)
    oe, _ = e.reset(seed=9)
    rng = np.random.default_rng(0)
    for _ in range(12):
        a = np.array([rng.integers(0, d) for d in (5, 5, 4, 4, 2)])
        ov, rv, *_ = v.step(a[None])
        oe, re, *_ = e.step(a)
        assert np.array_equal(ov[0], oe) and rv[0] == re
    v4 = BattleVectorEnv(4, "1v1", "SittingDuck", seed=2, view="tank")
    obs, _ = v4.reset(seed=2)
    assert obs.shape == (4, 62) and v4.action_space.shape == (4, 5)
    for _ in range(300):
        obs, r, term, trunc, info = v4.step(np.tile([4, 2, 3, 0, 1], (4, 1)))
        if "final_obs" in info:
            m = info["_final_obs"]
            assert all(info["final_obs"][i].shape == (62,) for i in np.flatnonzero(m))
            assert np.all(obs[m, 9] == 1.0) and np.all(obs[m, 11] == 0.0)  # a new round: nothing scanned yet
            break
    else:
        raise AssertionError("no round against SittingDuck ended in 300 steps")


def test_tank_view_pettingzoo_team_shares_the_score_margin() -> None:
    parallel_api_test(parallel_env(scenario="4v4", opponents="SpinBot", view="tank"), num_cycles=60)
    env = parallel_env(scenario="4v4", opponents="Walls", view="tank", seed=3)
    obs, _ = env.reset(seed=3)
    assert all(o.shape == (62,) for o in obs.values())
    seen_nonzero = False
    for _ in range(40):
        acts = {a: env.action_space(a).sample() for a in env.agents}
        obs, rew, term, trunc, _ = env.step(acts)
        values = set(rew.values())
        assert len(values) <= 1  # one team, one margin
        seen_nonzero |= any(v != 0 for v in values)
        if not env.agents:
            break
    assert seen_nonzero
    with pytest.raises(ValueError, match="action of tank_0: a tank action"):
        env.reset(seed=3)
        env.step({"tank_0": 7})


def test_bad_api_arguments_are_refused_not_rounded() -> None:
    """Issue 34 item 22: 2.5 battles, a seed beyond a Java long, a step that lacks an agent's action."""
    from confront.arena.smdp import TeamBattleEnv

    for bad in (2.5, True, 0, "2"):
        with pytest.raises(ValueError, match="n_battles must be a whole number"):
            TeamBattleEnv("1v1", n_battles=bad, opponents="SpinBot")  # type: ignore[arg-type]
    env = TeamBattleEnv("1v1", n_battles=2, opponents="SpinBot")
    for seed in (2**64, 2**63 - 1, 1.5):
        with pytest.raises(ValueError, match="seed must be a whole number"):
            env.reset(seed=seed)  # type: ignore[arg-type]
    env.reset(seed=np.int64(2**63 - 2))  # the largest a battle pair can take
    pz = parallel_env(scenario="4v4", opponents="SpinBot")
    pz.reset(seed=0)
    with pytest.raises(ValueError, match="actions lack the live agents tank_1, tank_2, tank_3"):
        pz.step({"tank_0": 0})
