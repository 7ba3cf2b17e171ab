"""Exported robots: the Java inference decides exactly like the Python policy, and plays in the engine."""

from __future__ import annotations

import math
import subprocess
import zipfile

import numpy as np
import pytest

from confront.arena.observe import N_STATES, ObservationConfig
from confront.engine.battle import BattleSpec
from confront.engine.bridge import Observation, Scan, format_observation, parse_observation
from confront.engine.bridged import BRIDGE_BOT, run_bridged_battle
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.java_build import compile_java
from confront.engine.runner import EngineOptions, run_battle

HELLO = {"name": "me", "team": "", "width": 800.0, "height": 600.0}


def _parse(line: str) -> Observation:
    """An observation line on the connection of its own round (the bridge checks the round)."""
    return parse_observation(line, {**HELLO, "round": int(line.split("\t")[0].split(" ")[1])})


def _q_policy(seed: int = 0) -> ExportedPolicy:
    return ExportedPolicy("qtable", q=np.random.default_rng(seed).normal(size=(320, 4)))


def _mlp_policy(seed: int = 1) -> ExportedPolicy:
    rng = np.random.default_rng(seed)
    shapes = [(16, 9), (4, 16)]
    return ExportedPolicy(
        "mlp", weights=tuple(rng.normal(size=s) for s in shapes), biases=tuple(rng.normal(size=s[0]) for s in shapes),
        observation=ObservationConfig(include_position=True), step_turns=4,
    )


def test_q_policy_hand_computed_state() -> None:
    q = np.zeros((320, 4))
    # enemy straight ahead (rel bin 0) of a tank heading 100 deg (heading bin 1), 230 px away (bin 4 of 50 px)
    q[(0 * 4 + 1) * 20 + 4] = [0.0, 0.0, 5.0, 1.0]
    pol = ExportedPolicy("qtable", q=q)
    h = math.radians(100)
    me = Observation("me", (), 0, 1, 400.0, 300.0, h, 0.0, 0.0, 0.0, 100.0, 0.0, 1, 0.0, 800.0, 600.0,
                     (Scan("e", 0, False, 0.0, 230.0, 0.0, 0.0, 50.0,
                           400.0 + 230 * math.sin(h), 300.0 + 230 * math.cos(h)),))
    assert pol.act(me) == 2
    ahead, turn, gun, radar, fire = pol(me)
    assert (ahead, turn) == (0.0, math.radians(45))
    assert gun == pytest.approx(h) and fire == 0.0  # gun at 0 must turn to the bearing first
    assert radar == pytest.approx(h + math.radians(20))


def test_bad_policies_rejected() -> None:
    with pytest.raises(ValueError, match="q must be"):
        ExportedPolicy("qtable", q=np.zeros((10, 4)))
    with pytest.raises(ValueError, match="kind"):
        ExportedPolicy("tree")
    with pytest.raises(ValueError, match="chain"):
        ExportedPolicy("mlp", weights=(np.zeros((4, 5)),), biases=(np.zeros(4),))


def _random_observations(n: int, seed: int) -> list[str]:
    rng = np.random.default_rng(seed)
    lines = []
    for i in range(n):
        scans = tuple(
            Scan(f"e{k}", i, bool(k == 2), 0.0, 0.0, 0.0, 0.0, float(rng.uniform(0, 100)),
                 float(rng.uniform(18, 782)), float(rng.uniform(18, 582)))
            for k in range(int(rng.integers(0, 4)))
        )
        obs = Observation("me", (), 0, i + 1, float(rng.uniform(18, 782)), float(rng.uniform(18, 582)),
                          float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(0, 2 * math.pi)),
                          float(rng.uniform(0, 2 * math.pi)), 0.0, float(rng.uniform(0, 100)),
                          float(rng.choice([0.0, 0.5])), len(scans), 0.0, 800.0, 600.0, scans)
        lines.append(format_observation(obs))
    return lines


def _java_decisions(install, policy: ExportedPolicy, lines: list[str], tmp_path) -> list[list[float]]:
    classes = compile_java(install)
    pfile = tmp_path / "policy.txt"
    pfile.write_text(policy.to_text())
    proc = subprocess.run([install.java, "-cp", str(classes), "confront.PolicyCheck", str(pfile), "800", "600"],
                          input="\n".join(lines) + "\n", capture_output=True, text=True, check=True, timeout=60)
    return [[float(v) for v in ln.split()] for ln in proc.stdout.splitlines()]


