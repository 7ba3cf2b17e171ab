import numpy as np
import pytest

from confront.experiments.migration import (
    METHODS,
    BinaryTreeMigration,
    MigrationResult,
    convergence_episode,
    convergence_table,
    paired_rows,
    paired_table,
    paper_claims,
    plot_migration,
    q_limit,
    run_migration,
    seed_draws,
)
from confront.learning import make_learner
from confront.learning.base import Transition
from confront.learning.exploration import policy_probs

TABLE1 = {"alpha": 0.3, "gamma": 0.9, "exploit": 0.9, "eta": 0.9, "t_max": 0.1, "t_min": 0.01, "exploit_decay": 0.99}


def test_environment_walks_the_heap_numbered_tree():
    env = BinaryTreeMigration(layers=3)
    assert env.reset()[0] == 1
    assert env.step(1)[:3] == (3, 0.0, False)
    assert env.step(1)[:3] == (7, 1000.0, True)
    env.reset()
    env.step(0)
    assert env.step(1)[:3] == (5, 0.0, True)
    with pytest.raises(ValueError, match="reset"):
        env.step(0)
    with pytest.raises(ValueError, match="action"):
        BinaryTreeMigration(3).step(2)


def test_limits_and_convergence_criterion():
    # N = 10, gamma = 0.9: Q_3 = 0.9^8 1000, Q_7 = 0.9^7 1000, Q_15 = 0.9^6 1000
    assert q_limit(3, 10, 0.9) == pytest.approx(430.46721)
    assert q_limit(7, 10, 0.9) == pytest.approx(478.2969)
    assert q_limit(15, 10, 0.9) == pytest.approx(531.441)
    assert q_limit(1023, 10, 0.9) == pytest.approx(1000.0)
    vals = np.array([0.0, 50.0, 99.5, 98.0, 99.2, 100.0])
    assert convergence_episode(vals, 100.0, 0.01) == 5.0
    assert np.isnan(convergence_episode(np.array([100.0, 50.0]), 100.0))
    assert convergence_episode(np.full(3, 100.0), 100.0) == 1.0


def _reference(kind: str, u: np.ndarray, layers: int) -> tuple[np.ndarray, float]:
    """One seed with the project's TabularQ learner, moving by the inverse CDF of its policy on the draws u."""
    env = BinaryTreeMigration(layers)
    lr = make_learner(kind, n_states=2**layers, n_actions=2, **TABLE1)
    ex = lr.params.exploration_params()
    out = np.empty((u.shape[0], 3))
    first = float("nan")
    for e in range(u.shape[0]):
        s, _ = env.reset()
        obs, act, rew, nxt = [], [], [], []
        for i in range(layers - 1):
            a = int(u[e, i] >= policy_probs(ex, lr.q[s], lr.step)[0])
            s2, r, _, _, _ = env.step(a)
            obs.append(s), act.append(a), rew.append([r]), nxt.append(s2)
            s = s2
        done = np.zeros(layers - 1, bool)
        done[-1] = True
        lr.learn(Transition(np.array(obs), np.array(act), np.array(rew), np.array(nxt), done))
        out[e] = lr.q[[1, 3, 7], [1, 1, 1]]
        if s == env.goal and first != first:
            first = float(e + 1)
    return out, first


def test_vectorised_run_equals_the_tabular_learners_on_the_same_draws():
    layers, seeds, episodes = 5, 3, 150
    res = run_migration(seeds=seeds, episodes=episodes, layers=layers, seed=11, keep_runs=True)
    u = np.concatenate(list(seed_draws(11, seeds, episodes, layers - 1)), axis=1)
    for m, kind in METHODS.items():
        # the kernel's per-episode quartiles over seeds are NumPy's (linear interpolation)
        np.testing.assert_allclose(res.bands[m], np.quantile(res.q[m], [0.25, 0.5, 0.75], axis=0), rtol=0, atol=1e-12)
        for s in range(seeds):
            traj, first = _reference(kind, u[s], layers)
            np.testing.assert_allclose(res.q[m][s], traj, rtol=1e-12, atol=1e-9)
            assert res.first_goal[m][s] == first
            for j in range(3):
                ref = convergence_episode(traj[:, j], res.limits[j])
                assert res.convergence[m][s, j] == ref or (np.isnan(ref) and np.isnan(res.convergence[m][s, j]))


def test_draws_are_per_seed_streams_whatever_the_chunking():
    chunks = list(seed_draws(7, 3, 10, 4, chunk=3))
    assert [c.shape for c in chunks] == [(3, 3, 4), (3, 3, 4), (3, 3, 4), (3, 1, 4)]
    u = np.concatenate(chunks, axis=1)
    for i in range(3):
        np.testing.assert_array_equal(u[i], np.random.default_rng(7 + i).random((10, 4)))


def test_changing_only_the_policy_leaves_the_draws_identical():
    # while every Q is 0 each policy is 50/50, so on shared draws all methods walk the same path until the
    # first reward: the first episode whose moves all go right (u >= 0.5)
    layers, seeds, episodes = 5, 40, 200
    res = run_migration(seeds=seeds, episodes=episodes, layers=layers, seed=3)
    u = np.concatenate(list(seed_draws(3, seeds, episodes, layers - 1)), axis=1)
    right = (u >= 0.5).all(axis=2)
    expected = np.where(right.any(axis=1), right.argmax(axis=1) + 1.0, np.nan)
    for m in METHODS:
        np.testing.assert_array_equal(res.first_goal[m], expected)


