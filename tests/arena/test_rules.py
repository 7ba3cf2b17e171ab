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
    # Rules.getBulletSpeed clamps the power to [0.1, 3]: a bullet fired with 0.05 energy left flies at 19.7
    assert R.bullet_speed(0.05) == R.bullet_speed(0.1) == 20.0 - 3.0 * 0.1
    assert R.bullet_speed(0.0) == R.bullet_speed(0.1)
    assert R.bullet_speed(5.0) == 11.0
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


def _pie_meets_box(x: float, y: float, start: float, extent: float, cx: float, cy: float, half: float) -> bool:
    """Geometric reference for the radar pie (radius 1200, headings clockwise from north) against the square of
    half-side ``half`` centred on (cx, cy), by dense sampling: a box edge point in the pie, or a point of the
    pie's boundary (its two radii and its arc, or the start line alone for a zero sweep) in the box."""
    r = R.RADAR_SCAN_RADIUS
    t = np.linspace(0.0, 1.0, 801)
    s = 2 * half * t - half
    ex = np.concatenate([cx + s, cx + s, np.full_like(s, cx - half), np.full_like(s, cx + half)]) - x
    ey = np.concatenate([np.full_like(s, cy - half), np.full_like(s, cy + half), cy + s, cy + s]) - y
    lo, hi = (start, start + extent) if extent >= 0 else (start + extent, start)
    ang = np.arctan2(ex, ey)  # heading of each edge point
    off = np.mod(ang - lo, 2 * np.pi)
    inside = (ex * ex + ey * ey <= r * r) & (off <= hi - lo)
    if extent != 0.0 and inside.any():
        return True
    lines = [start] if extent == 0.0 else [start, start + extent]
    pts = [(x + r * t * math.sin(a), y + r * t * math.cos(a)) for a in lines]
    if extent != 0.0:
        arc = lo + (hi - lo) * t
        pts.append((x + r * np.sin(arc), y + r * np.cos(arc)))
    return any(bool(np.any((np.abs(px - cx) <= half) & (np.abs(py - cy) <= half))) for px, py in pts)


def test_radar_sweep_against_a_sampled_reference():
    # random robots, sweeps of both signs up to pi, narrow and zero sweeps; cases within half a pixel of the boundary
    # (the sampled reference answers differently for a box 0.5 px smaller and larger) are left out
    rng = np.random.default_rng(7)
    checked = hits = 0
    for _ in range(1500):
        x, y = rng.uniform(0, 800, 2)
        cx, cy = rng.uniform(0, 800, 2)
        start = rng.uniform(-2 * np.pi, 2 * np.pi)
        kind = rng.random()  # a zero sweep, a narrow one (a box far off can be wider than it), or any
        extent = 0.0 if kind < 0.15 else rng.uniform(-0.05, 0.05) if kind < 0.5 else rng.uniform(-np.pi, np.pi)
        small = _pie_meets_box(x, y, start, extent, cx, cy, R.ROBOT_HALF - 0.5)
        large = _pie_meets_box(x, y, start, extent, cx, cy, R.ROBOT_HALF + 0.5)
        if small != large:
            continue
        assert R.sweep_hits_box(x, y, start, extent, cx, cy) == small, (x, y, start, extent, cx, cy)
        checked += 1
        hits += small
    assert checked > 1400 and 100 < hits < checked - 100


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
    from confront.arena.kernels import shuffle_into, skip_shuffle

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


def test_shuffle_and_skips_match_collections_shuffle():
    """shuffle_into and the jump-ahead skip equal Collections.shuffle step by step, also when a draw is rejected."""
    from confront.arena.kernels import shuffle_into, skip_shuffle

    mult, mask = 0x5DEECE66D, (1 << 48) - 1
    back = pow(mult, -1, 1 << 48)

    def shuffle_reference(state: int, n: int) -> tuple[int, list[int]]:
        perm = list(range(n))
        for i in range(n, 1, -1):
            state, j = _java_next_int_reference(state, i)
            perm[i - 1], perm[j] = perm[j], perm[i - 1]
        return state, perm

    rng = np.random.default_rng(3)
    states = [int(v) for v in rng.integers(0, 1 << 48, 300)]
    for k in range(6):  # the (k+1)-th draw of a shuffle of 7 is nextInt(7 - k): 2^31 - 1 is rejected (not 6 - k = 4)
        s = _state_before((1 << 31) - 1)
        for _ in range(k):
            s = ((s - 0xB) * back) & mask
        states.append(s)
    perm = np.zeros(40, dtype=np.int32)
    rejected = 0
    for s in states:
        for n in (1, 2, 3, 7, 8, 13, 40):
            want_state, want_perm = shuffle_reference(s, n)
            assert shuffle_into(s, perm, n, 0) == want_state
            assert perm[:n].tolist() == want_perm
            assert skip_shuffle(s, n, 0) == want_state
            rejected += want_state != ((s * pow(mult, max(n - 1, 0), 1 << 48)
                                        + sum(0xB * pow(mult, e, 1 << 48) for e in range(max(n - 1, 0)))) & mask)
    assert rejected >= 6  # the constructed states do exercise the rejection path
    assert shuffle_into(states[0], perm, 7, 2) == states[0] and perm[:7].tolist() == list(range(7))