def _compare(policy: ExportedPolicy, lines: list[str], java: list[list[float]]) -> None:
    assert len(java) == len(lines)
    for line, (a, gun, radar, fire, state) in zip(lines, java, strict=True):
        obs = _parse(line)
        assert policy.act(obs) == int(a), line
        assert policy.state_and_features(obs)[0] == int(state), line
        pg, pr, pf = policy.gun_radar(obs)
        assert (math.isnan(pg) and math.isnan(gun)) or gun == pytest.approx(pg, abs=1e-12)
        assert radar == pytest.approx(pr, abs=1e-12) and fire == pf


def _sim_observations(steps: int = 40) -> tuple[list[str], list[tuple[int, float, float, float]]]:
    """Every living tank's view in 4v4 simulator battles (own state, and the enemies it knows: its scan
    memory) as bridge observation lines, with the simulator's discrete state and the commands its compiled
    controller gave that tank for the turn (gun, radar, fire)."""
    from confront.arena.smdp import SMDPConfig, TeamBattleEnv

    env = TeamBattleEnv("4v4", n_battles=2, seed=3, opponents="td", config=SMDPConfig(turns_per_step=1))
    env.reset()
    rng = np.random.default_rng(4)
    lines: list[str] = []
    expected: list[tuple[int, float, float, float]] = []
    s, team = env.arena.state, env.team_ids()
    for _ in range(steps):
        before = [(b, i) for b in range(2) for i in range(8) if s.alive[b, i]]
        _, disc, _ = env.observe()
        views = []
        for b, i in before:
            scans = tuple(Scan(f"r{j}", int(s.scan_time[b, i, j]), False, 0.0, 0.0, 0.0, 0.0,
                               float(env._memory[b, 2, i, j]), float(env._memory[b, 0, i, j]),
                               float(env._memory[b, 1, i, j]))
                          for j in range(8) if team[j] != team[i] and s.alive[b, j] and s.scan_time[b, i, j] >= 0)
            views.append(Observation(f"r{i}", (), 0, int(s.time[b]) + 1, float(s.x[b, i]), float(s.y[b, i]),
                                     float(s.heading[b, i]), float(s.gun_heading[b, i]), float(s.radar_heading[b, i]),
                                     float(s.velocity[b, i]), float(s.energy[b, i]), float(s.gun_heat[b, i]), 7, 0.0,
                                     800.0, 600.0, scans))
        env.step(rng.integers(0, 4, size=(2, 8)))
        for (b, i), obs in zip(before, views, strict=True):
            lines.append(format_observation(obs))
            expected.append((int(disc[b, i]), *(float(v) for v in env._cmd[b, i, 2:5])))
    return lines, expected


def test_export_twin_equals_the_simulator_on_its_own_observations() -> None:
    # the simulator's observation, target and controller, fed the same knowledge, decide like the exported twin
    policy = _q_policy(6)
    lines, expected = _sim_observations()
    unknown = stale = fired = 0
    for line, (state, gun, radar, fire) in zip(lines, expected, strict=True):
        obs = _parse(line)
        assert policy.state_and_features(obs)[0] == state, line
        pg, pr, pf = policy.gun_radar(obs)
        assert (math.isnan(pg) and math.isnan(gun)) or gun == pytest.approx(pg, abs=1e-12), line
        assert radar == pytest.approx(pr, abs=1e-12) and fire == pf, line
        unknown += not obs.enemies()
        stale += any(s.time < obs.turn - 1 for s in obs.enemies())
        fired += fire > 0
    # the cases that matter occur: no enemy known yet, stale scans, shots
    assert unknown > 0 and stale > 0 and fired > 0


@pytest.mark.engine
def test_java_inference_equals_the_simulator_on_its_observations(install, tmp_path) -> None:
    policy = _q_policy(6)
    lines, expected = _sim_observations()
    java = _java_decisions(install, policy, lines, tmp_path)
    _compare(policy, lines, java)
    for (state, gun, radar, fire), (_, jg, jr, jf, js) in zip(expected, java, strict=True):
        assert int(js) == state and jf == fire and jr == pytest.approx(radar, abs=1e-12)
        assert (math.isnan(gun) and math.isnan(jg)) or jg == pytest.approx(gun, abs=1e-12)


def _tanh_mlp_policy(seed: int = 2) -> ExportedPolicy:
    """An MLP with tanh hidden layers, as an SB3 network is exported."""
    from dataclasses import replace

    return replace(_mlp_policy(seed), hidden_activation="tanh")


