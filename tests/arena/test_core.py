"""Turn-level behaviour of the Arena against hand-computed Robocode numbers."""

import math

import numpy as np
import pytest

from confront.arena import kernels as K
from confront.arena.core import Arena
from confront.arena.rules import segments_intersect
from confront.arena.scenarios import get_scenario


def duel(positions, advanced=True, **kw):
    sc = get_scenario("1v1").replace(initial_positions=tuple(positions), advanced=advanced, **kw)
    return Arena(sc, 1, seed=0, order="fixed")


def cmd(arena, **cols):
    c = arena.idle_commands()
    names = {"move": 0, "body": 1, "gun": 2, "radar": 3, "fire": 4}
    for k, v in cols.items():
        c[0, :, names[k]] = v
    return c


def test_start_state():
    a = duel([(100, 300, 90), (400, 300, 270)])
    s = a.state
    assert s.x[0].tolist() == [100, 400]
    assert s.heading[0, 0] == pytest.approx(math.pi / 2)
    assert s.gun_heat[0].tolist() == [3.0, 3.0]
    assert s.energy[0].tolist() == [100.0, 100.0]
    assert s.time[0] == 0


def test_first_bullet_in_turn_31_and_travels_in_its_first_turn():
    a = duel([(200, 300, 90), (600, 500, 0)])
    c = cmd(a, fire=np.array([3.0, 0.0]))
    fired_at = None
    for _ in range(35):
        a.step(c)
        if a.state.ev_fired[0, 0] and fired_at is None:
            fired_at = int(a.state.time[0])
            slot = a.state.b_list[0, 0]
            assert a.state.b_x[0, slot] == pytest.approx(211.0)  # power 3 from x=200 is at 211
            assert a.state.energy[0, 0] == pytest.approx(97.0)
    assert fired_at == 31


def test_east_wall_at_speed_8():
    a = duel([(700, 300, 90), (100, 100, 0)])
    c = cmd(a, move=np.array([1000.0, 0.0]))
    for _ in range(30):
        a.step(c)
        if a.state.ev_hit_wall[0, 0]:
            break
    assert a.state.ev_hit_wall[0, 0]
    assert a.state.x[0, 0] == 782.0
    assert a.state.energy[0, 0] == pytest.approx(97.0)
    assert a.state.velocity[0, 0] == 0.0


def test_plain_robot_takes_no_wall_damage():
    a = duel([(700, 300, 90), (100, 100, 0)], advanced=False)
    c = cmd(a, move=np.array([1000.0, 0.0]))
    for _ in range(30):
        a.step(c)
    assert a.state.x[0, 0] == 782.0
    assert a.state.energy[0, 0] == 100.0


def test_turning_at_speed_6():
    a = duel([(400, 300, 0), (100, 100, 0)])
    a.step(cmd(a, move=np.array([1000.0, 0.0])))
    for _ in range(5):  # speeds 1..6
        a.step(a.idle_commands())
    assert a.state.velocity[0, 0] == 6.0
    h0 = a.state.heading[0, 0]
    a.step(cmd(a, body=np.array([1.0, 0.0])))
    assert math.degrees(a.state.heading[0, 0] - h0) == pytest.approx(5.5)


def test_gun_turns_with_body_unless_adjusted():
    a = duel([(400, 300, 0), (100, 100, 0)])
    a.step(cmd(a, body=np.array([math.radians(10), 0.0])))
    assert math.degrees(a.state.gun_heading[0, 0]) == pytest.approx(10.0)
    assert math.degrees(a.state.radar_heading[0, 0]) == pytest.approx(10.0)
    a.state.adjust_gun_for_body[0, 0] = True
    a.step(cmd(a, body=np.array([math.radians(10), 0.0]), gun=np.array([0.0, 0.0])))
    # the gun turned 10 with the body and -10 from the adjustment: net 0 (remaining corrected)
    assert math.degrees(a.state.heading[0, 0]) == pytest.approx(20.0)
    assert math.degrees(a.state.gun_heading[0, 0]) == pytest.approx(10.0, abs=1e-9) or \
        a.state.gun_turn_remaining[0, 0] == pytest.approx(math.radians(-10))


def test_gun_and_radar_rates():
    a = duel([(400, 300, 0), (100, 100, 0)])
    a.step(cmd(a, gun=np.array([1.0, 0.0]), radar=np.array([2.0, 0.0])))
    assert math.degrees(a.state.gun_heading[0, 0]) == pytest.approx(20.0)
    assert math.degrees(a.state.radar_heading[0, 0]) == pytest.approx(65.0)  # 20 with the gun + 45
    assert a.state.gun_turn_remaining[0, 0] == pytest.approx(1.0 - math.radians(20))


