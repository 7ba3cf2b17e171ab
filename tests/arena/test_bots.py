"""Scripted sample robots behave like Robocode's samples (observable behaviour)."""

import math

import numpy as np
import pytest

from confront.arena.bots import BOT_NAMES, ScriptedBots, bot_battle
from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario
from confront.engine.install import engine_available


def run(names, positions, turns, seed=0):
    sc = get_scenario("melee").replace(teams=tuple(1 for _ in names), initial_positions=tuple(positions))
    arena = Arena(sc, 1, seed=seed, order="fixed")
    bots = ScriptedBots(arena, list(names))
    cmd = arena.idle_commands()
    traj = []
    for _ in range(turns):
        bots.commands(cmd)
        arena.step(cmd)
        s = arena.state
        traj.append(np.stack([s.x[0], s.y[0], s.heading[0], s.velocity[0], s.energy[0], s.gun_heading[0]], 1))
        if s.done[0]:
            break
    return arena, np.array(traj)


def test_sitting_duck_sits():
    arena, tr = run(["SittingDuck", "SittingDuck"], [(100, 100, 0), (700, 500, 0)], 50)
    assert np.all(tr[:, :, :4] == tr[0, :, :4])


def test_spinbot_circles_at_speed_5():
    _, tr = run(["SpinBot", "SittingDuck"], [(400, 300, 0), (780, 580, 0)], 60)
    v = tr[10:, 0, 3]
    assert np.all(v == 5.0)
    dh = np.diff(np.unwrap(tr[10:, 0, 2]))
    assert dh == pytest.approx(math.radians(10 - 0.75 * 5))  # turning at the limit for speed 5
    # the positions lie on one circle: chord 5 per turn of 6.25 deg, radius 5 / (2 sin(3.125 deg))
    x, y = tr[10:, 0, 0], tr[10:, 0, 1]
    sol = np.linalg.lstsq(np.stack([2 * x, 2 * y, np.ones_like(x)], 1), x * x + y * y, rcond=None)[0]
    r = np.hypot(x - sol[0], y - sol[1])
    assert r == pytest.approx(5 / (2 * math.sin(math.radians(3.125))), abs=1e-6)


def test_walls_drives_along_the_walls():
    _, tr = run(["Walls", "SittingDuck"], [(400, 300, 30), (100, 500, 0)], 400)
    x, y, h = tr[150:, 0, 0], tr[150:, 0, 1], tr[150:, 0, 2]
    near = np.minimum.reduce([x - 18, 782 - x, y - 18, 582 - y])
    assert np.mean(near < 1.0) > 0.9  # hugging a wall nearly all the time
    assert np.all(np.isclose(np.mod(h, math.pi / 2), 0) | np.isclose(np.mod(h, math.pi / 2), math.pi / 2)
                  | (tr[150:, 0, 3] == 0))
    assert tr[-1, 1, 4] < 100  # and hits the duck


def test_tracker_closes_in_and_fires():
    _, tr = run(["Tracker", "SittingDuck"], [(100, 100, 0), (600, 500, 0)], 300)
    d = np.hypot(tr[:, 0, 0] - 600, tr[:, 0, 1] - 500)
    assert d[0] > 600 and d[-1] < 160
    assert tr[-1, 1, 4] < 100


def test_ramfire_rams():
    arena, tr = run(["RamFire", "SittingDuck"], [(100, 100, 0), (500, 400, 0)], 200)
    d = np.hypot(tr[:, 0, 0] - 500, tr[:, 0, 1] - 400)
    assert d.min() < 36 * math.sqrt(2)  # boxes overlapping
    assert arena.state.score[0, 0, 4] > 0  # ram damage scored


def test_fire_turns_its_gun_and_shoots_what_it_sees():
    _, tr = run(["Fire", "SittingDuck"], [(400, 300, 0), (400, 500, 90)], 150)
    assert np.all(tr[:, 0, :2] == [400, 300])  # never moves unless hit
    assert tr[-1, 1, 4] < 100


def test_corners_goes_to_a_corner():
    _, tr = run(["Corners", "SittingDuck"], [(400, 300, 0), (700, 100, 0)], 400)
    x, y = tr[-1, 0, 0], tr[-1, 0, 1]
    assert (x < 20 or x > 780) and (y < 20 or y > 580)


def test_crazy_moves_and_turns():
    _, tr = run(["Crazy", "SittingDuck"], [(400, 300, 0), (100, 100, 0)], 200)
    assert np.abs(tr[:, 0, 3]).max() == 8.0
    assert np.ptp(np.unwrap(tr[:, 0, 2])) > math.radians(90)


def test_every_bot_survives_a_melee_round():
    names = list(BOT_NAMES)
    sc = get_scenario("melee").replace(teams=tuple(1 for _ in names), max_turns=3000)
    arena = Arena(sc, 4, seed=5)
    bots = ScriptedBots(arena, names)
    cmd = arena.idle_commands()
    for _ in range(3000):
        bots.commands(cmd)
        arena.step(cmd)
        if arena.state.done.all():
            break
    assert arena.state.score_total.sum() > 0


