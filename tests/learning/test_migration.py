import numpy as np
import pytest

from confront.learning.migration import (
    BinaryTreeMigration,
    convergence_episode,
    convergence_table,
    paper_claims,
    plot_migration,
    q_limit,
    run_migration,
)


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


def test_ssaq_reaches_the_optimum_on_a_small_tree(tmp_path):
    res = run_migration(methods=("ssaq", "greedy"), seeds=3, episodes=400, layers=5)
    assert np.allclose(res.limits, [1000 * 0.9**3, 1000 * 0.9**2, 1000 * 0.9])
    for m in ("ssaq", "greedy"):
        final = res.q[m][:, -1, :]
        assert np.allclose(final, res.limits, rtol=1e-3)
        assert np.all(np.isfinite(res.convergence[m]))
        # a value converges only after the goal was first reached, deeper nodes first
        c = res.convergence[m]
        assert np.all(c[:, 0] >= c[:, 1]) and np.all(c[:, 1] >= c[:, 2])
        assert np.all(c[:, 2] >= res.first_goal[m])
    s = res.summary()
    assert s["ssaq"]["Q3"]["converged"] == 3.0
    assert s["ssaq"]["Q3"]["q25"] <= s["ssaq"]["Q3"]["median"] <= s["ssaq"]["Q3"]["q75"]
    (out,) = plot_migration(res, tmp_path / "fig9.png")
    assert out.stat().st_size > 1000
    assert plot_migration(res, tmp_path)[0].name == "figure9_migration.png"
    table = convergence_table(res)
    assert "| paper, SSAQ | 214 | 168 | 122 |" in table and "| SSAQ |" in table
    claims = paper_claims(res)
    assert [c["text"][:14] for c in claims] == ["SSAQ converges", "Q_15 converges", "SSAQ converges"]
    order = s["ssaq"]
    assert claims[1]["holds"] == (order["Q15"]["median"] <= order["Q7"]["median"] <= order["Q3"]["median"])


def test_greedy_policy_of_trained_ssaq_takes_the_rewarding_path():
    from confront.learning import make_learner
    from confront.learning.base import Transition

    rng = np.random.default_rng(4)
    env = BinaryTreeMigration(layers=4)
    lr = make_learner("ssaq", n_states=16, n_actions=2)
    for _ in range(300):
        s, _ = env.reset()
        done = False
        while not done:
            a = int(lr.act(np.array([s]), rng)[0])
            s2, r, done, _, _ = env.step(a)
            lr.learn(Transition(np.array([s]), np.array([a]), np.array([[r]]), np.array([s2]), np.array([done])))
            s = s2
    assert np.array_equal(lr.act(np.array([1, 3, 7]), rng, explore=False), [1, 1, 1])


def test_bad_method_is_rejected():
    with pytest.raises(ValueError, match="method='sarsa'"):
        run_migration(methods=("sarsa",), seeds=1, episodes=1)
