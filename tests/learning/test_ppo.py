"""PPO: GAE by hand, the factorised joint action, the team critic's input, learning a known problem, state."""

import math

import numpy as np
import pytest
import torch

from confront.config import ConfigError, from_dict, to_dict
from confront.learning.ppo import PPO, Rollout, Tanh, gae, greedy_joint, team_mean
from confront.learning.ppo_config import PPOConfig


def test_gae_hand_computed() -> None:
    # one agent, 3 steps, gamma 0.5, lambda 0.5; the episode ends at step 1, a new one starts at step 2
    r = np.array([[1.0], [2.0], [3.0]])
    v = np.array([[0.5], [1.0], [2.0]])
    done = np.array([[False], [True], [False]])
    active = np.ones((3, 1), bool)
    adv, ret = gae(r, v, done, active, np.array([4.0]), 0.5, 0.5)
    d2 = 3.0 + 0.5 * 4.0 - 2.0  # 3
    d1 = 2.0 - 1.0  # 1 (terminal: no bootstrap)
    d0 = 1.0 + 0.5 * 1.0 - 0.5  # 1
    a1 = d1
    a0 = d0 + 0.25 * a1
    np.testing.assert_allclose(adv[:, 0], [a0, a1, d2])
    np.testing.assert_allclose(ret, adv + v)


def test_gae_inactive_steps_are_zero_and_cut() -> None:
    r = np.array([[1.0], [5.0], [1.0]])
    v = np.array([[0.0], [9.0], [0.0]])
    done = np.array([[True], [False], [False]])  # died at step 0, dead (inactive) at step 1, new round at 2
    active = np.array([[True], [False], [True]])
    adv, _ = gae(r, v, done, active, np.array([0.0]), 0.9, 0.9)
    np.testing.assert_allclose(adv[:, 0], [1.0, 0.0, 1.0])


def test_joint_action_is_mixed_radix() -> None:
    dims = (5, 5, 4, 4)
    logits = np.full((1, sum(dims)), -1.0)
    for start, pick in zip(np.cumsum((0,) + dims[:-1]), (3, 1, 2, 0), strict=True):
        logits[0, start + pick] = 1.0
    assert greedy_joint(logits, dims)[0] == ((3 * 5 + 1) * 4 + 2) * 4 + 0
    assert greedy_joint(np.zeros((1, 18)), dims)[0] == 0  # ties go to the lower index


def test_team_mean_over_living() -> None:
    obs = np.array([[1.0, 0.0], [3.0, 2.0], [5.0, 5.0]], np.float32)
    out = team_mean(obs, np.array([0, 0, 1]), 2, np.array([True, True, False]))
    np.testing.assert_allclose(out[0], [2.0, 1.0], atol=1e-5)
    np.testing.assert_allclose(out[2], [5.0, 5.0], atol=1e-5)  # nobody alive: the plain mean


def _bandit_rollout(ppo: PPO, rng: np.random.Generator, s: int = 8, n: int = 64) -> Rollout:
    """A contextual bandit: the sign of feature 0 says which of head 0's two actions pays 1."""
    obs = rng.choice([-1.0, 1.0], size=(s, n, 2)).astype(np.float32)
    heads, logp, value = np.zeros((s, n, 2), np.int64), np.zeros((s, n), np.float32), np.zeros((s, n), np.float32)
    reward = np.zeros((s, n))
    for t in range(s):
        _, h, lp = ppo.act(obs[t])
        heads[t], logp[t], value[t] = h, lp, ppo.values(obs[t])
        reward[t] = (h[:, 0] == (obs[t, :, 0] > 0)).astype(float)
    return Rollout(obs, obs.copy(), heads, logp, value, reward, np.ones((s, n), bool), np.ones((s, n), bool),
                   np.zeros(n, np.float32))


