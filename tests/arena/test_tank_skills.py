"""The tank's skills (confront.arena.tank): the technique brain it carries in the simulator, its knowledge block,
surfing and the GuessFactor lead; off by default, and then the tank of before."""

from __future__ import annotations

import math

import numpy as np
import pytest

from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.tank import KNOWLEDGE_FEATURES, TankSpace, action_table, feature_names
from confront.arena.tech import MID, S_SURF, S_VG, T_AIMSLOT, W0, W_SIZE, WON, guess_aim

SKILLS = TankSpace(leads=("none", "circular", "gf"), surf=True, knowledge=True)


def _env(space: TankSpace, opponent: str = "SpinBot", n: int = 2, turns: int = 5, seed: int = 3,
         rounds_per_battle: int = 35) -> TeamBattleEnv:
    return TeamBattleEnv("1v1", n_battles=n, seed=seed, opponents=opponent,
                         config=SMDPConfig(turns_per_step=turns, tank=space, reward="score",
                                           rounds_per_battle=rounds_per_battle))


def _actions(space: TankSpace, env: TeamBattleEnv, rng: np.random.Generator, **fixed: int) -> np.ndarray:
    """Random tank actions (B, R), some heads fixed (d, t, f, k, lead)."""
    heads = [rng.integers(0, n, size=(env.n_battles, env.n_robots)) for n in space.dims]
    for h, name in enumerate("dtfkl"):
        if name in fixed:
            heads[h][...] = fixed[name]
    return np.ravel_multi_index(tuple(heads), space.dims)


def test_skills_are_off_by_default_and_their_encoding() -> None:
    plain = TankSpace()
    assert not plain.skills and plain.n_features == 62 and plain.dims == (5, 5, 4, 4, 2)
    assert not action_table(plain)[:, 6].any() and _env(plain).brains is None
    assert SKILLS.skills and SKILLS.n_features == 62 + KNOWLEDGE_FEATURES == 70
    assert SKILLS.dims == (6, 5, 4, 4, 3)  # surf: the distance head's extra last entry
    names = feature_names(4, 3, knowledge=True)
    assert len(names) == 70 and names[62:] == ["know_vg_head", "know_vg_linear", "know_vg_circular", "know_vg_gf",
                                               "know_waves", "know_wave_impact", "know_gf_peak", "know_surf_peak"]
    table = action_table(SKILLS)
    d = np.unravel_index(np.arange(SKILLS.n_actions), SKILLS.dims)[0]
    assert (table[:, 6] == (d == 5)).all() and (table[d == 5, 0] == 0).all() and set(table[:, 5]) == {0, 2, 3}
    assert TankSpace(leads=("gf",)).skills and TankSpace(knowledge=True).skills and TankSpace(surf=True).skills
    with pytest.raises(ValueError, match="tank.leads"):
        TankSpace(leads=("aimbot",))
    with pytest.raises(ValueError, match="tank.surf must be true or false"):
        TankSpace(surf=1)  # type: ignore[arg-type]


def test_knowledge_alone_changes_no_move_and_ends_the_view() -> None:
    """A brain that only watches: the battles are those of the tank without skills, bit for bit; the view is the
    same followed by the knowledge block, whose values are the brain's."""
    know = TankSpace(knowledge=True)
    a, b = _env(TankSpace()), _env(know)
    _, fa = a.reset()
    _, fb = b.reset()
    rng = np.random.default_rng(1)
    waves = 0
    for _ in range(120):
        acts = _actions(know, a, rng)
        fa, fb = a.step(acts).features, b.step(acts).features
        np.testing.assert_array_equal(fa, fb[..., :62])
        for name in ("x", "y", "heading", "gun_heading", "energy"):
            np.testing.assert_array_equal(getattr(a.arena.state, name), getattr(b.arena.state, name))
        np.testing.assert_array_equal(fb[:, 0, 62:66], b.brains.stat[:, 0, S_VG:S_VG + 4].astype(np.float32))
        waves += int((fb[:, 0, 66] > 0).sum())
        assert (fb[:, 1, 62:] == 0).all()  # SpinBot carries no brain
    assert waves > 0 and (fb[:, 0, 62:66] > 0).any()


