"""Seeded runs give the recorded results, and the fused runner equals the step loop."""

import numpy as np
import pytest

from confront.arena.bots import ScriptedBots, bot_battle
from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario

OURS4 = ["SpinBot", "Walls", "Tracker", "RamFire"]
THEM4 = ["Walls", "Tracker", "Crazy", "Fire"]

# bot_battle(names, rounds=6, seed, n_battles=3, scenario): (score parts (R, 6), placements (R, 3)), recorded
# with the simulator. melee4 and 4v4 re-recorded for issue 11 (rules that were wrong before, each shown by an
# engine trace in tests/fixtures/traces/samples, tests/arena/test_bots_engine.py): one HitRobotEvent per
# collision, disabled robots run on, a dying robot's last wake and the interruptible flag kept across rounds,
# stop()/resume() at a round start, degree arithmetic, onWin; re-recorded again for Java's atan2 / hypot
# (fdlibm, rules.java_atan2: scan and collision bearings, scan distances). 4v4 re-recorded again (2026-12-03) for
# the HitByBulletEvent's heading, now the bullet's own (Fire's onHitByBullet turn; engine trace
# sample_fire_hitby_heading); melee4 has no Fire, fire_corners is unchanged. (Before: the event queue of
# commit 69360a4; before that commit 34b3372 used the newest event only.)
RECORDED = {
    "melee4": (OURS4, None, 3,
               [[600.0, 0.0, 521.0000000000003, 24.56000000000007, 16.8, 0.0],
                [900.0, 180.0, 448.79999999999944, 66.11999999999989, 8.399999999999999, 0.0],
                [250.0, 0.0, 785.0000000000014, 69.00000000000001, 9.6, 0.0],
                [50.0, 0.0, 435.6, 10.800000000000004, 88.79999999999997, 0.0]],
               [[0, 6, 0], [6, 0, 0], [0, 0, 5], [0, 0, 1]]),
    "fire_corners": (["Fire", "Corners"], None, 5,
                     [[300.0, 60.0, 623.0, 124.60000000000001, 0.0, 0.0], [0.0, 0.0, 392.0, 0.0, 0.0, 0.0]],
                     [[6, 0, 0], [0, 6, 0]]),
    "4v4": (OURS4 + THEM4, "4v4", 11,
            [[850.0, 0.0, 291.0, 35.52, 22.799999999999997, 0.0],
             [700.0, 0.0, 277.19999999999993, 94.64000000000004, 6.0, 0.0],
             [600.0, 0.0, 703.6000000000001, 85.96000000000001, 14.399999999999999, 0.0],
             [450.0, 0.0, 177.20000000000022, 0.0, 43.19999999999999, 13.320000000000002],
             [1200.0, 240.0, 710.8000000000002, 124.24000000000004, 2.4, 0.0],
             [300.0, 0.0, 431.60000000000025, 65.96000000000005, 6.0, 31.139999999999997],
             [500.0, 40.0, 144.40000000000015, 10.4, 29.999999999999993, 0.0],
             [200.0, 0.0, 256.0, 0.0, 2.4, 0.0]],
            [[0, 2, 0], [0, 4, 0], [0, 0, 0], [0, 0, 0], [6, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]]),
}


@pytest.mark.parametrize("key", sorted(RECORDED))
def test_bot_battle_results_are_unchanged(key):
    names, scenario, seed, parts, placements = RECORDED[key]
    sc = get_scenario(scenario) if scenario else None
    got_parts, got_pl = bot_battle(names, rounds=6, seed=seed, n_battles=3, scenario=sc)
    np.testing.assert_array_equal(got_pl, np.array(placements))
    np.testing.assert_allclose(got_parts, np.array(parts), rtol=0, atol=1e-9)


def _loop(arena: Arena, bots: ScriptedBots, turns: int) -> int:
    """The Python loop that ScriptedBots.play replaces."""
    cmd = arena.idle_commands()
    alive = 0
    for _ in range(turns):
        arena.step(bots.commands(cmd))
        alive += int(arena.state.alive.sum())
        done = arena.state.done
        if done.any():
            arena.reset(done)
    return alive


