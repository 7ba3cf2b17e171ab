"""PoolEnv: the entries' kernels run together, with the same results as stepping each env on its own."""

import numpy as np
import pytest

from confront.arena.pool import PoolEntry, PoolEnv
from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.tank import TankSpace

CONFIG = SMDPConfig(turns_per_step=5, tank=TankSpace(), reward="score")


def _paper_random(disc: np.ndarray, feats: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return rng.integers(0, 4, size=len(disc))


def _entries() -> list[PoolEntry]:
    return [PoolEntry("1v1/SpinBot", "1v1", "SpinBot", 3), PoolEntry("4v4/td", "4v4", "td", 2, policy=_paper_random,
                                                                      opponent_actions="paper"),
            PoolEntry("4v4/Walls", "4v4", "Walls", 2), PoolEntry("1v1/Crazy", "1v1", "Crazy", 9),
            PoolEntry("1v1/td", "1v1", "td", 2, policy=_paper_random, opponent_actions="paper")]


@pytest.mark.parametrize("pick", [(0, 1, 2, 3, 4), (3, 1)])  # one kernel call per entry; battle ranges
def test_pool_step_equals_each_env_stepped_alone(pick: tuple[int, ...]) -> None:
    pool = PoolEnv([_entries()[i] for i in pick], CONFIG, seed=3)
    # the same envs, stepped one by one with the actions the pool gives them
    alone = [TeamBattleEnv(e.scenario, n_battles=e.battles, seed=3 * 1000 + k, opponents=e.opponents, config=CONFIG,
                           opponent_actions=e.opponent_actions) for k, e in enumerate(pool.entries)]
    obs = pool.reset()
    last = [env.reset() for env in alone]
    rng, opp_rng = np.random.default_rng(0), np.random.default_rng([3, 17])
    n_rounds = 0
    for _ in range(60):
        a = rng.integers(0, int(np.prod(pool.action_dims)), size=pool.n_agents)
        st = pool.step(a)
        want_obs, want_rew, want_rounds = [], [], 0
        for k, (e, env) in enumerate(zip(pool.entries, alone, strict=True)):
            ours = env.team_ids() == 0
            full = np.zeros((env.n_battles, env.n_robots), dtype=np.int64)
            full[:, ours] = a[pool.bounds[k]:pool.bounds[k + 1]].reshape(env.n_battles, -1)
            if e.policy is not None:
                theirs = ~ours
                full[:, theirs] = e.policy(last[k][0][:, theirs].reshape(-1), None, opp_rng).reshape(env.n_battles, -1)
            res = env.step(full)
            last[k] = (res.discrete, res.features)
            want_obs.append(res.features[:, ours].reshape(-1, pool.n_features))
            want_rew.append(res.rewards[:, ours].sum(axis=2).reshape(-1))
            want_rounds += 0 if res.round_end is None else int(res.round_end.mask.sum())
        np.testing.assert_array_equal(st.obs, np.concatenate(want_obs))
        np.testing.assert_array_equal(st.reward, np.concatenate(want_rew))
        assert len(st.rounds) == want_rounds
        n_rounds += len(st.rounds)
        obs = st.obs
    assert obs.shape == (pool.n_agents, pool.n_features) and n_rounds > 0


def test_pool_computes_observations_only_for_those_read() -> None:
    pool = PoolEnv(_entries(), CONFIG, seed=1)
    pool.reset()
    rng = np.random.default_rng(1)
    for _ in range(5):
        pool.step(rng.integers(0, int(np.prod(pool.action_dims)), size=pool.n_agents))
    for env, feats in zip(pool.envs, pool._feats, strict=True):
        assert (env.view_robots == env.learner).all()
        assert not feats[:, ~env.learner].any() and (env.slots[:, ~env.learner] == -1).all()
        assert feats[:, env.learner].any()
    for env, disc in zip(pool.envs, pool._disc, strict=True):  # paper observations only for the opponents' policies
        assert (env.paper_robots == (env.learner & (env.team_ids() != 0))).all()
        assert not disc[:, ~env.paper_robots].any()


def test_waiting_entries_keep_their_battles_and_give_no_transitions() -> None:
    """An entry that does not play waits where it is: its agents' observations do not change, their reward is 0 and
    inactive; when it plays again it goes on as if the waiting steps had not been (= an env stepped only then)."""
    entries = [PoolEntry("1v1/SpinBot", "1v1", "SpinBot", 3), PoolEntry("4v4/Walls", "4v4", "Walls", 2)]
    pool = PoolEnv(entries, CONFIG, seed=5)
    alone = TeamBattleEnv("4v4", n_battles=2, seed=5 * 1000 + 1, opponents="Walls", config=CONFIG)
    obs = pool.reset()
    alone.reset()
    ours = alone.team_ids() == 0
    rng = np.random.default_rng(1)
    lo, hi = int(pool.bounds[1]), int(pool.bounds[2])
    played = 0
    for step in range(40):
        a = rng.integers(0, int(np.prod(pool.action_dims)), size=pool.n_agents)
        playing = np.array([True, step % 3 == 0])
        st = pool.step(a, playing)
        if playing[1]:
            full = np.zeros((2, alone.n_robots), dtype=np.int64)
            full[:, ours] = a[lo:hi].reshape(2, -1)
            res = alone.step(full)
            np.testing.assert_array_equal(st.obs[lo:hi], res.features[:, ours].reshape(-1, pool.n_features))
            played += 1
        else:
            np.testing.assert_array_equal(st.obs[lo:hi], obs[lo:hi])
            assert not st.active[lo:hi].any() and not st.reward[lo:hi].any() and not st.done[lo:hi].any()
            assert all(r["opponent"] == "1v1/SpinBot" for r in st.rounds)
        assert st.active[:lo].any()
        obs = st.obs
    assert played == 14
    with pytest.raises(ValueError, match="playing must have shape"):
        pool.step(np.zeros(pool.n_agents, dtype=np.int64), np.array([True]))