def test_bullet_hit_damage_and_energy_return():
    a = duel([(100, 300, 90), (400, 300, 0)])
    c = cmd(a, fire=np.array([3.0, 0.0]))
    hit_at = None
    for _ in range(60):
        a.step(c)
        c[0, 0, 4] = 0.0 if a.state.time[0] >= 31 else 3.0
        if a.state.ev_hit_by_bullet[0, 1]:
            hit_at = int(a.state.time[0])
            break
    # fired in turn 31 at x=100, 11 px per turn, the box's left edge at 382: 26 moves -> turn 56
    assert hit_at == 56
    assert a.state.energy[0, 1] == pytest.approx(84.0)
    assert a.state.energy[0, 0] == pytest.approx(100.0 - 3.0 + 9.0)
    assert a.state.score[0, 0, 2] == pytest.approx(16.0)
    assert a.state.ev_bullet_hit[0, 0] == 1


def test_kill_scores_like_robocode():
    a = duel([(100, 300, 90), (400, 300, 0)])
    c = cmd(a, fire=np.array([3.0, 0.0]))
    for _ in range(400):
        a.step(c)
        if a.state.done[0]:
            break
    s = a.state
    assert s.done[0] and not s.alive[0, 1]
    # 6 hits of 16 then a capped 4: bullet damage 100, kill bonus 20, survival 50, last survivor 10
    assert s.score_total[0, 0].tolist() == pytest.approx([50.0, 10.0, 100.0, 20.0, 0.0, 0.0])
    assert s.score_total[0, 1].tolist() == pytest.approx([0.0] * 6)
    assert s.placements_total[0, 0].tolist() == [1, 0, 0]
    assert s.placements_total[0, 1].tolist() == [0, 1, 0]


def test_head_on_ram_costs_both():
    a = duel([(300, 300, 90), (399, 300, 270)])  # boxes first overlap in turn 8 for both
    c = cmd(a, move=np.array([100.0, 100.0]))
    for _ in range(40):
        a.step(c)
        c = a.idle_commands()
        if a.state.ev_hit_robot[0, 0] >= 0:
            break
    s = a.state
    assert s.ev_at_fault[0].tolist() == [True, True]
    assert s.energy[0].tolist() == pytest.approx([98.8, 98.8])
    assert s.score[0, :, 4].tolist() == pytest.approx([1.2, 1.2])
    assert s.damage_ledger[0, 0, 1] == pytest.approx(0.6)
    assert s.velocity[0].tolist() == [0.0, 0.0]


def test_disabled_robot_cannot_move():
    a = duel([(300, 300, 90), (600, 300, 270)])
    a.state.energy[0, 0] = 0.0
    a.step(cmd(a, move=np.array([100.0, 0.0])))
    assert a.state.x[0, 0] == 300.0
    assert a.state.alive[0, 0]


def test_radar_scan_event():
    a = duel([(100, 300, 0), (400, 300, 0)])
    a.step(cmd(a, radar=np.array([math.radians(45), 0.0])))
    assert not a.state.scanned[0, 0, 1]
    a.step(cmd(a, radar=np.array([math.radians(45), 0.0])))
    assert a.state.scanned[0, 0, 1]  # 45..90 deg sweeps east
    assert a.state.scan_time[0, 0, 1] == 2


def test_inactivity_drain():
    sc = get_scenario("1v1").replace(initial_positions=((100, 300, 0), (400, 300, 0)), inactivity_time=5)
    a = Arena(sc, 1, order="fixed")
    for _ in range(8):
        a.step(a.idle_commands())
    # counter exceeds 5 from turn 7 on: two drains of 0.1
    assert a.state.energy[0].tolist() == pytest.approx([99.8, 99.8])


def test_state_dict_round_trip_continues_identically():
    a = Arena("4v4", 4, seed=7)
    rng = np.random.default_rng(0)
    cmds = [np.where(rng.random((4, 8, 5)) < 0.3, np.nan, rng.normal(0, 50, (4, 8, 5))) for _ in range(200)]
    for c in cmds:
        c[..., 4] = np.abs(np.nan_to_num(c[..., 4])) % 3
    for c in cmds[:60]:
        a.step(c)
    saved = a.state_dict()
    ref = []
    for c in cmds[60:]:
        a.step(c)
        ref.append((a.state.x.copy(), a.state.energy.copy(), a.state.rng.copy()))
    b = Arena("4v4", 4, seed=99)
    b.load_state_dict(saved)
    for c, (x, e, r) in zip(cmds[60:], ref, strict=True):
        b.step(c)
        np.testing.assert_array_equal(b.state.x, x)
        np.testing.assert_array_equal(b.state.energy, e)
        np.testing.assert_array_equal(b.state.rng, r)


