"""TeamBattleEnv: per-turn Eq. 35 rewards over an SMDP step, round ends, auto-reset, checkpoints."""

import numpy as np
import pytest

from confront.arena.scenarios import get_scenario
from confront.arena.smdp import SMDPConfig, TeamBattleEnv, resolve_drivers
from confront.arena.tank import TankSpace


def _duel(turns: int = 40, opponents: str = "SittingDuck") -> TeamBattleEnv:
    sc = get_scenario("1v1").replace(initial_positions=((100.0, 300.0, 90.0), (400.0, 300.0, 0.0)))
    env = TeamBattleEnv(sc, 1, seed=0, opponents=opponents, config=SMDPConfig(turns_per_step=turns))
    env.reset()
    return env


def test_rewards_per_turn_hand_computed() -> None:
    # learner at (100, 300) facing a SittingDuck 300 px east; it turns on the spot while its gun aims.
    # Gun heat 3 -> first shot in turn 31 (power 2 at 300 px: energy 98), next in turn 45 (96).
    # Speed 14, 282 px to the box: the first bullet hits in turn 51 (index 10 of step 2):
    # own 96 -> 102 (+3p), duck 100 -> 90 (4p + 2(p-1) = 10); Eq. 35: (6 + 10) * 10 / |96 - 100| = 40.
    # Turn 65: own 102 -> 100 (shot in 59) -> 106, duck 90 -> 80: 16 * 10 / |100 - 90| = 16.
    # Turn 79: own 106 -> 104 (shot in 73) -> 110, duck 80 -> 70: 16 * 10 / |104 - 80| = 6.667.
    env = _duel()
    r1 = env.step(np.array([[2, 0]]))
    assert r1.rewards.shape == (1, 2, 40)
    assert np.all(r1.rewards[0, 0] == 0.0)
    # the learner's radar found the duck in turn 1 (it spins from 90 deg, the duck lies on the sweep's
    # start line) and then points exactly at it (no overshoot at a zero turn); after the 45-degree body
    # turn (5 turns) nothing moves, so nothing is scanned (Robocode scans only when something turned or
    # moved). The memory keeps the duck: it stays the target.
    assert env.arena.state.scan_time[0, 0, 1] == 5
    # a SittingDuck never turns its radar, so it never scans: it knows no target and earns no Eq. 35 reward
    assert env.arena.state.scan_time[0, 1, 0] == -1
    assert np.all(r1.rewards[0, 1] == 0.0) and r1.target[0].tolist() == [1, -1]
    assert env.arena.state.energy[0].tolist() == [98.0, 100.0]
    r2 = env.step(np.array([[2, 0]]))
    nz = np.flatnonzero(r2.rewards[0, 0])
    assert nz.tolist() == [10, 24, 38]
    np.testing.assert_allclose(r2.rewards[0, 0, nz], [40.0, 16.0, 160.0 / 24.0])
    assert r2.rewards[0, 0].sum() == pytest.approx(40.0 + 16.0 + 160.0 / 24.0)
    assert r2.active.tolist() == [[True, False]]
    assert env.arena.state.energy[0].tolist() == [110.0, 70.0]


def test_td_opponents_are_learners_with_rewards() -> None:
    env = _duel(opponents="td")
    assert env.learner.tolist() == [True, True]
    tot = np.zeros(2)
    for _ in range(6):
        r = env.step(np.array([[2, 0]]))  # robot 1 drives north, out of the line of fire
        assert r.active.tolist() == [[True, True]]
        tot += r.rewards[0].sum(axis=1)
    s = env.arena.state
    # both fire at each other; the side with more energy left collected the larger reward sum
    assert s.energy[0, 1] > s.energy[0, 0]
    assert tot[1] > 0 > tot[0]


