"""Hand-computed cases for the paper's state bins, targets, features and Eq. 35 reward."""

import numpy as np
import pytest

from confront.arena import observe as ob


def _deg(a: float) -> float:
    return np.deg2rad(a)


def test_bearing_convention_north_east() -> None:
    z = np.zeros(1)
    # target straight up (north) -> 0; to the right (east) -> 90 deg; below -> 180; left -> 270
    assert ob.absolute_bearing(z, z, z, z + 10)[0] == pytest.approx(0.0)
    assert ob.absolute_bearing(z, z, z + 10, z)[0] == pytest.approx(_deg(90))
    assert ob.absolute_bearing(z, z, z, z - 10)[0] == pytest.approx(_deg(180))
    assert ob.absolute_bearing(z, z, z - 10, z)[0] == pytest.approx(_deg(270))


def test_angle_bins_centred_and_quadrants() -> None:
    a = np.deg2rad(np.array([0.0, 44.9, 45.0, 134.9, 135.0, 224.9, 225.0, 314.9, 315.0, 359.9]))
    assert ob.angle_bins(a, 4, centred=True).tolist() == [0, 0, 1, 1, 2, 2, 3, 3, 0, 0]
    assert ob.angle_bins(a, 4, centred=False).tolist() == [0, 0, 0, 1, 1, 2, 2, 3, 3, 3]


def test_distance_bins_edges() -> None:
    d = np.array([0.0, 49.99, 50.0, 999.0, 1000.0, 5000.0])
    assert ob.distance_bins(d, 1000.0).tolist() == [0, 0, 1, 19, 19, 19]


def test_state_index_range_and_formula() -> None:
    assert ob.state_index(np.array(3), np.array(3), np.array(19)) == 319
    assert ob.state_index(np.array(1), np.array(2), np.array(5)) == (1 * 4 + 2) * 20 + 5
    assert ob.N_STATES == 320


def _two_robots(x1: float, y1: float, h1: float, x2: float, y2: float):
    x = np.array([[x1, x2]])
    y = np.array([[y1, y2]])
    h = np.array([[h1, 0.0]])
    e = np.array([[100.0, 40.0]])
    alive = np.array([[True, True]])
    team = np.array([0, 1])
    return x, y, h, e, alive, team


def test_discrete_state_hand_case() -> None:
    # robot 0 at (100, 100) heading 100 deg (quadrant 1); enemy at (400, 500): d = 500 -> bin 10 on an
    # 800x600 field (diagonal 1000); bearing atan2(300, 400) = 36.87 deg,
    # relative = -63.13 = 296.87 deg -> left (3)
    x, y, h, e, alive, team = _two_robots(100, 100, _deg(100), 400, 500)
    cfg = ob.ObservationConfig()
    tgt, disc, feats = ob.observe(x, y, h, e, alive, team, (800.0, 600.0), cfg)
    assert tgt.tolist() == [[1, 0]]
    assert disc[0, 0] == (3 * 4 + 1) * 20 + 10
    rel = np.deg2rad(36.869897645844 - 100.0)
    np.testing.assert_allclose(
        feats[0, 0],
        [np.sin(rel), np.cos(rel), np.sin(_deg(100)), np.cos(_deg(100)), 0.5, 1.0, 0.4],
        rtol=0,
        atol=1e-6,
    )
    # robot 1 (heading 0) sees robot 0 at bearing 216.87 -> behind (2), heading quadrant 0, same distance
    assert disc[0, 1] == (2 * 4 + 0) * 20 + 10
    assert feats[0, 1, 6] == pytest.approx(1.0)


def test_targets_nearest_weakest_and_none() -> None:
    # team 0: robots 0, 1; team 1: robots 2 (near robot 0, energy 80), 3 (far, energy 20)
    x = np.array([[0.0, 10.0, 100.0, 500.0]])
    y = np.zeros((1, 4))
    e = np.array([[100.0, 100.0, 80.0, 20.0]])
    alive = np.ones((1, 4), bool)
    team = np.array([0, 0, 1, 1])
    assert ob.select_targets(x, y, e, alive, team, "nearest").tolist() == [[2, 2, 1, 1]]
    # team 1 sees two equally weak enemies (100): the nearer one, robot 1, wins the tie
    assert ob.select_targets(x, y, e, alive, team, "weakest").tolist() == [[3, 3, 1, 1]]
    alive2 = np.array([[True, True, False, False]])
    assert ob.select_targets(x, y, e, alive2, team, "nearest").tolist() == [[-1, -1, 1, 1]]
    # dead robots still get targets; a dead enemy is never a target
    alive3 = np.array([[True, True, False, True]])
    assert ob.select_targets(x, y, e, alive3, team, "nearest").tolist() == [[3, 3, 1, 1]]