def test_a_block_of_seeds_run_alone_equals_its_slice_of_a_larger_run():
    big = run_migration(seeds=6, episodes=300, layers=5, seed=100)
    part = run_migration(seeds=2, episodes=300, layers=5, seed=103)
    for m in METHODS:
        np.testing.assert_array_equal(part.convergence[m], big.convergence[m][3:5])
        np.testing.assert_array_equal(part.final_q[m], big.final_q[m][3:5])
    sub = big.subset(slice(3, 5))
    assert sub.seeds == 2 and sub.settings["seeds"] == 2
    np.testing.assert_array_equal(sub.first_goal["ssaq"], part.first_goal["ssaq"])


def test_every_method_reaches_the_optimum_on_a_small_tree(tmp_path):
    res = run_migration(seeds=5, episodes=400, layers=5)
    assert np.allclose(res.limits, [1000 * 0.9**3, 1000 * 0.9**2, 1000 * 0.9])
    for m in METHODS:
        assert np.allclose(res.final_q[m], res.limits, rtol=1e-3)
        c = res.convergence[m]
        assert np.all(np.isfinite(c))
        # a value converges only after the goal was first reached, deeper nodes first
        assert np.all(c[:, 0] >= c[:, 1]) and np.all(c[:, 1] >= c[:, 2])
        assert np.all(c[:, 2] >= res.first_goal[m])
        q25, med, q75 = res.bands[m][:, -1, :]
        assert np.allclose(med, res.limits, rtol=1e-3) and np.all(q25 <= med) and np.all(med <= q75)
    s = res.summary()
    assert s["ssaq"]["Q3"]["converged"] == 5.0
    (out,) = plot_migration(res, tmp_path / "fig9.png")
    assert out.stat().st_size > 1000
    assert plot_migration(res, tmp_path)[0].name == "figure9_migration.png"
    with pytest.raises(ValueError, match="subset"):
        plot_migration(res.subset(slice(0, 2)), tmp_path)
    table = convergence_table(res)
    assert "| paper, SSAQ | 214 | 168 | 122 |" in table and "| SSAQ |" in table and "5/5" in table


def _crafted(conv: dict[str, np.ndarray]) -> MigrationResult:
    n = next(iter(conv.values())).shape[0]
    return MigrationResult(limits=np.array([430.47, 478.30, 531.44]), convergence=conv,
                           first_goal={m: np.ones(n) for m in conv}, final_q={m: np.zeros((n, 3)) for m in conv})


def test_claims_hold_on_runs_shaped_like_the_paper():
    # 20 seeds at the paper's episodes +- 10, Greedy 30 and Dgreedy 60 episodes later on every seed
    jitter = np.linspace(-10, 10, 20)[:, None]
    ssaq = np.array([214.0, 168.0, 122.0]) + jitter
    res = _crafted({"ssaq": ssaq, "greedy": ssaq + 30, "dgreedy": ssaq + 60})
    claims = paper_claims(res)
    assert [c["verdict"] for c in claims] == ["holds", "holds", "holds"]
    assert "Q_3 - Q_7 46 [46, 46]" in claims[1]["effect"]
    # sign test with 20 of 20 pairs the same way: p = 0.5^20
    rows = paired_rows(res)
    assert rows[0]["sign"].p == pytest.approx(0.5**20)
    assert rows[0]["diff"].mean == 30.0
    assert "| SSAQ vs Greedy-policy | Q_3 | 100.0% / 0.0% / 0.0% | 30 [30, 30] |" in paired_table(res)


def test_claims_partly_and_no():
    # structural gaps (4 and 5 episodes), 900 episodes, SSAQ earlier than Greedy but tied with Dgreedy;
    # one censored SSAQ run (NaN) counts as later than any finite episode
    base = 900.0 + np.arange(30)[:, None] + np.array([9.0, 5.0, 0.0])
    ssaq = base.copy()
    ssaq[0] = np.nan
    res = _crafted({"ssaq": ssaq, "greedy": base + 14, "dgreedy": base})
    level, order, faster = paper_claims(res)
    assert (level["verdict"], order["verdict"], faster["verdict"]) == ("no", "partly", "partly")
    st = paired_rows(res)[3]["sign"]  # SSAQ vs Dgreedy at Q_3: 29 ties, the censored seed later
    assert (st.less, st.equal, st.greater) == (0, 29, 1)
    assert st.p == 1.0
    st_g = paired_rows(res)[0]["sign"]  # SSAQ vs Greedy: 29 earlier, the censored seed later
    assert (st_g.less, st_g.greater) == (29, 1)
    assert st_g.p == pytest.approx(31 / 2**30)  # P(X >= 29), X ~ Bin(30, 1/2) = (C(30,29) + 1) / 2^30


def test_verdicts_are_stable_on_five_disjoint_blocks_of_seeds():
    res = run_migration(seeds=1000)
    full = [c["verdict"] for c in paper_claims(res)]
    assert full == ["no", "partly", "partly"]
    for k in range(5):
        block = res.subset(slice(200 * k, 200 * (k + 1)))
        assert [c["verdict"] for c in paper_claims(block)] == full, k


def test_bad_arguments_are_rejected():
    with pytest.raises(ValueError, match="method='sarsa'"):
        run_migration(methods=("sarsa",), seeds=1, episodes=1)
    for seeds in (0, -1):
        with pytest.raises(ValueError, match="seeds"):
            run_migration(seeds=seeds, episodes=1)
