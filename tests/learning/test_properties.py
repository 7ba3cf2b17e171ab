"""Property tests: invariants that hold for any input."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from confront.learning.backups import smdp_target
from confront.learning.exploration import boltzmann_probs
from confront.learning.fuzzy import FuzzyLearningRate, FuzzyParams

finite = st.floats(-1e3, 1e3, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (3, 5), elements=finite), st.floats(0.01, 10.0), finite)
def test_boltzmann_rows_sum_to_one_and_ignore_shifts(q, temperature, shift):
    p = boltzmann_probs(q, temperature)
    assert np.allclose(p.sum(axis=1), 1.0)
    assert np.all(p >= 0)
    assert np.allclose(p, boltzmann_probs(q + shift, temperature), atol=1e-9)
    # the arg max keeps the largest probability
    assert np.all(p[np.arange(3), q.argmax(axis=1)] >= p.max(axis=1) - 1e-12)


@settings(max_examples=10, deadline=None)
@given(st.lists(st.floats(0.5, 10.0), min_size=6, max_size=6), st.floats(-50, 50))
def test_fuzzy_rate_is_monotonic_and_within_output_range_for_any_domain(steps, start):
    pts = tuple(np.cumsum([start] + steps).tolist())
    f = FuzzyLearningRate(FuzzyParams(input_points=pts))
    r = np.linspace(pts[0] - 5, pts[-1] + 5, 300)
    a = f(r)
    assert np.all(np.diff(a) >= -1e-9)
    assert np.all((a >= 0.05 - 1e-12) & (a <= 0.95 + 1e-12))
    assert np.allclose(f(r[::7]), f.exact(r[::7], "numpy"), atol=1e-3)


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (4, 3), elements=st.floats(-10, 10)), arrays(np.float64, (4,), elements=finite),
       st.floats(0.0, 1.0))
def test_backups_are_linear_in_rewards_and_bootstrap(r, v, gamma):
    for backup in ("paper", "smdp"):
        base = smdp_target(r, v, gamma, backup)
        assert np.allclose(smdp_target(2 * r, 2 * v, gamma, backup), 2 * base, atol=1e-9)
        assert np.allclose(smdp_target(r + 1.0, v, gamma, backup) - base,
                           smdp_target(np.ones_like(r), np.zeros_like(v), gamma, backup), atol=1e-9)
