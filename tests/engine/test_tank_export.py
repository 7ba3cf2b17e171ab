"""The exported tank robot: its Java view, greedy and sampled actions and controller equal the Python twin's,
the twin's equal the simulator's on recorded battles, and the exported robot plays in the real engine."""

from __future__ import annotations

import json
import math
import subprocess
import tempfile
import zipfile
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest

from confront.arena.control import ControlConfig
from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.tank import TankSpace
from confront.checkpoint import CheckpointError
from confront.engine.java_build import compile_java
from confront.engine.tank_export import (
    TankPolicy,
    body_turn,
    export_tank_robot,
    is_tank_run,
    load_tank_policy,
    robot_control,
    robot_target,
    robot_view,
    sample_heads,
    turn_rate,
)

SPACE = TankSpace()
FIELD = (800.0, 600.0)


def _env(turns: int, seed: int) -> TeamBattleEnv:
    return TeamBattleEnv("4v4", n_battles=2, seed=seed, opponents="SpinBot",
                         config=SMDPConfig(turns_per_step=turns, tank=SPACE, reward="score"))


def _knowledge(env: TeamBattleEnv, b: int, i: int) -> dict:
    """What robot i of battle b knows, as TankBot holds it: own state, counts, known enemies (robot order)
    from its scan memory, living mates as their last team messages said (the env's one-turn-old copy)."""
    s, team = env.arena.state, env.team_ids()
    r = len(team)
    enemies = [j for j in range(r) if team[j] != team[i] and s.alive[b, j] and s.scan_time[b, i, j] >= 0]
    mates = [j for j in range(r) if j != i and team[j] == team[i] and s.alive[b, j] and env._mates_ok[b]]
    return {
        "own": [float(v) for v in (s.x[b, i], s.y[b, i], s.heading[b, i], s.velocity[b, i], s.energy[b, i],
                                   s.gun_heat[b, i])],
        "guns": [float(s.gun_heading[b, i]), float(s.radar_heading[b, i])],
        "counts": [int(sum(s.alive[b, j] for j in range(r) if team[j] != team[i])), int(sum(team != team[i])),
                   sum(1 for j in range(r) if j != i and team[j] == team[i] and s.alive[b, j]),
                   int(sum(team == team[i]) - 1)],
        "ids": enemies,
        "enemies": [[*(float(v) for v in env._memory[b, :6, i, j]), float(s.scan_time[b, i, j]),
                     float(env._memory[b, 7, i, j])] for j in enemies],
        "mates": [[float(v) for v in env._mates[b, :, j]] for j in mates],
        "time": float(s.time[b]),
    }


@pytest.fixture(scope="module")
def views() -> list[tuple[dict, np.ndarray, np.ndarray]]:
    """(knowledge, the simulator's tank view (float32), its enemy slots as robot ids) of every living robot at
    every decision of two 4v4 battles against SpinBot teams with random tank actions (T = 5)."""
    env = _env(5, seed=11)
    _, feats = env.reset()
    rng = np.random.default_rng(12)
    out = []
    for step in range(140):
        alive = env.arena.state.alive
        for b in range(2):
            for i in range(8):
                if alive[b, i]:
                    out.append((_knowledge(env, b, i), feats[b, i].copy(), env.slots[b, i].copy()))
        if step < 139:
            feats = env.step(rng.integers(0, env.n_actions, size=(2, 8))).features
    return out


@pytest.fixture(scope="module")
def recorded_turns() -> tuple[list[tuple], list[tuple[float, ...]]]:
    """(knowledge, step's fire power, chosen enemy row (-1 none), the action's body turn, its lead, the
    simulator's (body turn, gun, radar, fire)) of every living learning tank in turns of 4v4 battles with
    random tank actions held for one turn (T = 1, so every turn starts a step); and
    every scan's (seen before, previous heading, previous scan time, heading, time, the simulator's turn rate)."""
    env = _env(1, seed=21)
    env.reset()
    rng = np.random.default_rng(22)
    out, rates = [], []
    for _ in range(300):
        a = rng.integers(0, env.n_actions, size=(2, 8))
        s = env.arena.state
        before = [(b, i, _knowledge(env, b, i), env.slots[b, i].copy()) for b in range(2) for i in range(4)
                  if s.alive[b, i] and not s.done[b]]
        memory = env._memory.copy()
        env.step(a)
        for b, i, j in zip(*np.nonzero(s.scanned), strict=True):
            if not s.done[b]:
                rates.append((float(memory[b, 6, i, j]), float(memory[b, 3, i, j]), float(memory[b, 8, i, j]),
                              float(s.heading[b, j]), float(s.time[b]), float(env._memory[b, 7, i, j])))
        for b, i, k, slots in before:
            _, turn, power, slot = (float(v) for v in _table()[a[b, i]][:4])
            robot = slots[int(slot)]
            chosen = k["ids"].index(robot) if robot >= 0 and robot in k["ids"] else -1
            lead = SPACE.leads[int(np.unravel_index(a[b, i], SPACE.dims)[-1])]
            out.append((k, power, chosen, turn, lead, tuple(float(v) for v in env._cmd[b, i, 1:5])))
    return out, rates