def test_learns_a_contextual_bandit() -> None:
    rng = np.random.default_rng(0)
    ppo = PPO(2, (2, 3), PPOConfig(hidden=16, lr=3e-3, team_critic=False, ent_coef=0.0), seed=0)
    first = _bandit_rollout(ppo, rng).reward.mean()
    for _ in range(40):
        ppo.update(_bandit_rollout(ppo, rng))
    obs = np.array([[1.0, 1.0], [-1.0, 1.0]], np.float32)
    joint, heads, _ = ppo.act(obs, explore=False)
    assert first < 0.7
    assert heads[:, 0].tolist() == [1, 0]  # head 0 follows the sign of feature 0
    assert _bandit_rollout(ppo, rng).reward.mean() > 0.95


def test_state_dict_resumes_exactly() -> None:
    rng = np.random.default_rng(1)
    a = PPO(2, (2, 3), PPOConfig(hidden=8, team_critic=False), seed=3)
    a.update(_bandit_rollout(a, rng))
    b = PPO(2, (2, 3), PPOConfig(hidden=8, team_critic=False), seed=99)
    b.load_state_dict({k: v.copy() for k, v in a.state_dict().items()})
    ro = _bandit_rollout(PPO(2, (2, 3), PPOConfig(hidden=8, team_critic=False), seed=7), np.random.default_rng(5))
    a.update(ro)
    b.update(ro)
    for k, v in a.state_dict().items():
        np.testing.assert_array_equal(v, b.state_dict()[k], err_msg=k)
    obs = np.ones((4, 2), np.float32)
    np.testing.assert_array_equal(a.act(obs)[0], b.act(obs)[0])  # the sampling generator too


def test_bad_state_and_config_refused() -> None:
    a = PPO(2, (2, 3), PPOConfig(hidden=8))
    with pytest.raises(ValueError, match="does not fit"):
        a.load_state_dict(PPO(3, (2, 3), PPOConfig(hidden=8)).state_dict())
    for key, value, message in (("rollout_steps", 0, "out of range: must be >= 1"),
                                ("threads", 0, "out of range: must be >= 1"),
                                ("precision", "fp16", "not allowed: use one of 'fp32', 'bf16', 'bf16-hidden'"),
                                ("critic_hidden", -1, "out of range: must be >= 0"),
                                ("threads", 2.0, "the wrong type: expected an integer")):
        with pytest.raises(ConfigError, match=f"ppo.{key} = .* (is|has) {message}"):
            from_dict(PPOConfig, {key: value}, prefix="ppo")  # checked where a config is read


def test_one_config_type_for_the_learner_and_the_configs() -> None:
    """A config's [ppo] section is the learner's PPOConfig, its defaults the ones the shipped configs rely on."""
    from confront.train.spec import ExperimentConfig, load_experiment

    assert type(ExperimentConfig().ppo) is PPOConfig and ExperimentConfig().ppo == PPOConfig()
    assert (PPOConfig().lr, PPOConfig().gamma, PPOConfig().threads) == (2.5e-3, 0.97, 2)
    cfg = load_experiment("tanks-demo", ["ppo.lr=0.001"])
    assert cfg.ppo == from_dict(PPOConfig, {**to_dict(PPOConfig()), **to_dict(cfg.ppo)}) and cfg.ppo.lr == 1e-3


def test_critic_hidden_sizes_the_critic_only() -> None:
    """``critic_hidden`` narrows the critic; the actor (what is exported) is drawn as without it; a state of
    the other width is refused."""
    wide = PPO(3, (2, 3), PPOConfig(hidden=16), seed=4)
    narrow = PPO(3, (2, 3), PPOConfig(hidden=16, critic_hidden=4), seed=4)
    assert [tuple(p.shape) for p in narrow.net.critic.parameters()] == [(4, 6), (4,), (4, 4), (4,), (1, 4), (1,)]
    for a, b in zip(wide.net.actor.parameters(), narrow.net.actor.parameters(), strict=True):
        assert torch.equal(a, b)
    assert narrow.state_dict()["net.critic.0.weight"].shape == (4, 6)
    with pytest.raises(ValueError, match="does not fit"):
        wide.load_state_dict(narrow.state_dict())


