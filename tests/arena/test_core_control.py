"""The learning tanks' gun/radar controller and macro moves (confront.arena.control)."""

import math

import numpy as np
import pytest

from confront.arena.bots import ScriptedBots
from confront.arena.control import ControlConfig, gun_radar_commands, move_commands, nearest_enemy, set_adjustments
from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario


def arena_at(positions, teams):
    sc = get_scenario("melee").replace(teams=teams, initial_positions=tuple(positions))
    return Arena(sc, 1, order="fixed")


def test_nearest_living_enemy():
    a = arena_at([(100, 100, 0), (150, 100, 0), (400, 100, 0), (100, 500, 0)], (2, 2))
    assert nearest_enemy(a)[0].tolist() == [2, 2, 1, 0]  # team-mates never count; 400 < 403
    a.state.alive[0, 2] = False
    assert nearest_enemy(a)[0].tolist() == [3, 3, 1, 0]
    a.state.alive[0, 2:] = False
    assert nearest_enemy(a)[0].tolist() == [-1, -1, 1, 0]


def test_gun_and_radar_turn_toward_the_target():
    a = arena_at([(100, 100, 0), (400, 400, 0)], (1, 1))
    cmd = gun_radar_commands(a, a.idle_commands(), ControlConfig(radar_overshoot=0.1))
    assert cmd[0, 0, 2] == pytest.approx(math.pi / 4)  # north-east, clockwise from north
    assert cmd[0, 0, 3] == pytest.approx(math.pi / 4 + 0.1)
    assert cmd[0, 1, 2] == pytest.approx(-3 * math.pi / 4)
    assert cmd[0, 0, 4] == 0.0  # gun not aligned (and hot)


def test_fires_when_aligned_with_power_from_distance():
    a = arena_at([(100, 100, 0), (100, 300, 0)], (1, 1))
    a.state.gun_heat[0] = 0.0
    cfg = ControlConfig()
    cmd = gun_radar_commands(a, a.idle_commands(), cfg)
    assert cmd[0, 0, 4] == cfg.power_mid  # 200 px: mid band
    a.state.y[0, 1] = 200.0
    assert gun_radar_commands(a, a.idle_commands(), cfg)[0, 0, 4] == cfg.power_near
    a.state.y[0, 1] = 550.0
    assert gun_radar_commands(a, a.idle_commands(), cfg)[0, 0, 4] == cfg.power_far


def test_move_commands():
    cfg = ControlConfig(move_distance=80, turn_angle=0.5)
    d, t = move_commands(np.array([0, 1, 2, 3]), cfg)
    assert d.tolist() == [80, -80, 0, 0]
    assert t.tolist() == [0, 0, 0.5, -0.5]
    with pytest.raises(ValueError, match="actions"):
        move_commands(np.array([4]))


def test_bad_power_config():
    with pytest.raises(ValueError, match="power_near"):
        ControlConfig(power_near=5.0)


def test_controller_beats_a_sitting_duck():
    a = Arena(get_scenario("1v1").replace(max_turns=3000), 4, seed=2)
    bots = ScriptedBots(a, [None, "SittingDuck"])
    set_adjustments(a, np.array([True, False]))
    cmd = a.idle_commands()
    for _ in range(3000):
        bots.commands(cmd)
        gun_radar_commands(a, cmd, robots=np.array([True, False]))
        a.step(cmd)
        if a.state.done.all():
            break
    assert a.state.done.all()
    assert a.state.alive[:, 0].all() and not a.state.alive[:, 1].any()