@pytest.fixture(scope="module")
def controls(recorded_turns) -> list[tuple]:
    """The controller's recorded turns (see recorded_turns)."""
    return recorded_turns[0]


@pytest.fixture(scope="module")
def rates(recorded_turns) -> list[tuple[float, ...]]:
    """The recorded scans' turn rates (see recorded_turns)."""
    return recorded_turns[1]


def _table() -> np.ndarray:
    from confront.arena.tank import action_table

    return action_table(SPACE)


def _policy(seed: int, hidden: int = 24, space: TankSpace = SPACE) -> TankPolicy:
    rng = np.random.default_rng(seed)
    sizes = [space.n_features, hidden, hidden, sum(space.dims)]
    return TankPolicy(tuple(rng.normal(0, 1.0, size=(o, i)) for i, o in zip(sizes, sizes[1:], strict=False)),
                      tuple(rng.normal(0, 0.5, size=o) for o in sizes[1:]), space, ControlConfig(), 5)


# -- the Python twin against the simulator --------------------------------------------------------------


def test_twin_view_equals_the_simulator(views) -> None:
    covered = {"none": 0, "full": 0, "stale": 0, "drop": 0, "mates": 0, "dead": 0}
    for k, feats, slots in views:
        v, sl = robot_view(k["own"], k["counts"], k["enemies"], k["mates"], k["time"], *FIELD, SPACE)
        np.testing.assert_array_equal(v.astype(np.float32), feats)
        assert [k["ids"][j] if j >= 0 else -1 for j in sl] == list(slots)
        covered["none"] += not k["enemies"]
        covered["full"] += len(k["enemies"]) == 4
        covered["stale"] += any(e[6] < k["time"] for e in k["enemies"])
        covered["drop"] += any(e[5] > 0 for e in k["enemies"])
        covered["mates"] += len(k["mates"]) > 0
        covered["dead"] += k["counts"][0] < k["counts"][1] or k["counts"][2] < k["counts"][3]
    assert all(n > 0 for n in covered.values()), covered


def test_twin_controller_equals_the_simulator(controls) -> None:
    shots = led = none = held = chosen = 0
    for k, power, c, turn, lead, (body, gun, radar, fire) in controls:
        x, y = k["own"][:2]
        tgt = robot_target(x, y, k["enemies"], c)
        assert body_turn(SPACE, x, y, k["own"][2], k["enemies"], tgt, turn) == pytest.approx(body, abs=1e-12), k
        g, r, f = robot_control(ControlConfig(), lead, x, y, *k["guns"], k["own"][5], k["own"][4],
                                k["enemies"], tgt, power, k["time"], *FIELD)
        assert (math.isnan(g) and math.isnan(gun)) or g == pytest.approx(gun, abs=1e-12), k
        assert r == pytest.approx(radar, abs=1e-12) and f == fire, k
        shots += fire > 0
        none += tgt < 0
        held += power < 0 and tgt >= 0
        chosen += c >= 0 and c != robot_target(x, y, k["enemies"], -1)
        led += tgt >= 0 and lead == "circular" and k["enemies"][tgt][4] != 0 and k["enemies"][tgt][7] != 0
    assert min(shots, led, none, held, chosen) > 0, (shots, led, none, held, chosen)


def test_twin_turn_rate_equals_the_simulator(rates) -> None:
    turning = 0
    for seen, prev_h, prev_t, h, time, rate in rates:
        prev = [0.0, 0.0, 0.0, prev_h, 0.0, 0.0, prev_t, 0.0] if seen else None
        assert turn_rate(prev, h, time) == pytest.approx(rate, abs=1e-15)
        turning += rate != 0
    assert turning > 0 and any(seen and time - prev_t > 1 for seen, _, prev_t, _, time, _ in rates)


# -- Java against the twin ----------------------------------------------------------------------------


def _java(install, policy: TankPolicy, requests: list[str], tmp_path: Path) -> list[str]:
    classes = compile_java(install)
    pfile = tmp_path / "tank_policy.txt"
    pfile.write_text(policy.to_text())
    proc = subprocess.run([install.java, "-cp", str(classes), "confront.TankCheck", str(pfile)],
                          input="\n".join(requests) + "\n", capture_output=True, text=True, check=True, timeout=60)
    out = proc.stdout.splitlines()
    assert len(out) == len(requests)
    return out