def test_unknown_bot_name():
    arena = Arena("1v1", 1)
    with pytest.raises(ValueError, match="unknown bot"):
        ScriptedBots(arena, ["SpinBot", "Nope"])


def test_bot_battle_counts_rounds():
    parts, places = bot_battle(["Walls", "SittingDuck"], rounds=5, n_battles=2, turns_after_end=0)
    assert places[:, 0].sum() == 5  # one first per round
    assert parts[0].sum() > parts[1].sum()


@pytest.mark.engine
@pytest.mark.slow
@pytest.mark.skipif(not engine_available(), reason="needs the real Robocode engine")
@pytest.mark.parametrize("pair", [("SpinBot", "Walls"), ("Tracker", "RamFire")])
def test_score_shares_match_the_real_engine(pair):
    """Small version of the 100-round comparison: 20 rounds, same seed (one simulated battle draws the engine's
    start positions and processing order), shares within 5 points."""
    from confront.engine.battle import BattleSpec
    from confront.engine.runner import EngineOptions, run_battle

    run = run_battle(BattleSpec(contestants=pair, rounds=20), EngineOptions(seed=1, cpu_constant_ms=100.0))  # no skips
    eng = {r.name.split(".")[-1]: r.total for r in run.results.contestants}
    eng_share = eng[pair[0]] / sum(eng.values())
    parts, _ = bot_battle(list(pair), rounds=20, seed=1, n_battles=1)
    sim_share = parts[0].sum() / parts.sum()
    assert abs(sim_share - eng_share) < 0.05, (sim_share, eng_share)


def test_bots_state_dict_round_trip():
    sc = get_scenario("melee").replace(teams=(1, 1, 1, 1))
    names = ["SpinBot", "Walls", "Tracker", "Fire"]
    a = Arena(sc, 3, seed=4)
    bots = ScriptedBots(a, names)
    cmd = a.idle_commands()
    for _ in range(80):
        bots.commands(cmd)
        a.step(cmd)
    saved, saved_bots = a.state_dict(), bots.state_dict()
    ref = []
    for _ in range(80):
        bots.commands(cmd)
        a.step(cmd)
        ref.append(a.state.x.copy())
    b = Arena(sc, 3, seed=0)
    b.load_state_dict(saved)
    bots2 = ScriptedBots(b, names)
    bots2.load_state_dict(saved_bots)
    cmd2 = b.idle_commands()
    for x in ref:
        bots2.commands(cmd2)
        b.step(cmd2)
        np.testing.assert_array_equal(b.state.x, x)


# Recorded from the real engine (Robocode 1.9.3.9): sample.SpinBot vs sample.Walls, -DRANDOMSEED=5,
# CPU constant 10 ms, no skipped turns; round 1 lasted 1265 turns (150 after the decision). Per turn:
# (x, y, energy) of SpinBot and Walls. The simulator with seed 5 draws the same start positions and,
# with the scripted bots, plays the same round.
ENGINE_SPINBOT_WALLS = {
    50: ((563.065866142257, 127.74815304335698, 100.0), (372.2174922459349, 18.0, 100.0)),
    200: ((480.6401849450951, 100.37772280900053, 91.0), (18.0, 582.0, 96.0)),
    400: ((571.7130874513518, 107.73625104496173, 62.0), (754.0, 18.0, 100.0)),
    600: ((483.3015819923518, 84.67487183237904, 33.0), (102.0, 582.0, 104.0)),
    800: ((566.3653515491083, 122.73839368382762, 14.0), (642.0, 18.0, 104.0)),
    1000: ((491.1731685002858, 70.82927004389498, 4.0), (206.0, 582.0, 86.0)),
    1100: ((487.4517354741597, 124.12360351290145, 0.0), (782.0, 466.0, 82.0)),
    1265: ((487.4517354741597, 124.12360351290145, 0.0), (18.0, 18.0, 88.0)),
}


def test_spinbot_vs_walls_replays_an_engine_round():
    sc = get_scenario("melee").replace(teams=(1, 1), turns_after_end=150, max_turns=100000)
    arena = Arena(sc, 1, seed=5)
    bots = ScriptedBots(arena, ["SpinBot", "Walls"])
    cmd = arena.idle_commands()
    s = arena.state
    for t in range(1, 1266):
        bots.commands(cmd)
        arena.step(cmd)
        if t in ENGINE_SPINBOT_WALLS:
            got = np.stack([s.x[0], s.y[0], s.energy[0]], 1)
            np.testing.assert_allclose(got, ENGINE_SPINBOT_WALLS[t], atol=1e-6, err_msg=f"turn {t}")
    assert s.done[0] and s.time[0] == 1265
