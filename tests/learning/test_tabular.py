import numpy as np
import pytest

from confront.learning import Transition, make_learner
from confront.learning.exploration import boltzmann_probs


def _batch(s, a, r, s2, done):
    return Transition(np.array(s), np.array(a), np.array(r, dtype=float), np.array(s2), np.array(done))


def test_ssaq_update_eq8_to_eq10_three_steps():
    lr = make_learner("ssaq", n_states=3, n_actions=2, alpha=0.5, gamma=0.5)
    lr.q[1] = [2.0, 6.0]
    lr.q[0, 1] = 1.0
    # V(s') is the Boltzmann expectation at T_0 = 0.1 (Eq. 9)
    v = float((boltzmann_probs(np.array([2.0, 6.0]), 0.1) * [2.0, 6.0]).sum())
    q2 = 3 + 0.5 * v
    q1 = 2 + 0.5 * q2
    target = (1 + q1 + q2) / 3
    lr.learn(_batch([0], [1], [[1.0, 2.0, 3.0]], [1], [False]))
    assert lr.q[0, 1] == pytest.approx(1.0 + 0.5 * (target - 1.0))
    assert lr.step == 1


def test_td_learner_one_step_q_learning_with_max():
    lr = make_learner("qlearning_egreedy", n_states=2, n_actions=2, alpha=0.1, gamma=0.9)
    lr.q[1] = [4.0, 10.0]
    lr.learn(_batch([0], [0], [[1.0]], [1], [False]))
    assert lr.q[0, 0] == pytest.approx(0.1 * (1 + 0.9 * 10.0))  # Eq. 4
    lr.learn(_batch([1], [1], [[5.0]], [0], [True]))
    assert lr.q[1, 1] == pytest.approx(10.0 + 0.1 * (5.0 - 10.0))


def test_duplicate_state_actions_are_averaged():
    lr = make_learner("qlearning_egreedy", n_states=2, n_actions=2, alpha=0.5)
    lr.learn(_batch([0, 0, 0], [1, 1, 1], [[2.0], [4.0], [6.0]], [1, 1, 1], [True, True, True]))
    assert lr.q[0, 1] == pytest.approx(0.5 * 4.0)


def test_table_update_is_pure_and_averages():
    from confront.learning.tabular import table_update

    q = np.zeros((2, 2))
    out = table_update(q, np.array([1, 1, 0]), np.array([0, 0, 1]), np.array([1.0, 3.0, -2.0]))
    assert np.array_equal(out, [[0.0, -2.0], [2.0, 0.0]])
    assert not q.any()


def test_fuzzy_rate_is_used_per_transition():
    lr = make_learner("ssaq", n_states=2, n_actions=2, rate="fuzzy")
    lr.learn(_batch([0, 1], [0, 0], [[10.0, 10.0], [0.0, 0.0]], [1, 0], [True, True]))
    # summed rewards 20 -> 0.875, 0 -> 0.5; Eq. 10 paper target for T = 2: (r_t + Q_{t+1}) / 2
    assert lr.q[0, 0] == pytest.approx(0.875 * (10 + 10) / 2)
    assert lr.q[1, 0] == pytest.approx(0.0)
    assert lr.diagnostics()["learning_rate"] == pytest.approx((0.875 + 0.5) / 2)


def _chain_step(s, a):
    """States 0..4; a=1 right, a=0 left. Left at 0 pays 2 and ends; reaching 4 pays 10 and ends; else -1."""
    if a == 0 and s == 0:
        return 0, 2.0, True
    s2 = s + 1 if a == 1 else s - 1
    if s2 == 4:
        return 4, 10.0, True
    return s2, -1.0, False


@pytest.mark.parametrize("kind", ["ssaq", "qlearning_egreedy"])
def test_learns_optimal_policy_on_chain(kind):
    rng = np.random.default_rng(0)
    lr = make_learner(kind, n_states=5, n_actions=2, alpha=0.3, gamma=0.9, t_max=5.0, t_min=0.02, eta=0.995)
    for _ in range(600):
        s, done = int(rng.integers(0, 4)), False
        while not done:
            a = int(lr.act(np.array([s]), rng)[0])
            s2, r, done = _chain_step(s, a)
            lr.learn(_batch([s], [a], [[r]], [s2], [done]))
            s = s2
    # optimum by hand with gamma = 0.9: V(3)=10, V(2)=8, V(1)=6.2, V(0)=4.58 (right beats left's 2)
    # (SSAQ's Boltzmann expectation at the final T = 0.02 equals the max to 1e-20 with these gaps)
    assert np.array_equal(lr.act(np.arange(4), rng, explore=False), [1, 1, 1, 1])
    assert np.allclose(lr.q[:4, 1], [4.58, 6.2, 8.0, 10.0], atol=0.05)
    assert lr.q[0, 0] == pytest.approx(2.0, abs=0.05)