def _nums(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def _rows(rows) -> str:
    return "|".join(_nums(r) for r in rows)


@pytest.mark.engine
def test_java_view_equals_python(install, views, tmp_path) -> None:
    reqs = [f"V\t{_nums(k['own'] + k['counts'] + [k['time'], *FIELD])}\t{_rows(k['enemies'])}\t{_rows(k['mates'])}"
            for k, _, _ in views]
    worst = 0.0
    for line, (k, feats, _) in zip(_java(install, _policy(0), reqs, tmp_path), views, strict=True):
        vals, slots = line.split("|")
        jv = np.array([float(x) for x in vals.split()])
        v, sl = robot_view(k["own"], k["counts"], k["enemies"], k["mates"], k["time"], *FIELD, SPACE)
        worst = max(worst, float(np.abs(jv - v).max()), float(np.abs(jv.astype(np.float32) - feats).max()))
        assert [int(s) for s in slots.split()] == list(sl)
    assert worst <= 1e-15, worst  # 1.1e-16 (sin / cos); 1.7e-15 before the simulator took Math.atan2 / hypot


@pytest.mark.engine
def test_java_greedy_actions_equal_python(install, views, tmp_path) -> None:
    rng = np.random.default_rng(3)
    inputs = [f for _, f, _ in views] + [rng.uniform(-1, 1, SPACE.n_features) for _ in range(200)]
    for seed in (1, 2):
        policy = _policy(seed)
        out = _java(install, policy, [f"A\t{_nums(v)}" for v in inputs], tmp_path)
        heads = set()
        for line, v in zip(out, inputs, strict=True):
            a, logits = line.split("|")
            np.testing.assert_allclose([float(z) for z in logits.split()], policy.logits(v), rtol=0, atol=1e-9)
            assert int(a) == policy.act(v)
            heads.add(policy.decode(int(a)))
        assert all(len({h[i] for h in heads}) > 1 for i in range(5)), heads  # several choices per head


def test_sample_heads_hand_computed_and_its_frequencies() -> None:
    # head 0: logits (0, ln 3) -> p = (1/4, 3/4); head 1: (0, 0, 0) -> 1/3 each; joint = h0 * 3 + h1
    z = np.array([0.0, math.log(3.0), 5.0, 5.0, 5.0])
    assert sample_heads(z, (2, 3), [0.2, 0.5]) == 0 * 3 + 1
    assert sample_heads(z, (2, 3), [0.3, 0.99]) == 1 * 3 + 2
    assert sample_heads(z, (2, 3), [0.249, 0.0]) == 0 and sample_heads(z, (2, 3), [0.251, 0.34]) == 3 + 1
    with pytest.raises(ValueError, match="one draw per head"):
        sample_heads(z, (2, 3), [0.5])
    p = _policy(8)
    sampled = TankPolicy(p.weights, p.biases, p.space, p.control, p.step_turns, play="sampled")
    view = np.random.default_rng(1).uniform(-1, 1, SPACE.n_features)
    rng = np.random.default_rng(2)
    n = 20000
    heads = np.array([np.unravel_index(sampled.act(view, rng.random(5)), SPACE.dims) for _ in range(n)])
    zl, off = sampled.logits(view), 0
    for h, d in enumerate(SPACE.dims):
        want = np.exp(zl[off:off + d] - zl[off:off + d].max())
        want /= want.sum()
        got = np.bincount(heads[:, h], minlength=d) / n
        assert np.abs(got - want).max() < 4 * math.sqrt(0.25 / n), (h, got, want)  # 4 standard errors
        off += d
    assert "play sampled" in sampled.to_text() and "play" not in p.to_text()
    with pytest.raises(ValueError, match="uniform draws"):
        sampled.act(view)
    with pytest.raises(ValueError, match="play must be one of greedy, sampled"):
        TankPolicy(p.weights, p.biases, play="boltzmann")


@pytest.mark.engine
def test_java_sampled_actions_equal_python(install, views, tmp_path) -> None:
    rng = np.random.default_rng(4)
    policy = _policy(3)
    policy = TankPolicy(policy.weights, policy.biases, policy.space, policy.control, policy.step_turns, "sampled")
    inputs = [(f, rng.random(5)) for _, f, _ in views[:300]] + [(rng.uniform(-1, 1, SPACE.n_features),
                                                                  rng.random(5)) for _ in range(300)]
    out = _java(install, policy, [f"S\t{_nums(v)}\t{_nums(u)}" for v, u in inputs], tmp_path)
    acts = [int(line) for line in out]
    assert acts == [policy.act(v, u) for v, u in inputs]
    assert len(set(acts)) > 100  # draws, not one greedy answer


@pytest.mark.engine
@pytest.mark.parametrize("lead", ["none", "linear", "circular"])
def test_java_controller_equals_python(install, controls, tmp_path, lead) -> None:
    code = {"none": 0, "linear": 1, "circular": 2}[lead]
    reqs = [f"C\t{_nums(k['own'][:3] + k['guns'] + [k['own'][5], k['own'][4], p, c, turn, code, k['time'], *FIELD])}"
            f"\t{_rows(k['enemies'])}" for k, p, c, turn, _, _ in controls]
    out = _java(install, _policy(0), reqs, tmp_path)
    for line, (k, p, c, turn, sim_lead, (sim_body, *sim)) in zip(out, controls, strict=True):
        gun, radar, fire, tgt, body = (float(x) for x in line.split())
        x, y = k["own"][:2]
        assert int(tgt) == robot_target(x, y, k["enemies"], c)
        assert abs(body - body_turn(SPACE, x, y, k["own"][2], k["enemies"], int(tgt), turn)) <= 1e-9, line
        assert abs(body - sim_body) <= 1e-9, line  # the lead does not change the body turn
        g, r, f = robot_control(ControlConfig(), lead, x, y, *k["guns"], k["own"][5], k["own"][4], k["enemies"],
                                int(tgt), p, k["time"], *FIELD)
        assert (math.isnan(g) and math.isnan(gun)) or abs(gun - g) <= 1e-9, line
        assert abs(radar - r) <= 1e-9 and fire == f, line
        if lead == sim_lead:
            assert (math.isnan(sim[0]) and math.isnan(gun)) or abs(gun - sim[0]) <= 1e-9, line
            assert abs(radar - sim[1]) <= 1e-9 and fire == sim[2], line


@pytest.mark.engine
def test_java_turn_rate_equals_the_simulator(install, rates, tmp_path) -> None:
    out = _java(install, _policy(0), [f"R\t{_nums(r[:5])}" for r in rates], tmp_path)
    assert max(abs(float(line) - r[5]) for line, r in zip(out, rates, strict=True)) <= 1e-15


# -- the policy file and the run folder -----------------------------------------------------------------


def test_policy_from_state_and_checks() -> None:
    p = _policy(4)
    torch_names = {}
    for i, (w, b) in enumerate(zip(p.weights, p.biases, strict=True)):
        torch_names[f"actor.{2 * i}.weight"], torch_names[f"actor.{2 * i}.bias"] = w, b
    torch_names["critic.0.weight"] = np.zeros((3, 3))
    q = TankPolicy.from_state(torch_names, SPACE, step_turns=5)
    view = np.random.default_rng(0).uniform(-1, 1, SPACE.n_features)
    assert q.act(view) == p.act(view)
    d, t, power, k, lead = p.decode(p.act(view))
    assert d in SPACE.distances and power in (-1.0, 1.0, 2.0, 3.0) and 0 <= k < SPACE.enemy_slots
    assert lead in SPACE.leads
    text = p.to_text()
    assert text.startswith("confront-tank 1\n") and f"matrix w2 {sum(SPACE.dims)} 24" in text
    assert f"leads {' '.join(SPACE.leads)}" in text
    with pytest.raises(ValueError, match="chain"):
        TankPolicy((np.zeros((4, 5)),), (np.zeros(4),))
    with pytest.raises(ValueError, match="logits"):
        TankPolicy((np.zeros((4, SPACE.n_features)),), (np.zeros(4),))
    with pytest.raises(ValueError, match="actor"):
        TankPolicy.from_state({"x": np.zeros(2)})


def _write_run(run: Path, policy: TankPolicy) -> None:
    model = run / "model"
    model.mkdir(parents=True)
    (model / "model.json").write_text(json.dumps({"kind": "ppo"}))
    np.savez(model / "actor.npz", **{f"{n}{i}": a for i, (w, b) in enumerate(zip(policy.weights, policy.biases,
                                                                                  strict=True))
                                     for n, a in (("w", w), ("b", b))})
    (model / "tank.json").write_text(json.dumps({
        **asdict(policy.space), "step_turns": policy.step_turns,
        "control": {"radar_overshoot": policy.control.radar_overshoot, "aim_tolerance": 0.04}}))


def test_run_folder_loads(tmp_path) -> None:
    space = TankSpace(distances=(-100.0, 100.0), enemy_slots=1, mate_slots=0)
    p = _policy(5, hidden=8, space=space)
    _write_run(tmp_path / "run", p)
    assert is_tank_run(tmp_path / "run") and not is_tank_run(tmp_path)
    q = load_tank_policy(tmp_path / "run")
    assert q.space == space and q.step_turns == 5 and q.control.aim_tolerance == 0.04
    assert q.to_text().split("aim_tolerance")[0] == p.to_text().split("aim_tolerance")[0]
    tank = json.loads((tmp_path / "run" / "model" / "tank.json").read_text())
    (tmp_path / "run" / "model" / "tank.json").write_text(json.dumps({**tank, "dims": [2, 5, 4, 2, 2]}))
    with pytest.raises(CheckpointError, match="dims"):
        load_tank_policy(tmp_path / "run")


# -- the exported robot in the engine -------------------------------------------------------------------


@pytest.mark.engine
def test_exported_tank_robot_plays(install, tmp_path) -> None:
    from click.testing import CliRunner

    from confront.cli.main import cli
    from confront.engine.battle import BattleSpec
    from confront.engine.runner import EngineOptions, run_battle

    _write_run(tmp_path / "run", _policy(6))
    jar = tmp_path / "out" / "tankbot.jar"
    res = CliRunner().invoke(cli, ["export", str(tmp_path / "run"), "--out", str(jar)])
    assert res.exit_code == 0, res.output
    assert "confront.TankBot" in res.output
    assert "play sampled" in zipfile.ZipFile(jar).read("confront/tank_policy.txt").decode()  # the default
    greedy = tmp_path / "greedy" / "tankbot.jar"
    res = CliRunner().invoke(cli, ["export", str(tmp_path / "run"), "--out", str(greedy), "--play", "greedy"])
    assert res.exit_code == 0, res.output
    assert "play" not in zipfile.ZipFile(greedy).read("confront/tank_policy.txt").decode()
    names = set(zipfile.ZipFile(jar).namelist())
    assert {"confront/TankBot.class", "confront/TankModel.class", "confront/TankData.class",
            "confront/RoundStart.class", "confront/tank_policy.txt", "confront/TankBot.properties"} <= names
    folder = export_tank_robot(_policy(6), tmp_path / "robots", install)
    assert (folder / "confront" / "TankData.class").is_file()
    run = run_battle(BattleSpec(("confront.TankBot 1.0", "sample.SittingDuck"), rounds=1), EngineOptions(seed=3),
                     extra_robots=[jar])
    reports = run.summary["robot_reports"]
    assert not run.errors and run.results.rounds == 1
    assert not [r for r in reports if "tank-error" in r or "tank-load-failed" in r or "Exception" in r], reports
    rounds = [r for r in reports if "tank-round" in r]
    assert rounds and int(rounds[0].split("decisions=")[1].split()[0]) > 10, reports


@pytest.mark.engine
def test_exported_sampling_robot_plays_and_repeats_with_the_engine_seed(install, tmp_path) -> None:
    from click.testing import CliRunner

    from confront.cli.main import cli
    from confront.engine.battle import BattleSpec
    from confront.engine.runner import EngineOptions, run_battle

    _write_run(tmp_path / "run", _policy(6))
    jar = tmp_path / "out" / "tankbot.jar"
    res = CliRunner().invoke(cli, ["export", str(tmp_path / "run"), "--out", str(jar), "--play", "sampled"])
    assert res.exit_code == 0, res.output
    assert "play sampled" in zipfile.ZipFile(jar).read("confront/tank_policy.txt").decode()
    # a skipped turn (a robot over its time on a loaded machine) plays another battle: compare only battles without
    # one (a generous 100 ms per turn, up to three tries)
    for _ in range(3):
        scores, skipped = [], 0
        for seed in (3, 3, 4):
            run = run_battle(BattleSpec(("confront.TankBot 1.0", "sample.Walls"), rounds=2),
                             EngineOptions(seed=seed, cpu_constant_ms=100.0), extra_robots=[jar])
            reports = run.summary["robot_reports"]
            assert not run.errors and run.results.rounds == 2
            assert not [r for r in reports if "tank-error" in r or "tank-load-failed" in r or "Exception" in r], reports
            scores.append([(c.name, c.total, c.bullet_dmg) for c in run.results.contestants])
            skipped += sum(run.skipped_turns.values())
        if not skipped:
            break
    assert not skipped, "every try skipped turns (loaded machine)"
    assert scores[0] == scores[1]  # Robocode's random, which the robot draws from, follows the battle's seed
    assert scores[0] != scores[2]


@pytest.mark.engine
def test_exported_team_plays(install) -> None:
    from confront.engine.battle import scenario_battle
    from confront.engine.runner import EngineOptions, run_battle
    from confront.engine.tank_export import TANK_ROBOT, evaluate_tank_policy

    with tempfile.TemporaryDirectory() as tmp:
        jar = export_tank_robot(_policy(7), Path(tmp) / "tankbot.jar", install)
        run = run_battle(scenario_battle("4v4", TANK_ROBOT, "SpinBot", rounds=1), EngineOptions(seed=2),
                         extra_robots=[jar])
    reports = run.summary["robot_reports"]
    assert not run.errors and run.results.rounds == 1
    assert not [r for r in reports if "tank-error" in r or "tank-load-failed" in r], reports
    res, ratio = evaluate_tank_policy(_policy(7), "1v1", "SittingDuck", rounds=1, seed=1, install=install)
    ours = next(r for r in res.contestants if r.name.startswith("confront.TankBot"))
    assert res.rounds == 1 and ratio == res.score_ratio(ours.name)


@pytest.mark.engine
@pytest.mark.parametrize("opponent", ["SpinBot"])
def test_exported_robot_plays_like_the_simulator_turn_by_turn(install, tmp_path, opponent) -> None:
    """The exported robot in the engine and the simulator driven by the Python twin, from the same start
    positions: every robot's position, headings and energy agree at every turn while both live, up to the
    first bullet-bullet hit (where the engine's random bullet order can decide; docs/engine.md)."""
    from confront.arena.scenarios import get_scenario
    from confront.engine.battle import BattleSpec
    from confront.engine.runner import EngineOptions, run_battle

    policy = _policy(6)
    starts = ((150.0, 120.0, 30.0), (550.0, 420.0, 200.0))
    jar = export_tank_robot(policy, tmp_path / "tankbot.jar", install)
    trace = tmp_path / "trace.jsonl"
    run = run_battle(BattleSpec(("confront.TankBot 1.0", opponent), rounds=1, max_turns=400, initial_positions=starts),
                     EngineOptions(seed=1, cpu_constant_ms=50.0), trace=trace, extra_robots=[jar])
    assert not run.errors and not sum(run.skipped_turns.values())
    keys = ("x", "y", "body_heading", "gun_heading", "radar_heading", "energy")
    turns = [json.loads(line) for line in trace.read_text().splitlines()]
    turns = [t for t in turns if t.get("type") == "turn"]
    eng = np.array([[[r[k] for k in keys] for r in t["robots"]] for t in turns])
    clash = [i for i, t in enumerate(turns) if any(b["state"] == "HIT_BULLET" for b in t["bullets"])]

    env = TeamBattleEnv(get_scenario("1v1").replace(initial_positions=starts, max_turns=100000), 1, seed=1,
                        opponents=opponent, config=SMDPConfig(turns_per_step=policy.step_turns, tank=policy.space,
                                                               reward="score", auto_reset=False))
    _, feats = env.reset()
    env.start_recording(0)
    while env.arena.state.time[0] < len(eng) and not env.arena.state.done[0]:
        feats = env.step(np.array([[policy.act(feats[0, 0]), 0]])).features
    replay = env.stop_recording()
    sim = np.array([r for r, t in zip(replay.robots, replay.turn, strict=True) if t >= 1])[:, :, :6]  # turns 1, 2, ...
    sim[:, :, 2:5] = np.radians(sim[:, :, 2:5])
    n = min(len(sim), len(eng))
    alive = (eng[:n, :, 5] > 0).all(axis=1)
    n = int(np.argmin(alive)) + 1 if not alive.all() else n  # up to the turn a robot dies
    n = min([n] + clash)
    assert n > 200
    d = np.abs(eng[:n] - sim[:n])
    d[..., 2:5] = np.abs((eng[:n, :, 2:5] - sim[:n, :, 2:5] + math.pi) % (2 * math.pi) - math.pi)
    bad = np.flatnonzero(d.max(axis=(1, 2)) > 1e-6)
    assert bad.size == 0, f"turn {bad[0] + 1}: engine {eng[bad[0]]}, simulator {sim[bad[0]]}"


def test_twin_acts_like_the_ppo_learner(views) -> None:
    """The learner's actor arrays, as ``confront train`` saves them, give the learner's greedy actions."""
    from confront.learning.ppo import PPO
    from confront.learning.ppo_config import PPOConfig

    ppo = PPO(SPACE.n_features, SPACE.dims, PPOConfig(hidden=32), seed=3)
    rng = np.random.default_rng(5)
    ppo.load_actor_arrays({k: rng.normal(0, 0.5, v.shape) for k, v in ppo.actor_arrays().items()})
    policy = TankPolicy.from_state(ppo.actor_arrays(), SPACE)
    obs = np.stack([f for _, f, _ in views])
    joint = ppo.act(obs, explore=False)[0]
    close = 0
    for v, a in zip(obs, joint, strict=True):
        z, off, near = policy.logits(v), 0, False
        for n in SPACE.dims:  # a float32 (torch) vs float64 near-tie may pick either
            top = np.sort(z[off:off + n])[-2:]
            near |= n > 1 and top[1] - top[0] < 1e-5
            off += n
        close += near
        assert near or policy.act(v) == int(a)
    assert close < len(obs) // 100 and len(set(joint.tolist())) > 10


@pytest.mark.engine
def test_report_keeps_each_engine_battle(install, tmp_path) -> None:
    from confront.experiments.tank_report import engine_share

    share = engine_share(tmp_path, _policy(7), "1v1:SittingDuck", 1, 1)
    cache = tmp_path / "eval" / "engine-1.json"
    assert json.loads(cache.read_text()) == {"1v1:SittingDuck@1": share} and 0.0 <= share <= 1.0
    cache.write_text(json.dumps({"1v1:SittingDuck@1": 0.123}))
    assert engine_share(tmp_path, _policy(7), "1v1:SittingDuck", 1, 1) == 0.123  # read back, not played again
    cache.write_text(json.dumps({"1v1:SittingDuck@1": 0.123}))
    p = _policy(7)
    sampled = TankPolicy(p.weights, p.biases, p.space, p.control, p.step_turns, play="sampled")
    share = engine_share(tmp_path, sampled, "1v1:SittingDuck", 1, 1)  # its own cache, played
    assert json.loads((tmp_path / "eval" / "engine-sampled-1.json").read_text()) == {"1v1:SittingDuck@1": share}
    assert json.loads(cache.read_text()) == {"1v1:SittingDuck@1": 0.123}


@pytest.mark.engine
def test_tankbot_against_a_paper_move_team_in_the_engine(install) -> None:
    """A paper-move opponent (here the dodge) plays in the engine as four exported PolicyBots with random ties."""
    from confront.engine.export import ExportedPolicy
    from confront.engine.tank_export import evaluate_tank_policy
    from confront.train.league import paper_move_robot
    from confront.train.spec import load_experiment

    theirs = paper_move_robot(load_experiment("tanks-demo"), "dodge")
    assert isinstance(theirs, ExportedPolicy) and theirs.ties == "random" and theirs.step_turns == 5
    res, share = evaluate_tank_policy(_policy(3), "4v4", "dodge", rounds=2, seed=1, opponent_policy=theirs,
                                      install=install)
    names = [c.name for c in res.contestants]
    assert sorted(n.split()[0] for n in names) == ["confrontteams.Ours4", "confrontteams.Them4"]
    assert res.rounds == 2 and 0.0 <= share <= 1.0
    assert sum(c.total for c in res.contestants) > 0


@pytest.mark.engine
def test_tankbot_share_is_its_own_against_a_policybot_1v1(install) -> None:
    """1v1 against an exported PolicyBot both names start with "confront.": the share returned is TankBot's, also
    when the PolicyBot ranks first (here TankBot holds still and never fires)."""
    from confront.engine.tank_export import TANK_ROBOT, evaluate_tank_policy
    from confront.train.league import paper_move_robot
    from confront.train.spec import load_experiment

    sizes = [SPACE.n_features, 8, 8, sum(SPACE.dims)]
    b2 = np.zeros(sum(SPACE.dims))
    b2[np.cumsum((0,) + SPACE.dims[:-1]) + np.array((2, 2, 0, 0, 0))] = 10.0  # no move, no turn, hold fire
    still = TankPolicy(tuple(np.zeros((o, i)) for i, o in zip(sizes, sizes[1:], strict=False)),
                       (np.zeros(8), np.zeros(8), b2), SPACE, ControlConfig(), 5)
    theirs = paper_move_robot(load_experiment("tanks-demo"), "dodge")
    res, share = evaluate_tank_policy(still, "1v1", "dodge", rounds=1, seed=1, opponent_policy=theirs,
                                      install=install)
    ours = next(c for c in res.contestants if c.name.startswith(TANK_ROBOT.split()[0]))
    assert res.contestants[0].name != ours.name  # the PolicyBot won
    assert share == res.score_ratio(ours.name) < 0.5


@pytest.mark.engine
def test_second_team_knows_its_mates_like_the_simulator(install, tmp_path) -> None:
    """Robocode 1.9.3.9 lists the mates of a team that is not first in the battle under names they do not have
    (isTeammate fails there); the exported robots also count whoever sent them a message as a mate. A tank team
    holding one action against a PolicyBot team (a random Q table, second in the battle) then plays the
    simulator's battle turn by turn (it diverged at turn 6, a PolicyBot locking onto its mate)."""
    import dataclasses

    from confront.arena.observe import ObservationConfig
    from confront.arena.scenarios import get_scenario
    from confront.engine.battle import scenario_battle, single_star
    from confront.engine.export import ExportedPolicy, export_robot
    from confront.engine.runner import EngineOptions, run_battle

    sizes = [SPACE.n_features, 8, 8, sum(SPACE.dims)]
    b2 = np.zeros(sum(SPACE.dims))
    heads = (4, 4, 2, 0, 0)  # +150 px, at 90 deg to the target, power 2, slot 0, no lead
    b2[np.cumsum((0,) + SPACE.dims[:-1]) + np.array(heads)] = 10.0
    ours = TankPolicy(tuple(np.zeros((o, i)) for i, o in zip(sizes, sizes[1:], strict=False)),
                      (np.zeros(8), np.zeros(8), b2), SPACE, ControlConfig(), 5)
    q = np.random.default_rng(11).normal(size=(320, 4))
    theirs = ExportedPolicy("qtable", q=q, observation=ObservationConfig(), step_turns=5)
    starts = ((100.0, 100.0, 30.0), (100.0, 250.0, 60.0), (100.0, 400.0, 90.0), (100.0, 520.0, 120.0),
              (700.0, 100.0, 200.0), (700.0, 250.0, 230.0), (700.0, 400.0, 260.0), (700.0, 520.0, 300.0))
    robots = [export_tank_robot(ours, tmp_path / "tankbot.jar", install), export_robot(theirs, tmp_path / "robots")]
    spec = single_star(scenario_battle("4v4", "confront.TankBot 1.0", "confront.PolicyBot", rounds=1),
                       "confront.PolicyBot*")
    trace = tmp_path / "trace.jsonl"
    run = run_battle(dataclasses.replace(spec, max_turns=160, initial_positions=starts),
                     EngineOptions(seed=1, cpu_constant_ms=50.0), trace=trace, extra_robots=robots)
    assert not run.errors and not sum(run.skipped_turns.values())
    keys = ("x", "y", "body_heading", "gun_heading", "radar_heading", "energy")
    turns = [t for t in map(json.loads, trace.read_text().splitlines()) if t.get("type") == "turn"]
    eng = np.array([[[r[k] for k in keys] for r in t["robots"]] for t in turns])

    env = TeamBattleEnv(get_scenario("4v4").replace(initial_positions=starts, max_turns=100000), 1, seed=1,
                        opponents="td", config=SMDPConfig(turns_per_step=5, tank=SPACE, reward="score",
                                                          auto_reset=False), opponent_actions="paper")
    _, feats = env.reset()
    disc = env.observe()[1]
    env.start_recording(0)
    while env.arena.state.time[0] < len(eng) and not env.arena.state.done[0]:
        acts = [ours.act(feats[0, i]) if i < 4 else int(np.argmax(q[disc[0, i]])) for i in range(8)]
        st = env.step(np.array([acts]))
        feats, disc = st.features, st.discrete
    replay = env.stop_recording()
    sim = np.array([r for r, t in zip(replay.robots, replay.turn, strict=True) if t >= 1])[:, :, :6]
    sim[:, :, 2:5] = np.radians(sim[:, :, 2:5])
    n = min(len(sim), len(eng))
    assert n >= 150
    d = np.abs(eng[:n] - sim[:n])
    d[..., 2:5] = np.abs((eng[:n, :, 2:5] - sim[:n, :, 2:5] + math.pi) % (2 * math.pi) - math.pi)
    bad = np.flatnonzero(d.max(axis=(1, 2)) > 1e-6)
    assert bad.size == 0, f"turn {bad[0] + 1}: engine {eng[bad[0]]}, simulator {sim[bad[0]]}"


@pytest.mark.engine
def test_exported_jar_holds_a_team_robocode_lists_and_plays(install, tmp_path) -> None:
    """`confront export` puts the team confront.TankTeam (four TankBots) in the jar; Robocode's own command line,
    with the jar in its robots folder as a user would drop it, plays that team against the sample team."""
    from click.testing import CliRunner

    from confront.cli.main import cli
    from confront.engine.battle import BattleSpec
    from confront.engine.install import JVM_FLAGS
    from confront.engine.workdir import prepare_workdir
    from confront.results import parse_results_text

    _write_run(tmp_path / "run", _policy(6))
    jar = tmp_path / "MyTank.jar"
    res = CliRunner().invoke(cli, ["export", str(tmp_path / "run"), "--out", str(jar)])
    assert res.exit_code == 0 and "the team confront.TankTeam (4 TankBots)" in res.output
    team = zipfile.ZipFile(jar).read("confront/TankTeam.team").decode()
    assert "team.members=" + ",".join(["confront.TankBot 1.0"] * 4) + "\n" in team
    wd = prepare_workdir(tmp_path / "wd", install, compile_java(install), extra_robots=[jar])
    battle = tmp_path / "team.battle"
    battle.write_text(BattleSpec(("confront.TankTeam 1.0", "sampleteam.MyFirstTeam"), rounds=1).battle_file())
    results = tmp_path / "results.txt"
    subprocess.run([install.java, "-Xmx512M", f"-DWORKINGDIRECTORY={wd}", "-DRANDOMSEED=3", *JVM_FLAGS, "-cp",
                    str(install.jar), "robocode.Robocode", "-battle", str(battle), "-nodisplay", "-nosound",
                    "-results", str(results)], check=True, capture_output=True, timeout=300)
    rows = parse_results_text(results.read_text()).contestants
    assert sorted(r.name.split(" (")[0] for r in rows) == ["confront.TankTeam 1.0", "sampleteam.MyFirstTeam"]
    assert sum(r.firsts for r in rows) == 1 and all(r.total >= 0 for r in rows)
    assert max(r.bullet_dmg for r in rows) > 0  # the battle was fought


@pytest.mark.engine
def test_run_jar_exports_a_run_under_its_robots_fixed_name(install, tmp_path) -> None:
    """`confront robocode RUN`: the run becomes confront-TankBot.jar (robot and team), one name per robot class."""
    from confront.experiments.evaluate import run_jar

    _write_run(tmp_path / "run", _policy(6))
    jar = run_jar(tmp_path / "run", tmp_path / "robots")
    assert jar == tmp_path / "robots" / "confront-TankBot.jar"
    names = set(zipfile.ZipFile(jar).namelist())
    assert {"confront/TankBot.class", "confront/TankData.class", "confront/TankTeam.team"} <= names
    assert "play sampled" in zipfile.ZipFile(jar).read("confront/tank_policy.txt").decode()
    (tmp_path / "empty").mkdir()
    with pytest.raises(FileNotFoundError, match="is not a trained run folder"):
        run_jar(tmp_path / "empty", tmp_path / "robots")