def test_bf16_update_learns_and_stays_near_fp32() -> None:
    """bfloat16 hidden layers: log-probabilities within bf16's rounding of fp32's, output layers float32, one
    update's step within a few percent of fp32's, and the bandit still learned."""
    ppo = PPO(2, (2, 3), PPOConfig(hidden=16, lr=3e-3, team_critic=False, ent_coef=0.0, precision="bf16"), seed=0)
    obs = torch.from_numpy(np.random.default_rng(2).standard_normal((64, 2)).astype(np.float32))
    lp32, lp16 = ppo.net.log_probs(obs), ppo.net.log_probs(obs, "bf16")
    assert lp16.dtype == torch.float32 and ppo.net.value(obs, "bf16").dtype == torch.float32
    fin = torch.isfinite(lp32)
    assert 0 < (lp16[fin] - lp32[fin]).abs().max() < 0.02  # not fp32's bits, within bf16's 2^-8
    lph = ppo.net.log_probs(obs, "bf16-hidden")  # the first layer in float32: neither fp32's nor bf16's values
    assert 0 < (lph[fin] - lp32[fin]).abs().max() < 0.02 and not torch.equal(lph, lp16)
    twin = PPO(2, (2, 3), PPOConfig(hidden=16, lr=3e-3, team_critic=False, ent_coef=0.0), seed=0)
    ro = _bandit_rollout(twin, np.random.default_rng(0))
    w0 = twin.net.actor[0].weight.detach().clone()
    twin.update(ro)
    ppo.update(ro)
    step32, step16 = twin.net.actor[0].weight.detach() - w0, ppo.net.actor[0].weight.detach() - w0
    assert 0 < (step16 - step32).norm() < 0.05 * step32.norm()
    rng = np.random.default_rng(0)
    for _ in range(40):
        ppo.update(_bandit_rollout(ppo, rng))
    assert _bandit_rollout(ppo, rng).reward.mean() > 0.95