# Math.atan2 / Math.hypot as OpenJDK 17 computes them (fdlibm), for offsets where the C library's result is an
# ulp away; the first two atan2 rows are from the engine traces (TrackFire to RamFire, seed 1 turn 78; RamFire's
# collision with TrackFire, seed 2 turn 93), the rest from random offsets within 800 px
JAVA_ATAN2 = [
    (422.66443889049833, -31.950009461253217, 1.6462447410837993),
    (33.48562936708959, -5.91444090840173, 1.7456194755280456),
    (-749.7308178774707, -227.32812883659417, -1.8651982127823132),
    (585.0988741237636, -21.45494107808954, 1.6074488202547184),
    (580.5186540764188, 315.349302340128, 1.073173442709703),
    (27.680433662553483, 337.86816520536826, 0.08174416671189727),
    (526.0963120559334, 513.4216169920269, 0.7975904177760161),
    (311.29595908178516, -402.5047485745413, 2.4832848558742073),
    (-576.6033238626322, 41.72474983267627, -1.4985592326786565),
    (523.7556448269696, -25.85987660699054, 1.6201301982964447),
]
JAVA_HYPOT = [
    (204.69324066155625, -58.56116635464783, 212.90545548986412),
    (-109.90471178326224, -268.2811545844023, 289.9203745467053),
    (141.61381903086382, 632.2276565710965, 647.8937285341528),
    (-6.768960516071054, -518.6188768292512, 518.6630488381663),
    (-382.971186225844, 18.176971923704777, 383.40231061842235),
    (311.529070464009, -572.1507821782436, 651.4651788786148),
    (-144.54686399665616, 613.0514457683528, 629.8617872596618),
    (311.29595908178516, -402.5047485745413, 508.837151518738),
]


@pytest.mark.parametrize("y, x, java", JAVA_ATAN2)
def test_atan2_is_javas_bit_for_bit(y, x, java):
    assert R.java_atan2(y, x) == java


@pytest.mark.parametrize("x, y, java", JAVA_HYPOT)
def test_hypot_is_javas_bit_for_bit(x, y, java):
    assert R.java_hypot(x, y) == java


@pytest.mark.parametrize("a", [1.0, 0.75, 651.4651788786148, 1e300, 2.2250738585072014e-308, 2.225e-308, 5e-324,
                               1.2345e-310, 3.0 * 2.0 ** -1060])
def test_high_words_are_the_ieee_upper_32_bits(a):
    bits = int(np.array(a).view(np.int64))
    hw = R._high_word(a)
    assert hw == bits >> 32
    assert np.array(R._from_high_word(hw)).view(np.int64) == (bits >> 32) << 32  # lower word cleared


def test_atan2_and_hypot_special_values_as_java():
    pi = math.pi
    assert R.java_atan2(0.0, -1.0) == pi and R.java_atan2(-0.0, -1.0) == -pi
    assert R.java_atan2(0.0, 1.0) == 0.0 and R.java_atan2(1.0, 0.0) == pi / 2 and R.java_atan2(-1.0, 0.0) == -pi / 2
    assert R.java_atan2(math.inf, -math.inf) == 0.75 * pi and R.java_atan2(-1.0, math.inf) == 0.0
    assert math.isnan(R.java_atan2(math.nan, 1.0)) and math.isnan(R.java_hypot(math.nan, 1.0))
    assert R.java_hypot(math.inf, math.nan) == math.inf
    assert R.java_hypot(3.0, 4.0) == 5.0 and R.java_hypot(0.0, -2.5) == 2.5
    assert R.java_hypot(1e300, 1e300) == math.hypot(1e300, 1e300)  # scaled down (both agree here)
