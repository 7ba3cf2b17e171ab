import numpy as np
import pytest

from confront.learning.exploration import (
    ExplorationParams,
    anneal_temperature,
    boltzmann_probs,
    decayed_threshold,
    epsilon_greedy,
    epsilon_greedy_probs,
    greedy,
    sample_categorical,
    select_actions,
    temperature_at,
)


def test_boltzmann_probabilities_eq6_hand_values():
    q = np.array([[1.0, 2.0, 3.0]])
    p = boltzmann_probs(q, 1.0)
    e = np.exp([1.0, 2.0, 3.0])
    assert np.allclose(p, e / e.sum())
    assert np.allclose(p, [[0.09003057, 0.24472847, 0.66524096]])
    # T = 0.5 doubles the logits: exp(2), exp(4), exp(6)
    e2 = np.exp([2.0, 4.0, 6.0])
    assert np.allclose(boltzmann_probs(q, 0.5), e2 / e2.sum())


def test_boltzmann_is_stable_for_huge_values():
    p = boltzmann_probs(np.array([1000.0, 999.0]), 0.01)
    assert np.all(np.isfinite(p))
    assert p[0] == pytest.approx(1.0)
    assert np.allclose(boltzmann_probs(np.zeros((2, 4)), 0.01), 0.25)


def test_annealing_sequence_eq7():
    # T_max = 0.1, T_min = 0.01, eta = 0.9: 0.1, 0.091, 0.0829, 0.07561
    t = 0.1
    seq = [t]
    for _ in range(3):
        t = anneal_temperature(t, 0.9, 0.01)
        seq.append(t)
    assert np.allclose(seq, [0.1, 0.091, 0.0829, 0.07561])
    assert np.allclose(temperature_at(np.arange(4), 0.1, 0.01, 0.9), seq)
    assert temperature_at(1000, 0.1, 0.01, 0.9) == pytest.approx(0.01)
    assert ExplorationParams().temperature(2) == pytest.approx(0.0829)


def test_decayed_threshold():
    assert decayed_threshold(0, 0.9, 0.5) == pytest.approx(0.9)
    assert decayed_threshold(1, 0.9, 0.5) == pytest.approx(0.95)
    assert decayed_threshold(2, 0.9, 0.5) == pytest.approx(0.975)
    p = ExplorationParams(kind="degreedy", exploit=0.9, exploit_decay=0.5)
    assert p.threshold(1) == pytest.approx(0.95)
    assert ExplorationParams(kind="egreedy", exploit=0.9).threshold(50) == pytest.approx(0.9)


def test_sampling_frequencies_match_probabilities():
    rng = np.random.default_rng(1)
    probs = np.tile([0.1, 0.2, 0.7], (200_000, 1))
    counts = np.bincount(sample_categorical(probs, rng), minlength=3) / 200_000
    assert np.allclose(counts, [0.1, 0.2, 0.7], atol=0.005)


def test_epsilon_greedy_uses_exploitation_threshold():
    rng = np.random.default_rng(2)
    q = np.tile([0.0, 5.0, 1.0, 2.0], (200_000, 1))
    a = epsilon_greedy(q, 0.9, rng)
    freq = np.bincount(a, minlength=4) / a.size
    # greedy 90% + a uniform 10% spread over 4 actions
    assert np.allclose(freq, [0.025, 0.925, 0.025, 0.025], atol=0.005)
    assert np.allclose(epsilon_greedy_probs(q[:1], 0.9), [[0.025, 0.925, 0.025, 0.025]])


def test_greedy_breaks_ties_at_random_and_selects_max():
    rng = np.random.default_rng(3)
    q = np.tile([1.0, 3.0, 3.0, 0.0], (10_000, 1))
    a = greedy(q, rng)
    assert set(np.unique(a)) == {1, 2}
    assert abs((a == 1).mean() - 0.5) < 0.03
    assert np.array_equal(select_actions(ExplorationParams(), np.array([[0.0, 2.0, 1.0]]), 0, rng, False), [1])


def test_bad_exploration_values_name_the_key():
    with pytest.raises(ValueError, match="eta"):
        ExplorationParams(eta=1.5)
    with pytest.raises(ValueError, match="t_min"):
        ExplorationParams(t_max=0.1, t_min=0.2)
    with pytest.raises(ValueError, match="exploration"):
        ExplorationParams(kind="ucb")
