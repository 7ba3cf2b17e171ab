"""Each rule of confront.arena.rules against hand-computed values."""

import math

import numpy as np
import pytest

from confront.arena import rules as R


def test_ahead_25_from_standstill():
    v, d, out = 0.0, 25.0, []
    for _ in range(9):
        v = R.new_velocity(v, d)
        d -= v
        out.append(v)
    assert out == pytest.approx([1, 2, 3, 4, 5, 16 / 3, 10 / 3, 4 / 3, 0], abs=1e-12)
    assert d == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("v, expected", [(-1.0, 0.5), (-2.0, 0.0), (-8.0, -6.0), (8.0, 8.0), (3.0, 4.0)])
def test_new_velocity_reversing_and_accelerating(v, expected):
    assert R.new_velocity(v, 1000.0) == pytest.approx(expected)


def test_new_velocity_mirrored_backwards():
    assert R.new_velocity(0.0, -1000.0) == -1.0
    assert R.new_velocity(1.0, -1000.0) == pytest.approx(-0.5)


def test_max_velocity_setting_caps_goal():
    assert R.new_velocity(4.0, math.inf, 5.0) == 5.0
    assert R.new_velocity(4.0, math.inf, 3.0) == 3.0


def test_distance_until_stop():
    assert R.distance_until_stop(8.0) == 12.0  # 6 + 4 + 2
    assert R.distance_until_stop(-5.0) == 3 + 1


def test_turn_rate_at_speed_6_is_5_5_degrees():
    assert math.degrees(R.turn_rate(6.0)) == pytest.approx(5.5)
    assert math.degrees(R.turn_rate(0.0)) == pytest.approx(10.0)
    assert math.degrees(R.turn_rate(-8.0)) == pytest.approx(4.0)


def test_bullet_numbers():
    assert R.bullet_speed(3.0) == 11.0
    assert R.bullet_speed(0.1) == pytest.approx(19.7)
    assert R.bullet_damage(3.0) == 16.0
    assert R.bullet_damage(1.0) == 4.0
    assert R.bullet_damage(0.5) == 2.0
    assert R.bullet_hit_bonus(2.0) == 6.0
    assert R.gun_heat(3.0) == pytest.approx(1.6)
    assert R.clamp_power(5.0, 100.0) == 3.0
    assert R.clamp_power(0.01, 100.0) == 0.1
    assert R.clamp_power(3.0, 1.5) == 1.5


def test_wall_damage():
    assert R.wall_hit_damage(8.0) == 3.0
    assert R.wall_hit_damage(2.0) == 0.0
    assert R.wall_hit_damage(-6.0) == 2.0


def test_angle_normalisation():
    assert R.normal_absolute_angle(-0.5) == pytest.approx(2 * math.pi - 0.5)
    assert R.normal_relative_angle(math.pi) == pytest.approx(-math.pi)
    assert R.normal_relative_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert R.normal_near_absolute_angle(math.pi / 2 + 1e-7) == math.pi / 2
    assert R.normal_near_absolute_angle(2 * math.pi - 1e-7) == 0.0
    assert R.normal_near_absolute_angle(1.0) == 1.0


def test_segments_intersect_and_parallel():
    assert R.segments_intersect(0, 0, 10, 10, 0, 10, 10, 0)
    assert not R.segments_intersect(0, 0, 10, 10, 20, 0, 30, 10)
    # the same line head-on: parallel, never a hit (as the engine)
    assert not R.segments_intersect(0, 0, 0, 10, 0, 12, 0, 5)


def test_segment_vs_box():
    assert R.segment_intersects_box(0, 100, 200, 100, 100, 100)  # through the middle
    assert R.segment_intersects_box(82, 50, 82, 150, 100, 100)  # along the left edge (closed box)
    assert not R.segment_intersects_box(81.9, 50, 81.9, 150, 100, 100)
    assert R.segment_intersects_box(95, 95, 96, 96, 100, 100)  # fully inside


def test_boxes_strict_overlap():
    assert R.boxes_intersect(100, 100, 135.9, 100)
    assert not R.boxes_intersect(100, 100, 136, 100)  # touching boxes do not overlap


def test_radar_sweep():
    # robot at the origin-ish, target straight north at 500
    assert R.sweep_hits_box(400, 100, -0.1, 0.2, 400, 600)
    assert not R.sweep_hits_box(400, 100, 0.2, 0.5, 400, 600)
    # anticlockwise sweep across north
    assert R.sweep_hits_box(400, 100, 0.1, -0.2, 400, 600)
    # zero sweep: only the line counts
    assert R.sweep_hits_box(400, 100, 0.0, 0.0, 400, 600)
    assert not R.sweep_hits_box(400, 100, 0.2, 0.0, 400, 600)
    # beyond 1200
    assert not R.sweep_hits_box(0, 0, 0.7, 0.2, 1000, 1000)
    assert R.sweep_hits_box(0, 0, 0.7, 0.2, 800, 800)


def test_java_random_matches_java():
    s = R.java_seed(42)
    s, d = R.java_next_double(s)
    assert d == 0.7275636800328681  # new Random(42).nextDouble()
    s = R.java_seed(42)
    s, i = R.java_next(s, 32)
    assert i == -1170105035  # new Random(42).nextInt()
    s = R.java_seed(42)
    s, k = R.java_next_int(s, 10)
    assert k == 0  # new Random(42).nextInt(10)


def _state_before(u31: int, low17: int = 12345) -> int:
    """A generator state whose next next(31) returns u31 (inverting the LCG)."""
    mult, mask = 0x5DEECE66D, (1 << 48) - 1
    after = (u31 << 17) | low17
    return ((after - 0xB) * pow(mult, -1, 1 << 48)) & mask


def _java_next_int_reference(state: int, bound: int) -> tuple[int, int]:
    """java.util.Random.nextInt(bound) in plain Python, with Java's 32-bit overflow."""
    def nxt(s):
        s = (s * 0x5DEECE66D + 0xB) & ((1 << 48) - 1)
        return s, s >> 17
    state, r = nxt(state)
    m = bound - 1
    if bound & m == 0:
        return state, (bound * r) >> 31
    u = r
    while True:
        r = u % bound
        v = (u - r + m) & 0xFFFFFFFF
        if v < (1 << 31):  # not negative as a Java int
            return state, r
        state, u = nxt(state)


def test_next_int_rejection_and_skip_match_java():
    from confront.arena._kernels import shuffle_into, skip_shuffle

    perm = np.zeros(16, dtype=np.int32)
    for u in ((1 << 31) - 1, (1 << 31) - 3, (1 << 31) - 8, 5, 1 << 30):
        s = _state_before(u)
        for bound in (3, 5, 6, 7, 8, 12):
            assert R.java_next_int(s, bound) == _java_next_int_reference(s, bound)
        for n in (2, 3, 7, 12):
            assert skip_shuffle(s, n, 0) == shuffle_into(s, perm, n, 0)
    # (2^31 - 1) with bound 7 is rejected by Java: one extra draw is consumed
    s = _state_before((1 << 31) - 1)
    assert R.java_next_int(s, 7)[0] != R.java_next(s, 31)[0]