def test_state_dict_saved_before_the_bullet_heading_field_loads():
    """A dict without ``ev_hit_by_bullet_heading`` (saved before it existed) gets bearing + heading - pi."""
    a = Arena("1v1", 2, seed=3)
    for _ in range(5):
        a.step(a.idle_commands())
    a.state.ev_hit_by_bullet_bearing[...] = 0.5
    saved = a.state_dict()
    del saved["ev_hit_by_bullet_heading"]
    b = Arena("1v1", 2, seed=4)
    b.load_state_dict(saved)
    np.testing.assert_array_equal(b.state.x, a.state.x)
    np.testing.assert_array_equal(b.state.ev_hit_by_bullet_heading, 0.5 + a.state.heading - math.pi)


def test_state_dict_saved_before_the_per_bullet_rows_loads():
    """A dict without ``ev_hit_by_bullets`` (saved before the per-bullet rows) gets one row: the last bullet's."""
    a = Arena("1v1", 2, seed=3)
    for _ in range(5):
        a.step(a.idle_commands())
    a.state.ev_hit_by_bullet[...] = 2
    a.state.ev_hit_by_bullet_bearing[...] = 0.5
    a.state.ev_hit_by_bullet_heading[...] = 1.5
    saved = a.state_dict()
    for name in [n for n in saved if n.startswith("ev_hit_by_bullet_") and n[17].isdigit()] + ["ev_hit_by_bullets"]:
        del saved[name]
    b = Arena("1v1", 2, seed=4)
    b.load_state_dict(saved)
    np.testing.assert_array_equal(b.state.ev_hit_by_bullets, 1.0)
    np.testing.assert_array_equal(b.state.ev_hit_by_bullet_0_bearing, 0.5)
    np.testing.assert_array_equal(b.state.ev_hit_by_bullet_0_heading, 1.5)
    np.testing.assert_array_equal(b.state.ev_hit_by_bullet_1_heading, 0.0)


def test_reset_mask_only_touches_masked_battles():
    a = Arena("1v1", 3, seed=1)
    for _ in range(5):
        a.step(a.idle_commands())
    before = a.state.time.copy()
    a.reset(np.array([False, True, False]))
    assert a.state.time.tolist() == [before[0], 0, before[2]]
    with pytest.raises(ValueError, match="mask"):
        a.reset(np.array([True]))


def test_bad_commands_shape():
    a = Arena("1v1", 2)
    with pytest.raises(ValueError, match="shape"):
        a.step(np.zeros((2, 2, 4)))


def test_random_start_positions_follow_java_random():
    a = Arena("1v1", 1, seed=42)
    # first robot: x = 36 + nextDouble * (800 - 72) with new Random(42)
    assert a.state.x[0, 0] == pytest.approx(36 + 0.7275636800328681 * 728)
    assert (a.state.x >= 36).all() and (a.state.x <= 764).all()


def test_builtin_scenarios():
    from confront.arena.scenarios import scenario_names

    assert {"1v1", "4v4", "4v6", "4v10", "melee"} <= set(scenario_names())
    sc = get_scenario("4v10")
    assert sc.teams == (4, 10) and sc.n_robots == 14 and sc.width == 800 and sc.height == 600
    assert sc.team_ids()[:5] == [0, 0, 0, 0, 1]
    with pytest.raises(ValueError, match="unknown scenario"):
        get_scenario("9v9")


def test_user_scenario_from_toml(tmp_path):
    from confront.arena.scenarios import load_scenario

    p = tmp_path / "duel.toml"
    p.write_text('name = "wide"\nteams = [2, 3]\nwidth = 1000\nheight = 1000\nopponents = "Walls"\n')
    sc = load_scenario(p)
    assert (sc.name, sc.teams, sc.width, sc.opponents) == ("wide", (2, 3), 1000.0, "Walls")
    a = Arena(sc, 2, seed=3)
    assert a.state.is_leader[0].tolist() == [True, False, True, False, False]
    assert a.state.energy[0].tolist() == [200.0, 100.0, 200.0, 100.0, 100.0]
    p.write_text('name = "bad"\nteams = [1, 1]\nwidht = 900\n')
    with pytest.raises(ValueError, match="widht"):
        load_scenario(p)
    p.write_text('name = "bad"\nteams = [1, 1]\ngun_cooling_rate = 2.0\n')
    with pytest.raises(ValueError, match="gun_cooling_rate"):
        load_scenario(p)


