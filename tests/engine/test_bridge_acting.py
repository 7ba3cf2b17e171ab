"""Robots that act from their own copy of the policy (``RobotActing``): the protocol on loopback, and real
engine battles (the exported robot's battle, a learner's copy kept current, a stalled or failing Python side)."""

from __future__ import annotations

import json
import socket
import time
from dataclasses import replace

import numpy as np
import pytest

from confront.arena.control import ControlConfig
from confront.engine.battle import BattleSpec
from confront.engine.bridge import (
    BridgeServer,
    BridgeSettings,
    Observation,
    RobotActing,
    controller_lines,
    format_observation,
    parse_hello,
    parse_observation,
)
from confront.engine.bridged import BRIDGE_BOT, run_bridged_battle
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.learner_policy import LearnerPolicy
from confront.engine.runner import EngineOptions, run_battle
from confront.learning.tabular import TabularQ

HELLO = {"v": 2, "type": "hello", "token": "t0k", "name": "confront.BridgeBot* (1)", "team": "", "round": 0,
         "rounds": 3, "width": 800.0, "height": 600.0}
OBS = "O 0 11 100.0 200.0 0.0 0.5 1.0 8.0 99.5 2.3 1 12.0\tsample.Walls;6;0;0.5;300.0;1.0;-8.0;80.0;400.0;200.0\t[]\t"


def _acting(**kw) -> RobotActing:  # noqa: ANN003
    return RobotActing(model=lambda: "confront-policy 1\nkind qtable", **kw)


def test_hello_reply_carries_the_robots_own_policy() -> None:
    ctl = ControlConfig()
    settings = BridgeSettings(10, ctl, history=True, acting=_acting(explore="boltzmann", param=lambda: 0.5,
                                                                     seed=lambda: 7, max_lag=3))
    lines = settings.hello_reply().splitlines()
    n = len(controller_lines(ctl))
    assert lines[0] == f"OK 2 10 0 1 {n} 3"  # M = 3: the acting line and the two lines of the policy file
    assert lines[1:n + 1] == controller_lines(ctl)
    assert lines[n + 1:] == ["acting boltzmann 0.5 7 3 all 0", "confront-policy 1", "kind qtable"]
    row = replace(settings.acting, wait="row", fixed=lambda: True)  # a learner's robots: see RobotActing
    assert row.hello_lines()[0] == "acting boltzmann 0.5 7 3 row 1"
    assert BridgeSettings(10, ctl).hello_reply().splitlines()[0] == f"OK 2 10 0 0 {n}"  # unchanged without


def test_acting_settings_are_checked() -> None:
    with pytest.raises(ValueError, match="controller"):
        BridgeSettings(10, None, acting=_acting())
    with pytest.raises(ValueError, match="lead"):
        BridgeSettings(10, ControlConfig(), lead=2, acting=_acting())
    with pytest.raises(ValueError, match="explore"):
        _acting(explore="softmax")
    with pytest.raises(ValueError, match="max_lag"):
        _acting(max_lag=0)
    with pytest.raises(ValueError, match="wait"):
        _acting(wait="rows")
    with pytest.raises(ValueError, match="finite"):
        _acting(param=lambda: float("nan")).hello_lines()
    with pytest.raises(ValueError, match="temperature"):
        _acting(explore="boltzmann", param=lambda: 0.0).hello_lines()
    with pytest.raises(ValueError, match="threshold"):
        _acting(explore="egreedy", param=lambda: 1.5).hello_lines()
    with pytest.raises(ValueError, match="Q table"):
        ExportedPolicy("mlp", weights=(np.zeros((4, 7)),), biases=(np.zeros(4),)).robot_acting()


def test_observation_with_the_move_taken() -> None:
    hello = parse_hello(json.dumps(HELLO), "t0k")
    obs = parse_observation(OBS + "\t2;1;3", hello, acting=True)
    assert (obs.action, obs.behind, obs.ahead, obs.turn) == (2, 1, 3, 11)
    assert parse_observation(format_observation(obs), hello, acting=True) == obs
    assert parse_observation(OBS, hello).action == -1  # Python decides
    for bad in ("\t4;0;0", "\t-1;0;0", "\t2", "\t2;0", "\t2;-1;0", "\t2;0;-1", "\t2;600;401", "\t2;0;0;0",
                "\tx;0;0", ""):
        with pytest.raises(ValueError):
            parse_observation(OBS + bad, hello, acting=True)
    with pytest.raises(ValueError):
        parse_observation(OBS + "\t2;0;0", hello)  # a move where an answer is expected