def test_round_end_reports_scores_and_resets() -> None:
    env = TeamBattleEnv("1v1", n_battles=3, seed=2, opponents="SpinBot", config=SMDPConfig(turns_per_step=20))
    env.reset()
    rng = np.random.default_rng(0)
    seen = 0
    for _ in range(400):
        before = env.arena.state.score_total.copy()
        r = env.step(rng.integers(0, 4, size=(3, 2)))
        if r.round_end is None:
            assert not r.round_done.any()
            continue
        m = r.round_done
        assert r.terminated[m].all()
        assert r.final_discrete is not None and r.final_discrete.shape == (3, 2)
        # decided rounds add exactly their parts to the totals
        dec = m & r.round_end.decided
        np.testing.assert_allclose(
            r.info["score_total"][dec] - before[dec], r.round_end.score[dec], atol=1e-9
        )
        # survival: the survivor of a decided 1v1 got 50 for the other's death
        for b in np.flatnonzero(dec):
            winner = np.flatnonzero(r.round_end.alive[b])
            if winner.size == 1:
                assert r.round_end.score[b, winner[0], 0] == 50.0
        # the battle restarted: full energy, time 0
        assert np.all(env.arena.state.energy[m] == 100.0)
        assert np.all(env.arena.state.time[m] == 0)
        seen += int(m.sum())
        if seen >= 3:
            break
    assert seen >= 3


def test_state_dict_round_trip_repeats_the_future() -> None:
    env = TeamBattleEnv("4v4", n_battles=2, seed=5, opponents="Walls")
    env.reset()
    acts = np.random.default_rng(1).integers(0, 4, size=(30, 2, 8))
    for a in acts[:10]:
        env.step(a)
    snap = env.state_dict()
    out1 = [env.step(a).rewards for a in acts[10:]]
    env.load_state_dict(snap)
    out2 = [env.step(a).rewards for a in acts[10:]]
    for x, y in zip(out1, out2, strict=True):
        np.testing.assert_array_equal(x, y)


def test_fire_power_actions() -> None:
    sc = get_scenario("1v1").replace(initial_positions=((100.0, 300.0, 90.0), (400.0, 300.0, 0.0)))
    cfg = SMDPConfig(turns_per_step=40, fire_power_actions=True)
    env = TeamBattleEnv(sc, 1, seed=0, opponents="SittingDuck", config=cfg)
    env.reset()
    assert env.n_actions == 12
    env.step(np.array([[2 + 4 * 2, 0]]))  # clockwise with power 3.0: 100 - 3 = 97 after the first shot
    assert env.arena.state.energy[0, 0] == pytest.approx(97.0)


def test_bad_input_errors() -> None:
    env = TeamBattleEnv("1v1", n_battles=2, seed=0, opponents="SpinBot")
    env.reset()
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros((1, 2), dtype=int))
    with pytest.raises(ValueError, match="0..3"):
        env.step(np.full((2, 2), 4))
    with pytest.raises(ValueError, match="integers"):
        env.step(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="unknown opponent"):
        resolve_drivers(get_scenario("1v1"), "Nobody")
    with pytest.raises(ValueError, match="turns_per_step"):
        SMDPConfig(turns_per_step=0)


