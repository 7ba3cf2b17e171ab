import numpy as np
import pytest

from confront.learning import Transition, load_learner, make_learner, save_learner


def test_uniform_policy_draws_every_action_equally_and_never_learns(tmp_path):
    lr = make_learner("random", n_actions=4)
    rng = np.random.default_rng(0)
    a = lr.act(np.zeros(40_000, dtype=np.int64), rng, explore=False)  # greedy or not, it stays uniform
    counts = np.bincount(a, minlength=4)
    assert a.dtype == np.int64 and a.min() >= 0 and a.max() <= 3
    assert np.all(np.abs(counts / 40_000 - 0.25) < 0.01)  # 5 standard errors (0.0022 each)
    assert lr.learn(Transition(np.zeros(2, dtype=np.int64), [0, 1], [[1.0], [2.0]], np.zeros(2, dtype=np.int64),
                               [True, True])) == {}
    back = load_learner(save_learner(tmp_path / "u.npz", lr))
    assert (back.kind, back.n_actions, back.observation) == ("random", 4, "discrete")
    with pytest.raises(ValueError, match="n_actions"):
        make_learner("random", n_actions=0)