def test_team_fire_damages_but_scores_nothing():
    sc = get_scenario("4v4").replace(teams=(2, 1), initial_positions=((100, 300, 90), (300, 300, 0),
                                                                      (700, 500, 0)))
    a = Arena(sc, 1, order="fixed")
    cmd = a.idle_commands()
    cmd[0, 0, 4] = 3.0
    for _ in range(60):
        a.step(cmd)
        cmd[0, 0, 4] = 0.0 if a.state.ev_fired[0, 0] else cmd[0, 0, 4]
    # the team-mate at x=300 took 16 (leader has 200), the shooter got 9 back, no score
    assert a.state.energy[0, 1] == pytest.approx(84.0)
    assert a.state.energy[0, 0] == pytest.approx(200.0 - 3.0 + 9.0)
    assert a.state.score[0, 0].sum() == 0.0


def test_bullet_of_power_below_0_1_flies_at_the_speed_of_0_1():
    """A robot with 0.05 energy fires a bullet of power 0.05 that flies at 19.7 px a turn (Rules.getBulletSpeed)."""
    a = duel([(200, 300, 90), (600, 500, 0)])
    a.state.energy[0, 0] = 0.05
    a.state.gun_heat[0, 0] = 0.0
    a.step(cmd(a, fire=np.array([3.0, 0.0])))
    slot = a.state.b_list[0, 0]
    assert a.state.b_power[0, slot] == 0.05
    step = 20.0 - 3.0 * 0.1
    assert a.state.b_x[0, slot] == 200.0 + step  # heading east: one step in its firing turn
    a.step(cmd(a))
    assert a.state.b_x[0, slot] == 200.0 + step + step


def _bullet(a, k, owner, x, y, last_x, last_y, heading, power, state, has_line):
    """Put a bullet in list entry k (slot k) of battle 0."""
    s = a.state
    sp = 20.0 - 3.0 * power
    s.b_x[0, k], s.b_y[0, k], s.b_last_x[0, k], s.b_last_y[0, k] = x, y, last_x, last_y
    s.b_heading[0, k], s.b_power[0, k] = heading, power
    s.b_vx[0, k], s.b_vy[0, k] = sp * math.sin(heading), sp * math.cos(heading)
    s.b_owner[0, k], s.b_victim[0, k], s.b_state[0, k], s.b_frame[0, k] = owner, -1, state, 0
    s.b_has_line[0, k] = has_line
    s.b_list[0, k] = k


def test_nearly_collinear_bullets_63_px_apart_meet_as_in_the_engine():
    """StopGoCircular vs Fire (seed 3, round 64, turn 51): Fire fires back along the line of the other's bullet.
    Its new bullet moves first and tests the other's last move, which starts 63 px from its own: the lines are
    parallel to 4e-16 rad and BulletPeer.intersect's quotients are exactly 0 (both numerators are 0 in floating
    point), so the engine says they meet, and both bullets end as HIT_BULLET."""
    a = duel([(100, 500, 0), (700, 500, 0)])  # the robots far from the bullets
    a.state.gun_heat[0] = 3.0
    fire = (495.92860138609933, 82.25198635726409)  # Fire's bullet, fired this turn: no line yet
    _bullet(a, 0, 1, *fire, *fire, 5.4301759945002095, 1.0, K.B_FIRED, 0)
    _bullet(a, 1, 0, 443.17091859148417, 128.3178929550715, 432.77665385043076, 137.39375078943266,
            2.288583340910416, 2.0670056291958816, K.B_MOVING, 1)
    a.state.n_bullets[0] = 2
    nx, ny = fire[0] + a.state.b_vx[0, 0], fire[1] + a.state.b_vy[0, 0]
    # the hand-computed test the engine makes: Fire's move against the other bullet's last move
    assert segments_intersect(fire[0], fire[1], nx, ny, 432.77665385043076, 137.39375078943266,
                              443.17091859148417, 128.3178929550715)
    assert abs(432.77665385043076 - fire[0]) > 60  # beyond the distances a near-pair filter would look at
    a.step(cmd(a))  # order "fixed": the bullets move in list order, Fire's first
    assert a.state.b_state[0, 0] == K.B_HIT_BULLET and a.state.b_state[0, 1] == K.B_HIT_BULLET
    assert (a.state.b_x[0, 0], a.state.b_y[0, 0]) == fire  # both put back at their last points
    assert (a.state.b_x[0, 1], a.state.b_y[0, 1]) == (432.77665385043076, 137.39375078943266)
