"""The exported tank with skills (confront.arena.tank): Robocode's TankBot, carrying confront.tech.TechBrain, plays the
simulator's battle turn by turn and makes the simulator's views (the knowledge block included) and actions at every
decision; policy files without skills load and play as before."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from confront.arena.control import ControlConfig
from confront.arena.smdp import SMDPConfig, TeamBattleEnv
from confront.arena.tank import TankSpace
from confront.engine.tank_export import TankPolicy, export_tank_robot, load_tank_policy

SKILLS = TankSpace(leads=("none", "circular", "gf"), surf=True, knowledge=True)


def _policy(seed: int, space: TankSpace = SKILLS, hidden: int = 24) -> TankPolicy:
    rng = np.random.default_rng(seed)
    sizes = [space.n_features, hidden, hidden, sum(space.dims)]
    return TankPolicy(tuple(rng.normal(0, 1.0, size=(o, i)) for i, o in zip(sizes, sizes[1:], strict=False)),
                      tuple(rng.normal(0, 0.5, size=o) for o in sizes[1:]), space, ControlConfig(), 5)


def test_policy_files_without_skills_are_as_before(tmp_path: Path) -> None:
    """A tank.json of before (no surf, no knowledge) loads without skills, and its policy file has no skill line;
    one with skills keeps them."""
    plain = _policy(1, TankSpace())
    text = plain.to_text()
    assert "surf" not in text and "knowledge" not in text and "gf" not in text
    for space in (TankSpace(), SKILLS):
        p = _policy(2, space)
        model = tmp_path / str(space.skills) / "model"
        model.mkdir(parents=True)
        (model / "model.json").write_text(json.dumps({"kind": "ppo"}))
        np.savez(model / "actor.npz", **{f"{n}{i}": a for i, (w, b) in enumerate(zip(p.weights, p.biases,
                                                                                     strict=True))
                                         for n, a in (("w", w), ("b", b))})
        tank = {"distances": list(space.distances), "leads": list(space.leads), "step_turns": 5}
        if space.skills:
            tank |= {"surf": True, "knowledge": True}
        (model / "tank.json").write_text(json.dumps(tank))
        q = load_tank_policy(model.parent)
        assert q.space == space and q.to_text() == p.to_text()
    assert "surf 1\nknowledge 1\n" in _policy(2).to_text() and "leads none circular gf\n" in _policy(2).to_text()
    assert "brain" not in _policy(2).to_text()  # SurfGF, the brain of older files
    anti = TankSpace(leads=("gf",), knowledge=True, brain="SurfAS")
    assert "knowledge 1\nbrain SurfAS\n" in _policy(2, anti).to_text()


# fixed starts, or the engine's own from its seed (the simulator draws Robocode's random processing order only when
# it also draws the start positions; bullet-bullet hits and team-mates' collisions depend on that order; engine.md)
SEED = 1  # the engine's and the simulator's
STARTS = {("1v1", "SpinBot"): ((150.0, 120.0, 30.0), (550.0, 420.0, 200.0))}


@pytest.mark.engine
@pytest.mark.parametrize(("scenario", "opponent", "brain"), [("1v1", "SpinBot", "SurfGF"), ("1v1", "SurfVG", "SurfGF"),
                                                         ("4v4", "SpinBot", "SurfGF"), ("1v1", "SurfVG", "SurfAS")])
def test_skills_tank_plays_like_the_simulator_turn_by_turn(install, tmp_path, scenario, opponent, brain) -> None:
    """Against SpinBot (a team of them in 4v4, where the brain moves by minimum risk) and the technique robot
    SurfVG (a wave surfer with virtual guns, in both), with either brain: every robot's pose and
    energy agree at every turn while all live (1v1 from fixed starts: up to the first bullet-bullet hit, whose order
    is random there; docs/engine.md),
    and every decision's view and action (TankBot's decision log) equal the simulator's. The policy picks surf and
    gf, and the knowledge block sees waves (1v1): counted."""
    import dataclasses

    from confront.arena.scenarios import get_scenario
    from confront.engine.battle import scenario_battle
    from confront.engine.runner import EngineOptions, run_battle
    from confront.train.engine_logs import read_decisions

    p = _policy(6 if scenario == "1v1" else 2)
    b2 = p.biases[-1].copy()
    b2[len(SKILLS.distances)] += 1.5  # surf more often
    policy = TankPolicy(p.weights, (*p.biases[:-1], b2), dataclasses.replace(SKILLS, brain=brain), p.control,
                        p.step_turns)
    starts = STARTS.get((scenario, opponent))
    n_tanks = 1 if scenario == "1v1" else 4
    jar = export_tank_robot(policy, tmp_path / "tankbot.jar", install)
    trace, log = tmp_path / "trace.jsonl", tmp_path / "log"
    log.mkdir()
    spec = scenario_battle(scenario, "confront.TankBot 1.0", opponent, rounds=1)
    run = run_battle(dataclasses.replace(spec, max_turns=600, initial_positions=starts or ()),
                     EngineOptions(seed=SEED, cpu_constant_ms=50.0, nosecurity=True,
                                   extra_jvm_args=(f"-Dconfront.tank.log={log}",)), trace=trace, extra_robots=[jar])
    assert not run.errors and not sum(run.skipped_turns.values())
    assert not [r for r in run.summary["robot_reports"] if "tank-error" in r or "Exception" in r]
    keys = ("x", "y", "body_heading", "gun_heading", "radar_heading", "energy")
    turns = [t for t in map(json.loads, trace.read_text().splitlines()) if t.get("type") == "turn"]
    eng = np.array([[[r[k] for k in keys] for r in t["robots"]] for t in turns])
    clash = [i for i, t in enumerate(turns) if any(b["state"] == "HIT_BULLET" for b in t["bullets"])]

    env = TeamBattleEnv(get_scenario(scenario).replace(initial_positions=starts, max_turns=100000), 1, seed=SEED,
                        opponents=opponent, config=SMDPConfig(turns_per_step=policy.step_turns, tank=policy.space,
                                                               reward="score", auto_reset=False))
    _, feats = env.reset(seed=SEED)  # the engine's start positions and processing order (4v4)
    env.start_recording(0)
    views = {}
    while env.arena.state.time[0] < len(eng) and not env.arena.state.done[0]:
        alive = env.arena.state.alive[0]
        views.update({(i, int(env.arena.state.time[0])): feats[0, i].copy() for i in range(n_tanks) if alive[i]})
        acts = [policy.act(feats[0, i]) if i < n_tanks else 0 for i in range(2 * n_tanks)]
        feats = env.step(np.array([acts])).features
    replay = env.stop_recording()
    sim = np.array([r for r, t in zip(replay.robots, replay.turn, strict=True) if t >= 1])[:, :, :6]
    sim[:, :, 2:5] = np.radians(sim[:, :, 2:5])
    n = min(len(sim), len(eng))
    alive = (eng[:n, :, 5] > 0).all(axis=1)
    n = int(np.argmin(alive)) + 1 if not alive.all() else n
    n = min([n] + (clash if starts is not None else []))  # replayed from its start, the random order is the engine's
    assert n > 150, n
    d = np.abs(eng[:n] - sim[:n])
    d[..., 2:5] = np.abs((eng[:n, :, 2:5] - sim[:n, :, 2:5] + math.pi) % (2 * math.pi) - math.pi)
    bad = np.flatnonzero(d.max(axis=(1, 2)) > 1e-6)
    assert bad.size == 0, f"turn {bad[0] + 1}: engine {eng[bad[0]]}, simulator {sim[bad[0]]}"

    decisions = [x for x in read_decisions(log) if x.turn < n]
    assert len(decisions) >= n_tanks * (n // policy.step_turns)
    surf = gf = waves = 0
    for x in decisions:
        robot = int(x.robot.split("(")[1].rstrip(")")) - 1 if "(" in x.robot else 0
        want = views[(robot, x.turn)]
        np.testing.assert_array_equal(x.view.astype(np.float32), want, err_msg=f"{x.robot} turn {x.turn}")
        assert x.action == policy.act(want)
        dist, _, _, _, lead = np.unravel_index(x.action, SKILLS.dims)
        surf += dist == len(SKILLS.distances)
        gf += SKILLS.leads[lead] == "gf"
        waves += want[66] > 0
    assert surf >= 5 and gf >= 5 and (waves >= 5 or scenario != "1v1"), (surf, gf, waves, len(decisions))


def test_the_twins_gf_lead_turns_the_gun_to_the_brains_angle() -> None:
    """robot_control with the lead gf: the gun to the given angle (radar and fire rule as without a lead), circular
    when the brain has no angle."""
    from confront.engine.tank_export import robot_control

    row = [500.0, 400.0, 50.0, 0.5, 8.0, 0.0, 4.0, 0.05]  # x, y, energy, heading, velocity, drop, scan time, rate
    args = (400.0, 300.0, 0.3, 0.2, 0.0, 100.0, [row], 0, 2.0, 5.0, 800.0, 600.0)
    c = ControlConfig()
    assert robot_control(c, "gf", *args) == robot_control(c, "circular", *args)
    assert robot_control(c, "gf", *args) != robot_control(c, "linear", *args)
    gun, radar, fire = robot_control(c, "gf", *args, gun_aim=1.0)
    assert gun == pytest.approx(1.0 - 0.3, abs=1e-15) and fire == 0.0  # 0.7 rad off: no shot
    assert radar == robot_control(c, "none", *args)[1]
    bearing = math.atan2(100.0, 100.0)
    assert robot_control(c, "gf", *args, gun_aim=0.3 + 0.01)[0] == pytest.approx(0.01, abs=1e-15)
    assert robot_control(c, "gf", *args, gun_aim=0.3 + 0.01)[2] == 2.0  # within the tolerance, cold: fires
    assert abs(bearing - 0.3) > c.aim_tolerance