def test_tanh_is_tanh_with_tanhs_gradient() -> None:
    x = torch.linspace(-12, 12, 2001, dtype=torch.float32, requires_grad=True)
    y = Tanh()(x)
    np.testing.assert_allclose(y.detach().numpy(), np.tanh(x.detach().numpy().astype(np.float64)), atol=2.5e-7)
    assert Tanh()(torch.tensor([0.0, -12.0, 12.0])).tolist() == [0.0, -1.0, 1.0]  # odd at 0; saturates
    y.sum().backward()
    np.testing.assert_allclose(x.grad.numpy(), 1 - np.tanh(x.detach().numpy().astype(np.float64)) ** 2, atol=1e-6)
    x64 = torch.randn(20, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(Tanh(), (x64,))


def test_update_widens_to_its_threads_and_acts_on_one() -> None:
    seen: list[int] = []
    ppo = PPO(2, (2, 3), PPOConfig(hidden=8, team_critic=False, threads=2), seed=0)
    learn = ppo._learn
    ppo._learn = lambda ro: (seen.append(torch.get_num_threads()), learn(ro))[1]  # type: ignore[method-assign]
    assert torch.get_num_threads() == 1
    ppo.update(_bandit_rollout(ppo, np.random.default_rng(0)))
    assert seen == [2] and torch.get_num_threads() == 1


def test_overlap_acts_one_update_behind_and_stays_deterministic() -> None:
    obs = np.random.default_rng(2).standard_normal((64, 2)).astype(np.float32)
    runs = []
    for _ in range(2):
        rng = np.random.default_rng(4)
        ppo = PPO(2, (2, 3), PPOConfig(hidden=8, team_critic=False, lr=1e-2, overlap=True), seed=5)
        assert ppo.acting is not ppo.net
        ppo.update(_bandit_rollout(ppo, rng))  # the synchronous form: acting follows at once
        before = ppo.act(obs, explore=False)[1]
        ppo.start_update(_bandit_rollout(ppo, rng))
        during = ppo.act(obs, explore=False)[1]  # the update runs on the worker; acting keeps the old weights
        stats = ppo.finish_update()
        assert np.isfinite(stats["policy_loss"]) and 0.0 <= stats["clip_frac"] <= 1.0
        np.testing.assert_array_equal(before, during)
        for a, b in zip(ppo.acting.state_dict().values(), ppo.net.state_dict().values(), strict=True):
            np.testing.assert_array_equal(a.numpy(), b.numpy())
        runs.append(ppo.state_dict())
    for k, v in runs[0].items():  # thread timing does not enter the results
        np.testing.assert_array_equal(v, runs[1][k], err_msg=k)
    with pytest.raises(RuntimeError, match="without start_update"):
        PPO(2, (2, 3), PPOConfig(hidden=8)).finish_update()


def test_entropy_coefficient_anneals_linearly() -> None:
    from confront.learning.ppo import entropy_coef

    c = PPOConfig(ent_coef=0.01, ent_coef_end=0.002, ent_anneal_updates=100)
    assert entropy_coef(c, 0) == 0.01 and entropy_coef(c, 100) == 0.002 and entropy_coef(c, 500) == 0.002
    assert entropy_coef(c, 25) == pytest.approx(0.008)
    assert entropy_coef(PPOConfig(ent_coef=0.03), 10_000) == 0.03  # off by default
    with pytest.raises(ConfigError, match="ppo.ent_anneal_updates = -1 is out of range"):
        from_dict(PPOConfig, {"ent_anneal_updates": -1}, prefix="ppo")


def test_polyak_average_of_the_actor_hand_computed() -> None:
    """ema_decay = d: after updates 1 and 2 the average is d^2 w0 + d(1-d) w1 + (1-d) w2; it resumes from its
    state and a finished run adopts it as its actor."""
    rng = np.random.default_rng(4)
    d = 0.5
    ppo = PPO(2, (2, 3), PPOConfig(hidden=8, lr=1e-2, team_critic=False, ema_decay=d), seed=1)
    ws = [ppo.actor_arrays()]
    for _ in range(2):
        ppo.update(_bandit_rollout(ppo, rng))
        ws.append(ppo.actor_arrays())
    expected = {k: d * d * ws[0][k] + d * (1 - d) * ws[1][k] + (1 - d) * ws[2][k] for k in ws[0]}
    assert not np.allclose(ws[2]["w0"], expected["w0"], atol=1e-4)  # the average is not the last actor
    copy = PPO(2, (2, 3), PPOConfig(hidden=8, team_critic=False, ema_decay=d), seed=9)
    copy.load_state_dict(ppo.state_dict())
    for p in (ppo, copy):
        p.adopt_average()
        for k, v in p.actor_arrays().items():
            np.testing.assert_allclose(v, expected[k], rtol=1e-5, atol=1e-6, err_msg=k)
    with pytest.raises(ConfigError, match="ppo.ema_decay = 1.0 is out of range"):
        from_dict(PPOConfig, {"ema_decay": 1.0}, prefix="ppo")


def test_value_warmup_trains_the_critic_alone() -> None:
    """value_warmup_updates = 2: the first two updates leave the actor's bits alone and move the critic; the third
    moves the actor."""
    rng = np.random.default_rng(2)
    ppo = PPO(2, (2, 3), PPOConfig(hidden=8, lr=1e-2, team_critic=False, value_warmup_updates=2), seed=1)
    actor0 = ppo.actor_arrays()
    critic0 = [p.detach().clone() for p in ppo.net.critic.parameters()]
    for _ in range(2):
        ppo.update(_bandit_rollout(ppo, rng))
        for k, v in ppo.actor_arrays().items():
            np.testing.assert_array_equal(v, actor0[k], err_msg=k)
    assert any(not torch.equal(a, b) for a, b in zip(critic0, ppo.net.critic.parameters(), strict=True))
    ppo.update(_bandit_rollout(ppo, rng))
    assert not np.array_equal(ppo.actor_arrays()["w0"], actor0["w0"])


def test_learning_rate_anneals_linearly_to_zero() -> None:
    from confront.learning.ppo import learning_rate

    c = PPOConfig(lr=2e-3, anneal_lr=True, hidden=8, team_critic=False)
    assert learning_rate(c, 0.0) == 2e-3 and learning_rate(c, 0.25) == pytest.approx(1.5e-3)
    assert learning_rate(c, 1.0) == 0.0 and learning_rate(c, 1.3) == 0.0  # rounds past the end: no step
    assert learning_rate(PPOConfig(lr=2e-3), 0.9) == 2e-3  # off by default
    ppo = PPO(2, (2, 3), c, seed=0)
    ppo.set_progress(0.75)
    assert [g["lr"] for g in ppo.opt.param_groups] == [pytest.approx(5e-4)]
    before = {k: v.copy() for k, v in ppo.state_dict().items() if k.startswith("net.actor")}
    ppo.set_progress(1.0)
    ppo.update(_bandit_rollout(ppo, np.random.default_rng(0)))
    for k, v in before.items():  # a zero step leaves the weights
        np.testing.assert_array_equal(v, ppo.state_dict()[k], err_msg=k)


@pytest.mark.parametrize(("var", "given", "want"), [
    ("GOMP_SPINCOUNT", {}, "3000"), ("GOMP_SPINCOUNT", {"OMP_WAIT_POLICY": "ACTIVE"}, "unset"),
    ("GOMP_SPINCOUNT", {"GOMP_SPINCOUNT": "10"}, "10"),
    ("OPENBLAS_THREAD_TIMEOUT", {}, "4"), ("OPENBLAS_THREAD_TIMEOUT", {"OPENBLAS_THREAD_TIMEOUT": "20"}, "20")])
def test_thread_pools_spin_briefly_unless_the_user_says_otherwise(var: str, given: dict[str, str], want: str) -> None:
    """torch's OpenMP workers and NumPy's OpenBLAS workers stop busy-waiting soon (confront/__init__.py)."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "OPENBLAS_THREAD_TIMEOUT")} | given
    code = f"import confront, os; print(os.environ.get({var!r}, 'unset'))"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == want


def test_skill_prior_sets_the_untrained_policys_probabilities() -> None:
    from confront.arena.tank import TankSpace
    from confront.train.ppo_model import skill_logits

    space = TankSpace(leads=("none", "linear", "circular", "gf"), surf=True)
    logits = skill_logits(space, 3.0)
    # surf ends the distance head, power 2 (the brain's, at 400 px) is the fire head's third, gf ends the lead head
    assert logits.tolist() == [0] * 5 + [3] + [0] * 5 + [0, 0, 3, 0] + [0] * 7 + [3]
    assert not skill_logits(TankSpace(), 3.0).any()  # no skill: no prior
    obs = np.random.default_rng(0).normal(size=(4096, space.n_features)).astype(np.float32)
    ppo = PPO(space.n_features, space.dims, PPOConfig(hidden=32), seed=1, init_logits=logits)
    _, heads, _ = ppo.act(obs)
    surf, gf = (heads[:, 0] == 5).mean(), (heads[:, 4] == 3).mean()
    want = math.exp(3) / (math.exp(3) + 5), math.exp(3) / (math.exp(3) + 3)  # 0.801, 0.870 (other logits ~0)
    assert abs(surf - want[0]) < 0.03 and abs(gf - want[1]) < 0.03
    assert abs((heads[:, 2] == 2).mean() - want[1]) < 0.03  # power 2 of four powers, as gf of four leads
    assert abs((heads[:, 3] == 0).mean() - 0.25) < 0.03  # the target head untouched
    plain = PPO(space.n_features, space.dims, PPOConfig(hidden=32), seed=1)
    same = PPO(space.n_features, space.dims, PPOConfig(hidden=32), seed=1, init_logits=skill_logits(space, 0.0))
    for a, b in zip(plain.state_dict().values(), same.state_dict().values(), strict=True):
        np.testing.assert_array_equal(a, b)  # a zero prior changes no bit
    with pytest.raises(ValueError, match="init_logits"):
        PPO(space.n_features, space.dims, PPOConfig(hidden=32), init_logits=np.full(sum(space.dims), np.nan))
