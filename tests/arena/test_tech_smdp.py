"""The technique robots as TeamBattleEnv opponents: the compiled T-turn loop plays them as the Python turn loop
(TechBots.commands, Arena.step) does, and their battle memory lives for ``rounds_per_battle`` rounds."""

import numpy as np
import pytest

from confront.arena.control import set_adjustments
from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario
from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.tech import BINS, MID, S_GF, S_SURF, SEGMENTS, TechBots

ROWS = ("x", "y", "heading", "gun_heading", "radar_heading", "velocity", "energy", "gun_heat")


def _python_twin(env: TeamBattleEnv, names: list[str | None]) -> tuple[Arena, TechBots]:
    """The env's arena as a fresh Arena of the same scenario and seed after env.reset() (Arena.new_battle), and
    TechBots on it."""
    arena = Arena(env.scenario, env.n_battles, seed=0)
    arena.state.box_x[...] = np.nan
    arena.state.box_y[...] = np.nan
    arena.new_battle()
    set_adjustments(arena, env.learner)
    return arena, TechBots(arena, names, env.config.rounds_per_battle)


def test_env_plays_tech_robots_as_the_python_turn_loop_and_keeps_battle_memory_for_its_rounds():
    """A learning tank (seeded random paper moves, one turn a step) against two technique robots in a 3-robot
    free-for-all, 2 battles: every turn the env's robots equal a plain loop of TechBots.commands + Arena.step fed
    the tank's commands; the technique robots' memory too. With rounds_per_battle = 2 the battle memory (GuessFactor
    visit counts, surfing statistics) survives round 1's end and is cleared when round 3 (the next battle) starts."""
    sc = get_scenario("melee").replace(teams=(1, 1, 1))
    names = [None, "SurfGF", "OrbitVG"]
    env = TeamBattleEnv(sc, n_battles=2, seed=0, opponents=names[1:],
                        config=SMDPConfig(turns_per_step=1, rounds_per_battle=2))
    env.reset()
    arena, tech = _python_twin(env, names)
    assert env.tech is not None
    rng = np.random.default_rng(5)
    learner, bots = env.learner, ~env.learner
    s, s2 = env.arena.state, arena.state
    gf_at_round_end = {}
    checked = set()
    for turn in range(20000):
        rounds = s.round.copy()
        res = env.step(rng.integers(0, env.n_actions, size=(2, 3)))
        cmd = arena.idle_commands()
        cmd[:, learner] = env._cmd[:, learner]  # the tank's commands of this turn
        tech.commands(cmd)
        np.testing.assert_array_equal(cmd[:, bots], env._cmd[:, bots], err_msg=f"turn {turn}")
        arena.step(cmd)
        if res.round_done.any():
            for b in np.flatnonzero(res.round_done):
                gf_at_round_end[(b, int(rounds[b]))] = env.tech.stat[b, 1:, S_GF:S_GF + SEGMENTS * BINS].sum()
            arena.reset(s2.done.copy())
        for name in ROWS:
            np.testing.assert_array_equal(getattr(s, name), getattr(s2, name), err_msg=f"{name}, turn {turn}")
        for b in np.flatnonzero(s.round != rounds):  # a round started in battle b: at the next step's start
            checked.add((b, int(s.round[b])))
        if s.round.min() >= 4 and s.time.min() >= 2:
            break
    np.testing.assert_array_equal(env.tech.mem, tech.mem)
    np.testing.assert_array_equal(env.tech.stat, tech.stat)
    np.testing.assert_array_equal(env.tech.rng, tech.rng)
    assert all(v > 0 for v in gf_at_round_end.values())  # the guns learned in every round
    assert (s.score_total[:, 1:, 2] > 0).all()  # both technique robots hit with bullets in both battles
    np.testing.assert_array_equal(env.completed_battles, (s.round - 1) // 2)
    assert {(0, 2), (0, 3), (1, 2), (1, 3)} <= checked


def test_battle_memory_survives_round_ends_and_is_cleared_at_battle_boundaries():
    """1v1 against SurfVG, 5 turns a step: at the first step of round 2 the visit counts are round 1's (kept),
    at the first step of round 3 (a new battle of 2 rounds) they are cleared (surfing statistics back to their
    start: head-on aim expected); env.reset clears them too."""
    env = TeamBattleEnv("1v1", n_battles=1, seed=3, opponents="SurfVG",
                        config=SMDPConfig(turns_per_step=5, rounds_per_battle=2))
    env.reset()
    assert env.tech is not None
    stat = env.tech.stat[0, 1]
    start = np.zeros_like(stat)
    start[S_SURF + MID] = 1.0
    seen: dict[int, np.ndarray] = {}
    ended: dict[int, np.ndarray] = {}
    for _ in range(5000):
        r = int(env.arena.state.round[0])
        res = env.step(np.zeros((1, 2), dtype=np.int64))
        if r not in seen:
            seen[r] = stat.copy()  # after the round's first step (its memory synced at the step's start)
        if res.round_done[0]:
            ended[r] = stat.copy()
        if 4 in seen:
            break
    gf = slice(S_GF, S_GF + SEGMENTS * BINS)
    assert ended[1][gf].sum() > 0 and env.arena.state.score_total[0, 1].sum() > 0
    np.testing.assert_array_equal(seen[2][gf], ended[1][gf])  # kept across the round's end
    np.testing.assert_array_equal(seen[3], start)  # round 3 starts the second battle: cleared
    assert ended[2][gf].sum() > ended[1][gf].sum()
    assert env.completed_battles[0] == 1
    env.reset()
    np.testing.assert_array_equal(env.tech.stat[0, 1], start)
    assert env.completed_battles[0] == 0


def test_rounds_per_battle_is_validated():
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match="rounds_per_battle"):
            SMDPConfig(rounds_per_battle=bad)