def _read(sock: socket.socket, n: int, buf: bytearray) -> list[str]:
    while buf.count(b"\n") < n:
        chunk = sock.recv(65536)
        if not chunk:
            break
        buf += chunk
    lines = buf.decode().split("\n")
    del buf[: len("\n".join(lines[:n])) + 1]
    return lines[:n]


def test_updates_reach_every_acting_robot_and_a_silent_one_is_cut_off() -> None:
    """Each observation is acknowledged to its robot (K), the policy's updates go to every connected robot, and
    a robot that stops reading is disconnected with an error instead of holding the server up."""
    seen: list[Observation] = []
    queue: list[str] = []

    def policy(obs: Observation) -> tuple[float, ...]:
        seen.append(obs)
        queue.extend(["Q 5 1.0 2.0 3.0 4.0", "X 0.25"] * (1000 if obs.turn > 30 else 1))
        return (float("nan"),) * 5

    def drain() -> list[str]:
        out = list(queue)
        queue.clear()
        return out

    acting = RobotActing(model=lambda: "confront-policy 1", updates=drain, max_lag=2)
    settings = BridgeSettings(10, ControlConfig(), acting=acting)
    with BridgeServer(policy, token="t0k", settings=settings) as server:
        a = socket.create_connection(("127.0.0.1", server.port), timeout=5)
        b = socket.create_connection(("127.0.0.1", server.port), timeout=5)
        bufs = {a: bytearray(), b: bytearray()}
        n = len(settings.hello_reply().splitlines())
        for s, name in ((a, "A"), (b, "B")):
            s.sendall((json.dumps({**HELLO, "name": name}) + "\n").encode())
            assert _read(s, n, bufs[s])[0].startswith("OK 2 10 0 0 ")
        a.sendall((OBS + "\t1;0;0\n").encode())
        assert _read(a, 3, bufs[a]) == ["Q 5 1.0 2.0 3.0 4.0", "X 0.25", "K 11"]
        assert _read(b, 2, bufs[b]) == ["Q 5 1.0 2.0 3.0 4.0", "X 0.25"]  # B's copy too, without an ack
        b.sendall((OBS.replace("O 0 11", "O 0 21") + "\t3;0;0\n").encode())
        assert _read(b, 3, bufs[b]) == ["Q 5 1.0 2.0 3.0 4.0", "X 0.25", "K 21"]
        assert _read(a, 2, bufs[a]) == ["Q 5 1.0 2.0 3.0 4.0", "X 0.25"]
        # from now on B never reads: 2000 update lines per observation of A fill its buffers, and it is cut off
        turn = 31
        while not server.stats.errors and turn < 3000:
            a.sendall((OBS.replace("O 0 11", f"O 0 {turn}") + "\t0;0;0\n").encode())
            lines = _read(a, 2001, bufs[a])  # A reads its updates and the ack
            assert lines[-1] == f"K {turn}" and len(lines) == 2001
            turn += 10
        a.sendall(b"E 0 40 round_end 50.0 3 30 0 40 100\t\n")
        a.close()
        b.close()
    assert 50 < turn < 3000 and server.stats.decisions == len(seen) == 2 + (turn - 31) // 10
    assert [o.action for o in seen[:3]] == [1, 3, 0]
    assert server.stats.errors == ["B: stopped reading its policy updates; connection closed"]



class _Checked:
    """The twin as the policy of robots that play its Q table themselves: records each move it would differ on."""

    def __init__(self, policy: ExportedPolicy) -> None:
        self.policy, self.seen, self.differ = policy, [], []

    def __call__(self, obs: Observation) -> tuple[float, ...]:
        self.seen.append(obs)
        if self.policy.act(obs) != obs.action:
            self.differ.append(obs)
        return self.policy(obs)


@pytest.mark.engine
def test_acting_robot_plays_the_exported_robots_battle(install, tmp_path) -> None:
    policy = ExportedPolicy("qtable", q=np.random.default_rng(4).normal(size=(320, 4)), step_turns=5)
    checked = _Checked(policy)
    opts = EngineOptions(seed=2, cpu_constant_ms=50)
    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "Walls"), rounds=2), checked, opts, every=5,
                             controller=policy.control, acting=policy.robot_acting(max_lag=3))
    java = run_battle(BattleSpec(("confront.PolicyBot*", "Walls"), rounds=2), opts,
                      extra_robots=[export_robot(policy, tmp_path / "robots")])
    assert res.ok, (res.failures, res.server_errors)
    assert checked.differ == [] and res.decisions == len(checked.seen) > 100
    # decisions in turns 1, 6, 11, ...; a skipped turn (a loaded machine) makes one up at a later turn
    late = bool(res.run.skipped_turns)
    assert all(o.action >= 0 and ((o.turn - 1) % 5 == 0 or late) for o in checked.seen)
    assert res.rtt_mean_us > 0 and 0 <= res.behind <= res.decisions
    if not res.run.skipped_turns and not java.skipped_turns:  # a skipped turn changes the rest of a battle
        assert res.run.round_turns == java.round_turns
        assert [(c.name.startswith("sample."), c.total) for c in res.run.results.contestants] == [
            (c.name.startswith("sample."), c.total) for c in java.results.contestants]


