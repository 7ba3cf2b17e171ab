import numpy as np
import pytest

from confront.learning.fuzzy import (
    FuzzyLearningRate,
    FuzzyParams,
    memberships,
    memberships_numpy,
    paper_learning_rate,
    plot_fuzzy,
)

PTS = np.array([-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0])


def test_memberships_eq11_hand_values():
    mu = memberships(np.array([-25.0, -15.0, 0.0, 5.0, 25.0]), PTS)
    # LN is 1 below -20, (-10 - r)/10 between -20 and -10
    assert np.allclose(mu[:, 0], [1, 0, 0, 0, 0])
    assert np.allclose(mu[:, 1], [0.5, 0.5, 0, 0, 0])
    assert np.allclose(mu[:, 2], [0, 0, 1, 0, 0])
    assert np.allclose(mu[:, 3], [0, 0, 0.5, 0.5, 0])
    assert np.allclose(mu[:, 4], [0, 0, 0, 0, 1])


def test_skfuzzy_and_numpy_memberships_agree():
    x = np.linspace(-30, 30, 1201)
    assert np.allclose(memberships(x, PTS), memberships_numpy(x, PTS))


@pytest.mark.parametrize(
    ("reward", "rate"),
    [
        (0.0, 0.5),  # ZO -> M only
        (5.0, 0.575),  # FI = [0,0,0,.5,.5,0,0] -> (0.5 + 0.65)/2
        (10.0, 0.65),  # TP -> LL, peak at 0.65
        (12.5, 0.74),  # (0.75*0.65 + 0.25*0.8 + 0.25*0.95)/1.25
        (15.0, 0.8),  # (0.65 + 0.8 + 0.95)/3
        (20.0, 0.875),  # LP -> VL = (0.8 + 0.95)/2
        (30.0, 0.875),
        (-10.0, 0.35),
        (-15.0, 0.2),
        (-30.0, 0.125),
        (100.0, 0.875),  # clipped
        (-100.0, 0.125),
    ],
)
def test_fuzzy_rate_hand_values(reward, rate):
    assert paper_learning_rate(reward) == pytest.approx(rate, abs=1e-9)


def test_fuzzy_rate_symmetric_monotonic_and_table_matches_exact():
    f = FuzzyLearningRate()
    r = np.linspace(-40, 40, 4001)
    a = f(r)
    assert np.all(np.diff(a) >= -1e-12)
    assert np.allclose(a + a[::-1], 1.0)  # alpha(-r) = 1 - alpha(r) with the symmetric domains
    x = np.random.default_rng(0).uniform(-35, 35, 2000)
    assert np.allclose(f(x), f.exact(x, "numpy"), atol=1e-6)
    assert np.allclose(f.exact(x[:200], "skfuzzy"), f.exact(x[:200], "numpy"), atol=1e-12)
    assert isinstance(f(3.0), float)


def test_reversed_rules_give_descending_reading():
    f = FuzzyLearningRate(FuzzyParams(rules=(4, 3, 2, 1, 0)))
    assert f(30.0) == pytest.approx(0.125)
    assert f(-30.0) == pytest.approx(0.875)
    assert f(0.0) == pytest.approx(0.5)


def test_bad_fuzzy_params_name_the_key():
    with pytest.raises(ValueError, match="input_points"):
        FuzzyParams(input_points=(0.0, 1.0, 2.0))
    with pytest.raises(ValueError, match="output_points"):
        FuzzyParams(output_points=(0.95, 0.8, 0.65, 0.5, 0.35, 0.2, 0.05))
    with pytest.raises(ValueError, match="rules"):
        FuzzyParams(rules=(0, 0, 1, 2, 3))


def test_plot_fuzzy_writes_png(tmp_path):
    out = plot_fuzzy(tmp_path / "fig13.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_fuzzy_scalar_is_the_array_path_bit_for_bit():
    flr = FuzzyLearningRate()
    rng = np.random.default_rng(0)
    rewards = np.concatenate([rng.standard_t(2, 3000) * 20, flr.grid, [-1e9, 1e9, 0.0, -0.0]])
    for r, rate in zip(rewards.tolist(), flr(rewards).tolist(), strict=True):
        assert flr.scalar(r).hex() == rate.hex()