def test_the_battle_memory_lasts_a_battle_and_the_round_memory_a_round() -> None:
    """Rounds 1-2 are one battle (rounds_per_battle 2): the virtual-gun hit rates and the surfing statistics carry
    into round 2, the waves do not; round 3 starts a new battle with both forgotten."""
    env = _env(SKILLS, "Fire", n=1, turns=5, rounds_per_battle=2)
    env.reset()
    rng = np.random.default_rng(4)
    ends = []
    for _ in range(3000):
        before = env.brains.stat[0, 0].copy()
        res = env.step(_actions(SKILLS, env, rng, f=3, l=1))  # power 3, circular
        if res.round_end is not None:
            k = res.features[0, 0, 62:]
            ends.append((before, env.brains.stat[0, 0].copy(), k, env.brains.mem[0, 0].copy()))
            if len(ends) == 2:
                break
    assert len(ends) == 2, "two rounds did not end"
    (kept_before, kept, k2, mem2), (_, fresh, k3, _) = ends
    assert kept[S_VG:S_VG + 4].any() and np.array_equal(kept, kept_before)  # round 2 starts with round 1's stats
    np.testing.assert_array_equal(k2[:4], kept[S_VG:S_VG + 4].astype(np.float32))
    assert kept[S_SURF:S_SURF + 31].sum() > 1.0  # its bullets hit us: learned where
    assert not mem2.any() and k2[4] == 0 and k2[5] == 1 and k2[6] == 0  # no wave, no aim yet this round
    assert not fresh[S_VG:S_VG + 4].any() and fresh[S_SURF + MID] == 1 and fresh[S_SURF:S_SURF + 31].sum() == 1
    np.testing.assert_array_equal(k3, np.array([0, 0, 0, 0, 0, 1, 0, 1], dtype=np.float32))
    env.brains.stat[...] = 7.0
    env.reset()  # a new battle, also after one round
    assert env.brains.stat[0, 0, S_SURF + MID] == 1 and not env.brains.stat[0, 0, S_VG:S_VG + 4].any()


def test_surf_and_gf_follow_the_brain() -> None:
    """With surf the body's commands are the brain's every turn of the step; with the lead gf the gun turns to the
    brain's GuessFactor angle when it aimed at the target this turn (else circular)."""
    env = _env(SKILLS, "SpinBot", n=2, turns=1)
    env.reset()
    rng = np.random.default_rng(5)
    surfed = aimed = fallback = 0
    for _ in range(400):
        acts = _actions(SKILLS, env, rng, d=5, l=2, k=0)
        s = env.arena.state
        gun_before = s.gun_heading.copy()
        env.step(acts)
        cmd, brain = env._cmd, env._brain_cmd
        for b in range(2):
            if not s.alive[b, 0] or s.done[b]:
                continue
            np.testing.assert_array_equal(cmd[b, 0, :2], brain[b, 0, :2])
            surfed += not math.isnan(brain[b, 0, 0])
            m = env.brains.mem[b, 0]
            if m[T_AIMSLOT] >= 0 and env._chosen[b, 0] == 1:
                p = env._power[b, 0] if env._power[b, 0] > 0 else 2.0
                want = guess_aim(m, 1, p) - gun_before[b, 0]
                assert math.isclose((cmd[b, 0, 2] - want + math.pi) % (2 * math.pi) - math.pi, 0.0, abs_tol=1e-12)
                aimed += 1
            else:
                fallback += 1
    waves = sum(env.brains.mem[b, 0, W0 + k * W_SIZE + WON] for b in range(2) for k in range(16))
    assert surfed > 100 and aimed > 100 and fallback > 0, (surfed, aimed, fallback, waves)


def test_a_checkpoint_keeps_the_brains() -> None:
    a, b = _env(SKILLS), _env(SKILLS)
    a.reset()
    b.reset()
    rng = np.random.default_rng(6)
    for _ in range(60):
        a.step(_actions(SKILLS, a, rng))
    b.load_state_dict(a.state_dict())
    for _ in range(40):
        acts = _actions(SKILLS, a, rng)
        ra, rb = a.step(acts), b.step(acts)
        np.testing.assert_array_equal(ra.features, rb.features)
        np.testing.assert_array_equal(ra.rewards, rb.rewards)
    np.testing.assert_array_equal(a.brains.stat, b.brains.stat)
    d = a.state_dict()
    del d["brains.stat"]
    with pytest.raises(ValueError, match="stat is missing"):
        b.load_state_dict(d)


def test_the_config_exposes_the_skills() -> None:
    from confront.config import ConfigError
    from confront.train.ppo_model import smdp_tank_config, tank_space
    from confront.train.spec import load_experiment

    assert not tank_space(load_experiment("tanks-demo")).skills  # off unless a config asks
    cfg = load_experiment("tanks-demo", ['tank.leads=["none", "linear", "circular", "gf"]', "tank.surf=true",
                                         "tank.knowledge=true"])
    space = smdp_tank_config(cfg).tank
    assert space is not None and space.leads[-1] == "gf" and space.surf and space.knowledge
    assert space.n_features == 70 and space.dims[0] == 6
    with pytest.raises((ConfigError, ValueError), match="tank.leads entry 'aimbot'"):
        load_experiment("tanks-demo", ['tank.leads=["aimbot"]'])