@pytest.mark.engine
@pytest.mark.parametrize("make", [_q_policy, _mlp_policy, _tanh_mlp_policy], ids=["qtable", "mlp", "tanh-mlp"])
def test_java_inference_equals_python_on_random_observations(install, tmp_path, make) -> None:
    policy = make()
    lines = _random_observations(400, seed=5)
    java = _java_decisions(install, policy, lines, tmp_path)
    _compare(policy, lines, java)
    assert len({int(r[0]) for r in java}) > 1  # the test covers more than one action


@pytest.mark.engine
def test_exported_robot_matches_recorded_observations_and_plays(install, tmp_path) -> None:
    policy = _q_policy(3)
    recorded: list[str] = []

    def recording(obs: Observation):
        recorded.append(format_observation(obs))
        return policy(obs)

    bridged = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SpinBot"), rounds=1), recording)
    assert bridged.ok and len(recorded) > 100
    _compare(policy, recorded, _java_decisions(install, policy, recorded, tmp_path))

    jar = export_robot(policy, tmp_path / "out" / "policybot.jar", install)
    names = set(zipfile.ZipFile(jar).namelist())
    assert {"confront/PolicyBot.class", "confront/PolicyModel.class", "confront/PolicyData.class",
            "confront/policy.txt", "confront/PolicyBot.properties"} <= names
    folder = export_robot(policy, tmp_path / "robots", install)
    for robot, extra in (("confront.PolicyBot 1.0", jar), ("confront.PolicyBot*", folder)):
        run = run_battle(BattleSpec((robot, "SpinBot"), rounds=2), EngineOptions(seed=2), extra_robots=[extra])
        assert not [r for r in run.summary["robot_reports"] if "policy-load-failed" in r], run.summary
        assert not run.errors
        me = next(r for r in run.results.contestants if r.name.startswith("confront.PolicyBot"))
        assert me.bullet_dmg > 0  # it aims and hits with its own controller
        assert run.results.rounds == 2


@pytest.mark.engine
def test_evaluate_exported_policy_in_engine(install) -> None:
    from confront.engine.evaluate import evaluate_policy

    res, ratio = evaluate_policy(_q_policy(4), "1v1", "SittingDuck", rounds=1, seed=1)
    ours = next(r for r in res.contestants if r.name.startswith("confront.PolicyBot"))
    assert ratio == pytest.approx(ours.total / sum(r.total for r in res.contestants))
    assert ours.firsts == 1 and ratio > 0.5  # SittingDuck never shoots
    with pytest.raises(ValueError, match="mode"):
        evaluate_policy(_q_policy(4), "1v1", "SittingDuck", mode="jpype")


@pytest.mark.engine
@pytest.mark.parametrize("scenario", ["1v1", "4v4"])
def test_evaluate_against_an_exported_opponent_policy(install, scenario: str) -> None:
    """Both sides exported PolicyBots (one class in two jars), each with its own policy: only one side fires."""
    from dataclasses import replace

    from confront.arena.control import ControlConfig
    from confront.engine.evaluate import evaluate_policy

    fires, holds = _q_policy(4), replace(_q_policy(4), control=ControlConfig(fire=False))
    for ours, theirs in ((fires, holds), (holds, fires)):
        res, ratio = evaluate_policy(ours, scenario, "td", rounds=2, seed=1, opponent_policy=theirs)
        mine = next(r for r in res.contestants if r.name.startswith(("confront.PolicyBot 1.0", "confrontteams.Ours")))
        other = next(r for r in res.contestants if r is not mine)
        assert ratio == pytest.approx(mine.total / (mine.total + other.total))
        assert (mine.bullet_dmg > 0, other.bullet_dmg > 0) == (ours.control.fire, theirs.control.fire)
    with pytest.raises(ValueError, match="export mode"):
        evaluate_policy(fires, scenario, "td", mode="bridge", opponent_policy=holds)


def _trained_like(kind: str):
    from confront.learning.dmnn import DMNN, DMNNParams
    from confront.learning.tabular import TabularQ

    if kind == "tabular":
        learner = TabularQ()
        learner.q = np.random.default_rng(7).normal(size=(320, 4))
        return learner
    if kind == "dmnn_features":
        return DMNN(DMNNParams(n_inputs=7, hidden=(12,), observation="features", q_scale=3.0, init_seed=2))
    return DMNN(DMNNParams(n_inputs=320, hidden=(8,), observation="discrete", output="bipolar", init_seed=3))


