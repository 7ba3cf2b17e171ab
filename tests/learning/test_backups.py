import numpy as np
import pytest

from confront.learning.backups import bootstrap_values, intermediate_values, smdp_target


def test_three_step_example_eq8_to_eq10():
    # r = 1, 2, 3 over T = 3 turns, gamma = 0.5, V(s') = 4
    r = np.array([[1.0, 2.0, 3.0]])
    v = np.array([4.0])
    # Eq. 9: Q_{t+2} = 3 + 0.5*4 = 5; Eq. 8: Q_{t+1} = 2 + 0.5*5 = 4.5, Q_t = 1 + 0.5*4.5 = 3.25
    assert np.allclose(intermediate_values(r, v, 0.5), [[3.25, 4.5, 5.0]])
    # Eq. 10: (r_t + Q_{t+1} + Q_{t+2}) / 3 = (1 + 4.5 + 5) / 3 = 3.5
    assert smdp_target(r, v, 0.5, "paper") == pytest.approx([3.5])
    # textbook: 1 + 0.5*2 + 0.25*3 + 0.125*4 = 3.25
    assert smdp_target(r, v, 0.5, "smdp") == pytest.approx([3.25])


def test_single_turn_backups_agree_with_one_step_q_learning():
    r = np.array([[2.0], [-1.0]])
    v = np.array([10.0, 0.0])
    for backup in ("paper", "smdp"):
        assert np.allclose(smdp_target(r, v, 0.9, backup), [11.0, -1.0])


def test_bootstrap_expected_and_max_and_done():
    q_next = np.array([[1.0, 3.0], [2.0, 2.0]])
    probs = np.array([[0.25, 0.75], [0.5, 0.5]])
    assert np.allclose(bootstrap_values(q_next, probs, np.array([False, False])), [2.5, 2.0])
    assert np.allclose(bootstrap_values(q_next, None, np.array([False, True])), [3.0, 0.0])


def test_unknown_backup_is_rejected():
    with pytest.raises(ValueError, match="backup"):
        smdp_target(np.zeros((1, 2)), np.zeros(1), 0.9, "nstep")


@pytest.mark.parametrize("n", [*range(1, 40), 127, 128, 129, 200, 256, 300])
def test_pairwise_sum_is_numpys_sum_bit_for_bit(n):
    from confront.learning.backups import pairwise_sum

    rng = np.random.default_rng(n)
    for _ in range(50):
        a = rng.standard_normal(n) * 10.0 ** rng.integers(-6, 6, n)  # magnitudes apart: the order shows
        assert pairwise_sum(a.tolist()).hex() == float(a.sum()).hex()
        assert pairwise_sum(a.tolist(), 1).hex() == float(a[None, 1:].sum(axis=1)[0]).hex()
    zeros = [-0.0] * n
    assert pairwise_sum(zeros).hex() == float(np.sum(zeros)).hex() == "0x0.0p+0"  # +0.0, as NumPy's


def test_pairwise_sum_order_by_hand():
    from confront.learning.backups import pairwise_sum

    # below 8 values left to right: 1e16 + 1 rounds back to 1e16 (the doubles there are 2 apart), twice
    assert pairwise_sum([1e16, 1.0, 1.0]) == 1e16
    # from 8 values on, pairs first: ((1e16 + 1) + (1 + 1)) + ((1 + 1) + (1 + 1)) = 1e16 + 6
    assert pairwise_sum([1e16] + [1.0] * 7) == 1e16 + 6 == np.sum([1e16] + [1.0] * 7)


@pytest.mark.parametrize("t", [1, 2, 3, 9, 10, 11, 17])
def test_paper_target_one_is_smdp_target_bit_for_bit(t):
    from confront.learning.backups import paper_target_one

    rng = np.random.default_rng(t)
    for _ in range(200):
        r = rng.standard_t(3, (1, t)) * 5
        v = rng.normal() * 10
        want = float(smdp_target(r, np.array([v]), 0.9, "paper")[0])
        assert paper_target_one(r[0].tolist(), v, 0.9).hex() == want.hex()
    assert paper_target_one([1.0, 2.0, 3.0], 4.0, 0.5) == 3.5  # the three-step example above