def test_state_dict_resume_is_identical():
    def run(lr, rng, n):
        for _ in range(n):
            s = rng.integers(0, 5, 8)
            a = lr.act(s, rng)
            lr.learn(_batch(s, a, rng.normal(size=(8, 3)), rng.integers(0, 5, 8), rng.random(8) < 0.2))

    a = make_learner("ssaq", n_states=5, n_actions=3, rate="fuzzy")
    rng_a = np.random.default_rng(5)
    run(a, rng_a, 20)
    state, rng_state = a.state_dict(), rng_a.bit_generator.state
    run(a, rng_a, 20)
    b = make_learner("ssaq", n_states=5, n_actions=3, rate="fuzzy")
    b.load_state_dict(state)
    rng_b = np.random.default_rng()
    rng_b.bit_generator.state = rng_state
    run(b, rng_b, 20)
    assert np.array_equal(a.q, b.q)
    assert a.diagnostics() == b.diagnostics()


def test_bad_inputs_raise_clear_errors():
    lr = make_learner("ssaq", n_states=4, n_actions=2)
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="outside"):
        lr.act(np.array([4]), rng)
    with pytest.raises(ValueError, match="integer"):
        lr.act(np.array([0.5]), rng)
    with pytest.raises(ValueError, match="alpha"):
        make_learner("ssaq", alpha=0.0)
    with pytest.raises(ValueError, match="state_dict"):
        lr.load_state_dict({"q": np.zeros((3, 2)), "step": np.array(0), "last": np.zeros(2)})


@pytest.mark.parametrize("kind,params", [
    ("ssaq", {}),  # the paper's SSAQ: Boltzmann expectation, Eq. 10, fixed rate
    ("ssaq", {"rate": "fuzzy"}),
    ("ssaq", {"backup": "smdp", "bootstrap": "max"}),
    ("ssaq", {"t_max": 5.0, "eta": 0.999}),  # a temperature that stays high: the expectation matters
    ("qlearning_egreedy", {}),
    ("qlearning_dgreedy", {"bootstrap": "expected", "rate": "fuzzy"}),
])
@pytest.mark.parametrize("t", [1, 3, 10])
def test_learn_one_is_learn_on_a_batch_of_one_bit_for_bit(kind, params, t):
    rng = np.random.default_rng(t)
    batched = make_learner(kind, n_states=6, n_actions=4, **params)
    one = make_learner(kind, n_states=6, n_actions=4, **params)
    for k in range(600):
        s, a, s2 = int(rng.integers(6)), int(rng.integers(4)), int(rng.integers(6))
        r = rng.standard_t(3, t) * 5
        r[rng.random(t) < 0.2] = 0.0
        r[rng.random(t) < 0.1] = -0.0  # Eq. 35 gives -0.0 when we lose energy and the target does not
        done = bool(rng.random() < 0.1)
        before = one.q
        out_b = batched.learn(_batch([s], [a], [r], [s2], [done]))
        out_o = one.learn_one(s, a, r.tolist(), s2, done)
        assert one.q.tobytes() == batched.q.tobytes(), f"step {k}"
        assert out_o == out_b and one.step == batched.step == k + 1
        assert one._last.tobytes() == batched._last.tobytes()
        assert one.q is not before  # a new table, as table_update's
    assert one.diagnostics() == batched.diagnostics()


def test_learn_one_values_by_hand_and_bad_input():
    lr = make_learner("qlearning_egreedy", n_states=2, n_actions=2, alpha=0.1, gamma=0.9)
    lr.q[1] = [4.0, 10.0]
    assert lr.learn_one(0, 0, [1.0], 1, False) == {"td_error": pytest.approx(10.0), "learning_rate": 0.1}
    assert lr.q[0, 0] == pytest.approx(0.1 * (1 + 0.9 * 10.0))  # Eq. 4, as test_td_learner_one_step above
    for bad in ((2, 0, [1.0], 0, False), (0, 2, [1.0], 0, False), (0, 0, [1.0], -1, False), (0, 0, [], 0, False)):
        with pytest.raises(ValueError):
            lr.learn_one(*bad)
    assert lr.step == 1