@pytest.mark.parametrize("kind", ["tabular", "dmnn_features", "dmnn_discrete"])
def test_policy_from_learner_decides_like_the_learner(kind: str) -> None:
    learner = _trained_like(kind)
    policy = ExportedPolicy.from_learner(learner)
    rng = np.random.default_rng(0)
    acts = set()
    for line in _random_observations(150, seed=11):
        obs = _parse(line)
        x = policy.learner_observation(obs, learner.observation)
        q = learner.q_values(x)[0] if hasattr(learner, "q_values") else learner.q[x[0]]
        scale = getattr(learner.params, "q_scale", 1.0)
        np.testing.assert_allclose(policy.values(obs) * scale, q, rtol=1e-12, atol=1e-12)
        a = policy.act(obs)
        assert a == int(learner.act(x, rng, explore=False)[0])
        acts.add(a)
    assert len(acts) > 1


@pytest.mark.engine
def test_java_inference_equals_python_for_onehot_dmnn(install, tmp_path) -> None:
    policy = ExportedPolicy.from_learner(_trained_like("dmnn_discrete"))
    lines = _random_observations(200, seed=9)
    _compare(policy, lines, _java_decisions(install, policy, lines, tmp_path))


@pytest.mark.parametrize("cfg", [ObservationConfig(), ObservationConfig(include_position=True),
                                 ObservationConfig(max_distance=500.0)])
def test_one_robot_kernel_equals_the_batched_state_and_features(cfg: ObservationConfig) -> None:
    """The twin's fast path (the simulator's one-robot kernel) gives the batched functions' state and float32
    features exactly: no enemy, team-mates only, equally near enemies, headings beyond 2 pi and on bin edges."""
    rng = np.random.default_rng(11)
    twin = ExportedPolicy("qtable", q=np.zeros((320, 4)), observation=cfg)
    cases = 0
    for _ in range(600):
        x, y = rng.uniform(18, 782), rng.uniform(18, 582)
        scans = tuple(Scan(f"r{k}", 1, bool(rng.random() < 0.25), 0.0, 0.0, 0.0, 0.0, rng.uniform(0, 120),
                           rng.uniform(0, 800), rng.uniform(0, 600)) for k in range(rng.integers(0, 6)))
        if rng.random() < 0.2:  # two enemies at the same distance: the first one is the target
            scans = (Scan("a", 1, False, 0, 0, 0, 0, 50.0, x + 30, y), Scan("b", 1, False, 0, 0, 0, 0, 40.0, x - 30, y))
        heading = rng.choice([rng.uniform(-7, 14), 0.0, math.pi / 2, math.pi, 2 * math.pi, 1.5 * math.pi])
        obs = Observation("me", (), 0, 1, x, y, heading, 0.0, 0.0, 0.0, rng.uniform(0, 100), 0.0, len(scans), 0.0,
                          800.0, 600.0, scans)
        (s1, f1), (s2, f2) = twin.state_and_features(obs), twin.state_and_features_batched(obs)
        assert s1 == s2 and f1.dtype == f2.dtype == np.float32 and np.array_equal(f1, f2), obs
        cases += 1
    assert cases == 600


def test_java_random_ties_draw_among_the_maxima(install, tmp_path) -> None:
    """ties="random": Java picks one of the maxima at random (both halves of the dodge's pairs occur), never
    another move; "first" stays the first maximum."""
    rel = np.arange(N_STATES) // 80
    q = np.zeros((N_STATES, 4))
    side = (rel == 1) | (rel == 3)
    q[side, :2], q[~side, 2:] = 1.0, 1.0
    policy = ExportedPolicy("qtable", q=q, ties="random")
    lines = _random_observations(20, 7) * 20
    java = _java_decisions(install, policy, lines, tmp_path)
    picks: dict[int, set[int]] = {}
    for line, (a, *_rest, state) in zip(lines, java, strict=True):
        best = set(np.flatnonzero(q[int(state)] == 1.0).tolist())
        assert int(a) in best and policy.act(_parse(line), np.random.default_rng(0)) in best
        picks.setdefault(lines.index(line), set()).add(int(a))
    assert all(len(p) == 2 for p in picks.values())  # 20 draws each: both maxima (a miss has p = 2^-19)
    first = _java_decisions(install, ExportedPolicy("qtable", q=q), lines[:20], tmp_path)
    assert [int(r[0]) for r in first] == [int(np.argmax(q[int(r[4])])) for r in first]