@pytest.mark.parametrize("scenario,names,threads", [
    ("4v4", OURS4 + THEM4, 1),
    ("4v4", OURS4 + THEM4, 2),
    ("melee", ["Fire", "Corners", "Crazy", "Walls"], 2),
])
def test_play_equals_the_step_loop(scenario, names, threads):
    a = Arena(scenario, 6, seed=6, threads=threads)  # a seed whose 4v4 rounds end within the 1500 turns
    b = Arena(scenario, 6, seed=6, threads=threads)
    bots_a, bots_b = ScriptedBots(a, names), ScriptedBots(b, names)
    ref = _loop(a, bots_a, 1500)
    got = sum(bots_b.play(t) for t in (1, 499, 1000))
    assert got == ref
    assert a.state.round.sum() > 6  # rounds ended and restarted inside the run
    sa, sb = a.state_dict(), b.state_dict()
    for name in sa:
        np.testing.assert_array_equal(sb[name], sa[name], err_msg=name)
    np.testing.assert_array_equal(bots_b.mem, bots_a.mem)


def test_play_keeps_commands_of_robots_without_a_bot():
    sc = get_scenario("melee").replace(teams=(1, 1), initial_positions=((100, 100, 0), (600, 400, 0)))
    a = Arena(sc, 1, seed=0, order="fixed")
    bots = ScriptedBots(a, [None, "SittingDuck"])
    cmd = a.idle_commands()
    cmd[0, 0, 0] = 50.0  # robot 0 is told "50 px ahead" (north) again every turn: it never brakes
    assert bots.play(20, cmd) == 40
    assert a.state.y[0, 0] == 100.0 + (1 + 2 + 3 + 4 + 5 + 6 + 7 + 8) + 12 * 8.0
    assert a.state.x[0, 0] == 100.0


def test_play_rejects_bad_arguments():
    a = Arena("1v1", 2, seed=0)
    bots = ScriptedBots(a, ["SpinBot", "Walls"])
    with pytest.raises(ValueError, match="turns"):
        bots.play(-1)
    with pytest.raises(ValueError, match="cmd"):
        bots.play(3, np.zeros((2, 2, 4)))


# tech_battle(names, rounds=6, seed, n_battles=3, scenario): the technique robots' twins (confront.arena.tech, engine
# traces in tests/fixtures/traces/tech) with sample robots, in a melee and as teams of four; recorded with the
# simulator (2026-12-05)
TECH_RECORDED = {
    "surfvg_spinbot": (["SurfVG", "SpinBot"], None, 4,
                       [[300.0, 60.0, 563.4, 113.28000000000002, 6.0, 0.0], [0.0, 0.0, 32.0, 0.0, 1.2, 0.0]],
                       [[6, 0, 0], [0, 6, 0]]),
    "tech_melee": (["RiskGF", "OrbitGF", "SurfGF", "StopGoCircular"], None, 5,
                   [[550.0, 90.0, 357.81025140176934, 34.44464365930324, 0.0, 0.0],
                    [500.0, 60.0, 276.8185511274886, 21.276318453026768, 0.0, 0.0],
                    [300.0, 0.0, 284.2753833820735, 20.835342824155312, 0.0, 0.0],
                    [450.0, 30.0, 267.15955079930256, 15.616856458254556, 0.0, 0.0]],
                   [[3, 0, 2], [2, 1, 2], [0, 3, 0], [1, 2, 2]]),
    "tech_4v4": (["RiskGF"] * 4 + ["OrbitVG"] * 4, "4v4", 6,
                 [[1200.0, 240.0, 375.9017711126679, 81.53373713044213, 4.8, 0.0],
                  [1000.0, 160.0, 416.40060208193745, 57.27861052290908, 8.4, 0.0],
                  [750.0, 120.0, 496.4586442709343, 78.66957246807648, 61.200000000000045, 0.0],
                  [1100.0, 200.0, 379.95436242581457, 92.11969440867226, 0.0, 0.0],
                  [300.0, 0.0, 339.6886155720895, 18.080000000000002, 54.00000000000004, 0.0],
                  [100.0, 0.0, 98.97783787743978, 0.0, 0.0, 0.0],
                  [150.0, 0.0, 196.44305298271152, 15.976227678118347, 0.0, 0.0],
                  [200.0, 0.0, 170.40834611946292, 10.493976544391671, 20.4, 14.951975088622655]],
                 [[6, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 3, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0]]),
}


@pytest.mark.parametrize("key", sorted(TECH_RECORDED))
def test_technique_robot_results_are_unchanged(key):
    from confront.arena.tech import tech_battle

    names, scenario, seed, parts, placements = TECH_RECORDED[key]
    sc = get_scenario(scenario) if scenario else None
    got_parts, got_pl, _ = tech_battle(names, rounds=6, seed=seed, n_battles=3, scenario=sc)
    np.testing.assert_array_equal(got_pl, np.array(placements))
    np.testing.assert_allclose(got_parts, np.array(parts), rtol=0, atol=1e-9)
