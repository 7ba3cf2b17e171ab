"""The scan memory: the compiled SMDP turn equals control.py driving the arena in Python, turn by turn."""

import numpy as np
import pytest

from confront.arena.control import ControlConfig, gun_radar_commands, known_targets, move_commands, remember
from confront.arena.observe import ObservationConfig, observe, perceive
from confront.arena.scenarios import get_scenario
from confront.arena.smdp import SMDPConfig, TeamBattleEnv


def test_compiled_smdp_equals_python_controller_with_memory() -> None:
    T = 5
    cfg = SMDPConfig(turns_per_step=T)
    env = TeamBattleEnv("4v4", n_battles=3, seed=4, opponents="td", config=cfg)
    ref = TeamBattleEnv("4v4", n_battles=3, seed=4, opponents="td", config=cfg)  # its arena is driven below
    env.reset()
    ref.reset()
    arena, s = ref.arena, ref.arena.state
    memory = np.zeros((3, 3, 8, 8))
    table = np.stack(move_commands(np.arange(4), ControlConfig()), axis=-1)
    stale = 0
    for a in np.random.default_rng(3).integers(0, 4, size=(12, 3, 8)):
        res = env.step(a)
        for t in range(T):
            cmd = arena.idle_commands()
            if t == 0:
                cmd[..., 0], cmd[..., 1] = table[a, 0], table[a, 1]
            gun_radar_commands(arena, cmd, ControlConfig(), memory=memory)
            view = perceive(s.x, s.y, s.energy, s.alive, s.team, memory, s.scan_time)
            tgt = known_targets(view, s.team)
            stale += int(((tgt >= 0) & (np.take_along_axis(view[0], np.maximum(tgt, 0)[..., None], 2)[..., 0]
                                         != np.take_along_axis(s.x, np.maximum(tgt, 0), 1))).sum())
            arena.step(cmd)
            remember(memory, arena)
        assert not res.round_done.any()
        np.testing.assert_allclose(env.arena.state.x, s.x, rtol=0, atol=1e-9)
        np.testing.assert_allclose(env.arena.state.gun_heading, s.gun_heading, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(env.arena.state.energy, s.energy)
        np.testing.assert_array_equal(env.arena.state.scan_time, s.scan_time)
        np.testing.assert_allclose(env._memory[:, :3], memory, rtol=0, atol=1e-9)  # x, y, energy rows
        target, disc, _ = observe(s.x, s.y, s.heading, s.energy, s.alive, ref.team, ref.field,
                                  cfg.observation, memory, s.scan_time)
        np.testing.assert_array_equal(res.target, target)
        np.testing.assert_array_equal(res.discrete, disc)
    assert (s.energy < 100).any()  # shots were fired and hit
    assert stale > 0  # some turns aimed at a stale scan


def test_before_the_first_scan_no_target() -> None:
    # a new round: nobody has scanned anybody yet, so every robot's first decision sees no target
    env = TeamBattleEnv("4v4", n_battles=2, seed=0, opponents="SpinBot")
    disc, feats = env.reset()
    assert (env.observe()[0] == -1).all()
    # no target: relative angle 0 and distance 0 -> state (0 * 4 + heading bin) * 20 + 0
    hb = (np.floor(env.arena.state.heading / (np.pi / 2))).astype(int)
    np.testing.assert_array_equal(disc, hb * 20)
    assert (feats[..., 4] == 0).all() and (feats[..., 6] == 0).all()
    # with true sensing the same start already has a target
    true_env = TeamBattleEnv("4v4", n_battles=2, seed=0, opponents="SpinBot",
                             config=SMDPConfig(observation=ObservationConfig(sensing="true")))
    true_env.reset()
    assert (true_env.observe()[0] >= 0).all()


def test_memory_hand_case_stale_position_and_death() -> None:
    # robot 1 was scanned by robot 0 at (400, 300) with 80 energy; it has since moved to (400, 500).
    sc = get_scenario("1v1").replace(initial_positions=((100.0, 300.0, 0.0), (400.0, 500.0, 0.0)))
    env = TeamBattleEnv(sc, 1, seed=0, opponents="SittingDuck")
    env.reset()
    s = env.arena.state
    memory = np.zeros((1, 3, 2, 2))
    memory[0, :, 0, 1] = (400.0, 300.0, 80.0)
    seen = np.full((1, 2, 2), -1, dtype=np.int32)
    seen[0, 0, 1] = 3
    vx, vy, ve, va = perceive(s.x, s.y, s.energy, s.alive, s.team, memory, seen)
    assert (vx[0, 0, 1], vy[0, 0, 1], ve[0, 0, 1], bool(va[0, 0, 1])) == (400.0, 300.0, 80.0, True)
    assert not va[0, 1, 0]  # robot 1 never scanned robot 0
    # the controller aims at the stale position: due east (90 deg) from a gun pointing north
    s.scan_time[...] = seen
    cmd = gun_radar_commands(env.arena, env.arena.idle_commands(), ControlConfig(), memory=memory)
    assert cmd[0, 0, 2] == pytest.approx(np.pi / 2)
    assert cmd[0, 0, 3] == pytest.approx(np.pi / 2 + np.deg2rad(20))
    assert np.isnan(cmd[0, 1, 2]) and cmd[0, 1, 3] == 2 * np.pi  # no known target: radar spins
    # the state and features come from the same picture: east (right of a north heading: rel bin 1),
    # heading bin 0, 300 px (bin 6 of 50 px); the true enemy at 360.6 px would be bin 7
    tgt, disc, feats = observe(s.x, s.y, s.heading, s.energy, s.alive, s.team, env.field, ObservationConfig(),
                               memory, seen)
    assert tgt[0].tolist() == [1, -1] and disc[0, 0] == (1 * 4 + 0) * 20 + 6
    assert feats[0, 0, 4] == pytest.approx(0.3) and feats[0, 0, 6] == pytest.approx(0.8)
    true_disc = observe(s.x, s.y, s.heading, s.energy, s.alive, s.team, env.field, ObservationConfig())[1]
    assert true_disc[0, 0] == (1 * 4 + 0) * 20 + 7
    # a dead enemy is forgotten (RobotDeathEvent)
    s.alive[0, 1] = False
    assert not perceive(s.x, s.y, s.energy, s.alive, s.team, memory, seen)[3][0, 0, 1]
    with pytest.raises(ValueError, match="sensing"):
        perceive(s.x, s.y, s.energy, s.alive, s.team, None, None)