@pytest.mark.engine
def test_learner_copy_in_the_robot_is_current(install) -> None:
    """max_lag = 1: each move is a greedy move of the learner's table as it was before the step that ends at
    that decision was learned (the robot waited for every earlier update of the row it draws from), also when
    Python is slower than the robots' decisions and the robots go on without waiting for the other rows."""
    learner = TabularQ()
    pol = LearnerPolicy(learner, np.random.default_rng(3), train=True, explore=False, step_turns=5, max_lag=1)
    twin = ExportedPolicy("qtable", q=np.zeros((320, 4)))
    checks: list[bool] = []

    class Watch:
        def __call__(self, obs: Observation) -> tuple[float, ...]:
            row = learner.q[twin.state_and_features(obs)[0]]
            checks.append(obs.behind == 0 and row[obs.action] == row.max())
            time.sleep(0.003)  # slower than a decision every 5 turns: the robot runs ahead where it may
            return pol(obs)

        def end_episode(self, robot: str, round_: int, history=()) -> None:  # noqa: ANN001
            pol.end_episode(robot, round_, history)

    kwargs = pol.bridge_kwargs()
    assert kwargs["acting"].explore == "greedy"
    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SpinBot"), rounds=2), Watch(),
                             EngineOptions(seed=1, cpu_constant_ms=50), **kwargs)
    assert res.ok, (res.failures, res.server_errors)
    assert len(checks) == pol.decisions == res.decisions > 50 and all(checks)
    assert pol.updates >= pol.decisions - 2 and learner.step == pol.updates
    assert res.behind == 0 and 0 < res.ahead < res.decisions  # it went ahead, and it waited for its rows
    assert len({float(v) for v in learner.q.ravel()}) > 10  # the table moved away from its start


@pytest.mark.engine
def test_stalled_python_stops_an_acting_robot_at_its_lag(install) -> None:
    """A policy that stalls leaves its observations unacknowledged: the robot goes on for max_lag decisions,
    then waits at most its timeout and falls back; the next round plays bridged again."""
    policy = ExportedPolicy("qtable", q=np.random.default_rng(5).normal(size=(320, 4)), step_turns=5)
    seen: list[tuple[int, int]] = []

    def stalling(obs: Observation) -> tuple[float, ...]:
        seen.append((obs.round, obs.turn))
        if (obs.round, obs.turn) == (0, 41):
            time.sleep(0.6)  # three times the robot's 200 ms patience
        return policy(obs)

    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SittingDuck"), rounds=3), stalling,
                             EngineOptions(seed=1, cpu_constant_ms=50), timeout_ms=200, every=5,
                             controller=policy.control, acting=policy.robot_acting(max_lag=2))
    round0 = [f for f in res.failures if "round=0" in f]
    assert len(round0) == 1 and "SocketTimeoutException" in round0[0], res.failures
    assert "turn=50" in round0[0]  # 41 and 46 sent unacknowledged, then it waits in turn 51
    assert max(t for r, t in seen if r == 0) == 46
    assert any(r == 2 for r, _ in seen) and res.run.results.rounds == 3


@pytest.mark.engine
def test_failing_policy_cuts_an_acting_robot_off(install) -> None:
    """A policy error ends that robot's session (reported by the server); the robot notices the closed
    connection at its next decision and falls back; the next round is bridged again."""
    policy = ExportedPolicy("qtable", q=np.random.default_rng(6).normal(size=(320, 4)), step_turns=5)

    def failing(obs: Observation) -> tuple[float, ...]:
        if (obs.round, obs.turn) == (0, 21):
            raise RuntimeError("policy broke")
        return policy(obs)

    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SittingDuck"), rounds=2), failing,
                             EngineOptions(seed=1, cpu_constant_ms=50), every=5, controller=policy.control,
                             acting=replace(policy.robot_acting(), max_lag=1))
    assert any("RuntimeError: policy broke" in e for e in res.server_errors), res.server_errors
    round0 = [f for f in res.failures if "round=0" in f]
    assert len(round0) == 1 and "python side closed the connection" in round0[0], res.failures
    assert "turn=25" in round0[0]  # its next decision turn
    assert not [f for f in res.failures if "round=1" in f] and res.run.results.rounds == 2