def test_bad_opponent_names_list_the_technique_robots():
    with pytest.raises(ValueError, match="SurfGF"):
        TeamBattleEnv("1v1", opponents="SurfGG")


def test_multi_turn_steps_with_waiting_battles_play_as_the_python_turn_loop(monkeypatch):
    """7 turns a step, 3 battles of a learning tank against SurfVG in 1v1: a battle whose round ends mid-step waits
    (its technique robot decides nothing) until the step's end starts its next round. Each battle's turns equal a
    plain loop that starts the next round at once, fed the tank's commands of that battle's turns."""
    from confront.arena import smdp

    frames: list[tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]] = []
    env = TeamBattleEnv("1v1", n_battles=3, seed=0, opponents="SurfVG", config=SMDPConfig(turns_per_step=7))
    env.reset()
    s = env.arena.state
    live = [~s.done.copy()]

    def capture(rep, arena, b):  # every turn of a recorded step: who moved, the commands, the robots
        frames.append((live[0].copy(), env._cmd.copy(), {n: getattr(s, n).copy() for n in ROWS}))
        live[0] = ~s.done.copy()

    monkeypatch.setattr(smdp, "record_frame", capture)
    env.recording = (None, 0)
    rng = np.random.default_rng(2)
    waited = 0
    for _ in range(150):
        live[0] = ~s.done.copy()
        env.step(rng.integers(0, env.n_actions, size=(3, 2)))
        waited += int(sum((~f[0]).sum() for f in frames[-7:]))
    assert waited > 0  # some battles did wait within a step
    arena, tech = _python_twin(env, [None, "SurfVG"])
    per_battle = [[(f[1][b], {n: v[b] for n, v in f[2].items()}) for f in frames if f[0][b]] for b in range(3)]
    s2 = arena.state
    for k in range(min(len(p) for p in per_battle)):
        cmd = arena.idle_commands()
        for b in range(3):
            cmd[b, 0] = per_battle[b][k][0][0]
        tech.commands(cmd)
        for b in range(3):
            np.testing.assert_array_equal(cmd[b, 1], per_battle[b][k][0][1], err_msg=f"battle {b}, turn {k}")
        arena.step(cmd)
        for b in range(3):
            for name in ROWS:
                np.testing.assert_array_equal(getattr(s2, name)[b], per_battle[b][k][1][name],
                                              err_msg=f"{name}, battle {b}, turn {k}")
        if s2.done.any():
            arena.reset(s2.done.copy())
    assert s2.round.min() >= 2  # rounds ended and restarted on the way