def test_weakest_tie_broken_by_distance() -> None:
    x = np.array([[0.0, 300.0, 100.0]])
    y = np.zeros((1, 3))
    e = np.array([[100.0, 50.0, 50.0]])
    alive = np.ones((1, 3), bool)
    assert ob.select_targets(x, y, e, alive, np.array([0, 1, 1]), "weakest")[0, 0] == 2


def test_no_target_gives_zero_geometry() -> None:
    x, y, h, e, _, team = _two_robots(100, 100, _deg(200), 400, 500)
    alive = np.array([[True, False]])
    tgt, disc, feats = ob.observe(x, y, h, e, alive, team, (800.0, 600.0), ob.ObservationConfig())
    assert tgt[0, 0] == -1
    assert disc[0, 0] == (0 * 4 + 2) * 20 + 0
    assert feats[0, 0, 4] == 0.0 and feats[0, 0, 6] == 0.0 and feats[0, 0, 1] == 1.0


def test_position_features_and_max_distance() -> None:
    x, y, h, e, alive, team = _two_robots(100, 150, 0.0, 100, 450)
    cfg = ob.ObservationConfig(include_position=True, max_distance=600.0)
    _, disc, feats = ob.observe(x, y, h, e, alive, team, (800.0, 600.0), cfg)
    assert feats.shape == (1, 2, cfg.n_features) == (1, 2, 9)
    assert feats[0, 0, 4] == pytest.approx(0.5)
    assert feats[0, 0, 7:].tolist() == pytest.approx([0.125, 0.25])
    assert disc[0, 0] == 10  # ahead, heading quadrant 0, 300 px of 600 -> bin 10


def test_reward_eq35_hand_cases() -> None:
    # we lose 0, enemy loses 16: (0 - (-16)) * 16 / |100 - 100| -> guard 1 -> 256
    assert ob.reward_eq35(np.array(100.0), np.array(100.0), np.array(100.0), np.array(84.0)) == 256.0
    # we lose 4, enemy loses 10 from 50: (-4 + 10) * 10 / |80 - 50| = 2
    r = ob.reward_eq35(np.array(80.0), np.array(76.0), np.array(50.0), np.array(40.0))
    assert r == pytest.approx(2.0)
    # enemy unchanged -> 0 whatever we lose
    assert ob.reward_eq35(np.array(80.0), np.array(70.0), np.array(50.0), np.array(50.0)) == 0.0
    # enemy gains energy (its bullet hit us): (-3 - 9) * 9 / 20 = -5.4
    r = ob.reward_eq35(np.array(70.0), np.array(67.0), np.array(50.0), np.array(59.0))
    assert r == pytest.approx(-5.4)
    # denominator 0.5 < guard 1 -> divided by 1; with guard 0.25 -> by 0.5
    args = (np.array(50.5), np.array(50.5), np.array(50.0), np.array(48.0))
    assert ob.reward_eq35(*args) == pytest.approx(4.0)
    assert ob.reward_eq35(*args, guard=0.25) == pytest.approx(8.0)


def test_config_errors() -> None:
    with pytest.raises(ValueError, match="target"):
        ob.ObservationConfig(target="far")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="max_distance"):
        ob.ObservationConfig(max_distance=0.0)
    with pytest.raises(ValueError, match="reward_guard"):
        ob.ObservationConfig(reward_guard=0.0)


def test_compiled_observe_matches_array_functions() -> None:
    rng = np.random.default_rng(7)
    b, r = 5, 6
    x = rng.uniform(18, 782, (b, r))
    y = rng.uniform(18, 582, (b, r))
    h = rng.uniform(0, 2 * np.pi, (b, r))
    e = rng.uniform(0, 120, (b, r))
    alive = rng.random((b, r)) > 0.3
    team = np.array([0, 0, 1, 1, 2, 2])
    for rule in ("nearest", "weakest"):
        cfg = ob.ObservationConfig(target=rule, include_position=True)
        tgt, disc, feats = ob.observe(x, y, h, e, alive, team, (800.0, 600.0), cfg)
        np.testing.assert_array_equal(tgt, ob.select_targets(x, y, e, alive, team, rule))
        np.testing.assert_array_equal(disc, ob.discrete_state(x, y, h, tgt, 1000.0))
        np.testing.assert_allclose(feats, ob.features(x, y, h, e, tgt, 1000.0, (800.0, 600.0)), atol=1e-6)