def test_compiled_controller_matches_control_module() -> None:
    from confront.arena import kernels as K
    from confront.arena.control import ControlConfig, gun_radar_commands
    from confront.arena.observe import perceive
    from confront.arena.smdp_kernel import controller_turn

    env = TeamBattleEnv("4v4", n_battles=4, seed=8, opponents="td")
    env.reset()
    for a in np.random.default_rng(2).integers(0, 4, size=(25, 4, 8)):
        env.step(a)  # a mix of positions, headings, gun heat, energies and stale scans
    s = env.arena.state
    s.gun_heat[:, ::2] = 0.0
    tgt = env.observe()[0]
    cfg = ControlConfig()
    ref = gun_radar_commands(env.arena, env.arena.idle_commands(), cfg, memory=env._memory)
    vx, vy, _, _ = perceive(s.x, s.y, s.energy, s.alive, s.team, env._memory, s.scan_time)
    out = env.arena.idle_commands()
    rf = env.arena.state.packed["rf"]
    stale = 0
    for b in range(4):
        for i in range(8):
            t = int(tgt[b, i])
            if s.alive[b, i]:
                controller_turn(rf, b, i, t, vx[b, i, t], vy[b, i, t], env.tanks.ctrl, 0.0, out)
                stale += t >= 0 and (vx[b, i, t], vy[b, i, t]) != (s.x[b, t], s.y[b, t])
    # equal up to the last bit of arctan2 (NumPy's and LLVM's libm may differ by one ulp)
    np.testing.assert_allclose(out[..., :4], ref[..., :4], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(out[..., 4], ref[..., 4])
    assert (ref[..., 4] > 0).any()  # some tanks fire
    assert stale > 0  # some tanks aim at a stale scan, not at the true position
    assert K.X == 0  # the kernel reads the packed arrays by these positions


@pytest.mark.parametrize("scenario, opponents, config", [
    ("4v4", "SpinBot", SMDPConfig()),
    ("4v4", "td", SMDPConfig(reward="score", tank=TankSpace())),
    ("1v1", "Walls", SMDPConfig(turns_per_step=40)),
])
def test_results_do_not_depend_on_the_battle_group(scenario: str, opponents: str, config: SMDPConfig) -> None:
    # the kernel steps battles in groups; a group whose battles all end early is given the turns it missed (bots,
    # scan memory, team messages, rewards), so any group size gives the bits of stepping all battles together
    envs = []
    for group in (1, 5, 24):
        env = TeamBattleEnv(scenario, 24, seed=3, opponents=opponents, config=config)
        env.battle_group = group
        env.reset()
        envs.append(env)
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(60):
        actions = rng.integers(0, envs[0].n_actions, size=(24, envs[0].n_robots))
        results = [env.step(actions) for env in envs]
        for res in results[1:]:
            for name in ("discrete", "features", "target", "rewards", "terminated", "round_done", "active"):
                np.testing.assert_array_equal(getattr(res, name), getattr(results[0], name), err_msg=name)
        np.testing.assert_array_equal(envs[1]._memory, envs[0]._memory)
        ended += int(results[0].round_done.sum())
    assert ended >= 1  # rounds ended mid-step while other battles played on: the groups of 1 and 5 caught up


def test_battle_group_must_be_a_positive_integer() -> None:
    env = TeamBattleEnv("1v1", 2, seed=0)
    for bad in (0, -3, 2.5, True):
        with pytest.raises(ValueError, match="battle_group"):
            env.battle_group = bad
    env.battle_group = 1
    assert env.battle_group == 1


def test_a_sample_team_fills_each_other_team_with_its_leader_and_droids() -> None:
    assert resolve_drivers(get_scenario("4v4"), "MyFirstTeam") == [None] * 4 + ["MyFirstLeader"] + ["MyFirstDroid"] * 3
    assert resolve_drivers(get_scenario("4v6"), "MyFirstTeam")[4:] == ["MyFirstLeader"] + ["MyFirstDroid"] * 5
    assert resolve_drivers(get_scenario("4v4"), "TrackFire")[4:] == ["TrackFire"] * 4
    for name in ("1v1", "melee"):  # a leader alone has no droid to command
        with pytest.raises(ValueError, match="MyFirstTeam needs teams of 2 or more robots"):
            resolve_drivers(get_scenario(name), "MyFirstTeam")
    env = TeamBattleEnv("4v4", 1, seed=0, opponents="MyFirstTeam")
    env.reset()
    s = env.arena.state
    assert s.is_droid[0].tolist() == [False] * 5 + [True] * 3
    assert s.is_leader[0].tolist() == [True, False, False, False, True, False, False, False]
    assert s.energy[0].tolist() == [200.0, 100.0, 100.0, 100.0, 200.0, 120.0, 120.0, 120.0]  # leaders 200, droids 120
