"""Seeded runs give the results recorded before the speed work, and the fused runner equals the step loop."""

import numpy as np
import pytest

from confront.arena.bots import ScriptedBots, bot_battle
from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario

OURS4 = ["SpinBot", "Walls", "Tracker", "RamFire"]
THEM4 = ["Walls", "Tracker", "Crazy", "Fire"]

# bot_battle(names, rounds=6, seed, n_battles=3, scenario): (score parts (R, 6), placements (R, 3)), recorded
# with the simulator as it was before the throughput work (commit 34b3372)
RECORDED = {
    "melee4": (OURS4, None, 3,
               [[500.0, 0.0, 358.0000000000001, 26.92000000000003, 28.79999999999999, 0.0],
                [900.0, 180.0, 478.5000000000001, 80.18000000000002, 7.199999999999999, 0.0],
                [350.0, 0.0, 680.6000000000001, 91.12000000000003, 32.39999999999999, 0.0],
                [50.0, 0.0, 504.0, 0.0, 130.79999999999995, 30.89999999999998]],
               [[0, 5, 0], [6, 0, 0], [0, 1, 5], [0, 0, 1]]),
    "fire_corners": (["Fire", "Corners"], None, 5,
                     [[250.0, 50.0, 493.0, 94.6, 0.0, 0.0], [50.0, 10.0, 352.0, 21.6, 0.0, 0.0]],
                     [[5, 1, 0], [1, 5, 0]]),
    "4v4": (OURS4 + THEM4, "4v4", 11,
            [[800.0, 0.0, 497.6, 62.040000000000006, 35.99999999999999, 0.0],
             [750.0, 0.0, 396.10000000000025, 98.78000000000004, 6.0, 0.0],
             [600.0, 0.0, 472.6, 33.0, 12.0, 0.0],
             [350.0, 0.0, 221.80000000000007, 15.480000000000002, 57.59999999999999, 37.55999999999999],
             [1200.0, 240.0, 638.5, 88.02000000000001, 4.8, 0.0],
             [450.0, 0.0, 516.2000000000002, 55.08000000000001, 12.0, 0.0],
             [450.0, 0.0, 112.2, 6.840000000000001, 25.199999999999996, 0.0],
             [200.0, 0.0, 292.0, 19.200000000000003, 0.0, 0.0]],
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
    a = Arena(scenario, 6, seed=3, threads=threads)
    b = Arena(scenario, 6, seed=3, threads=threads)
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
