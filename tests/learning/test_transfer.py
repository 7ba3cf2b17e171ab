import numpy as np
import pytest

from confront.learning import (
    CurriculumStage,
    Frozen,
    TransferParams,
    TransferPolicy,
    Transition,
    make_learner,
    transfer_epsilon,
    transfer_from,
)


def test_decay_eq34_hand_values():
    # eps(t) = 0.9 exp(-0.1 (t - 10)), floor 0.05
    assert transfer_epsilon(10, 0.9, 0.1, t0=10) == pytest.approx(0.9)
    assert transfer_epsilon(20, 0.9, 0.1, t0=10) == pytest.approx(0.9 * np.exp(-1.0))
    assert transfer_epsilon(20, 0.9, 0.1, t0=10) == pytest.approx(0.331091, abs=1e-6)
    assert transfer_epsilon(5, 0.9, 0.1, t0=10) == pytest.approx(0.9)
    assert transfer_epsilon(1000, 0.9, 0.1, t0=10, floor=0.05) == pytest.approx(0.05)
    assert TransferParams(eps0=0.5, decay=np.log(2), floor=0.0).epsilon(1) == pytest.approx(0.25)


def _tab(best):
    lr = make_learner("qlearning_egreedy", n_states=3, n_actions=3)
    lr.q[:, best] = 1.0
    return lr


def test_transfer_policy_mixes_source_and_current_with_eps():
    src, cur = _tab(0), _tab(2)
    pol = TransferPolicy(cur, src, TransferParams(eps0=0.6, decay=0.0, floor=0.0))
    rng = np.random.default_rng(0)
    # current explores (exploit 0.9): P(action 0) = 0.6 + 0.4 * 0.1/3
    a = pol.act(np.zeros(100_000, dtype=np.int64), rng)
    assert (a == 0).mean() == pytest.approx(0.6 + 0.4 * 0.1 / 3, abs=0.006)
    assert np.all(pol.act(np.zeros(50, dtype=np.int64), rng, explore=False) == 2)


def test_transfer_policy_time_and_learning():
    src, cur = _tab(0), _tab(2)
    pol = TransferPolicy(cur, src, TransferParams(eps0=0.8, decay=0.5, floor=0.1))
    batch = Transition(np.array([1]), np.array([1]), np.array([[3.0]]), np.array([2]), np.array([True]))
    pol.learn(batch)
    assert pol.epsilon() == pytest.approx(0.8 * np.exp(-0.5))
    assert cur.q[1, 1] == pytest.approx(0.1 * 3.0)
    assert src.q[1, 1] == 0.0  # the source is frozen
    assert pol.diagnostics()["transfer_epsilon"] == pytest.approx(pol.epsilon())
    state = pol.state_dict()
    other = TransferPolicy(_tab(1), _tab(1), pol.transfer)
    other.load_state_dict(state)
    assert other.t == 1
    assert np.array_equal(other.current.q, cur.q)
    assert np.array_equal(other.source.inner.q, src.q)


def test_transfer_from_carries_the_model_and_freezes_a_copy():
    src = _tab(1)
    pol = transfer_from(src)
    assert np.array_equal(pol.current.q, src.q)
    pol.current.q[0, 0] = 7.0
    assert src.q[0, 0] == 0.0 and pol.source.inner.q[0, 0] == 0.0
    fresh = transfer_from(src, warm_start=False)
    assert not fresh.current.q.any()
    nxt = transfer_from(pol)  # a curriculum chains: target task starts from the intermediate one's model
    assert nxt.current.q[0, 0] == 7.0


def test_frozen_does_not_learn_and_mismatch_is_rejected():
    lr = _tab(0)
    fz = Frozen(lr)
    assert fz.learn(Transition(np.array([0]), np.array([0]), np.array([[9.0]]), np.array([0]),
                               np.array([True]))) == {}
    assert lr.q[0, 0] == 1.0
    with pytest.raises(ValueError, match="same spaces"):
        TransferPolicy(make_learner("ssaq", n_actions=4), make_learner("ssaq", n_actions=12))
    with pytest.raises(ValueError, match="floor"):
        TransferParams(eps0=0.5, floor=0.6)
    with pytest.raises(ValueError, match="rounds"):
        CurriculumStage("4v6", 0)
