"""Bridge protocol v2: message validation and a real loopback round trip (no engine needed)."""

from __future__ import annotations

import json
import math
import socket
import time
from dataclasses import fields

import pytest

from confront.arena.control import ControlConfig
from confront.engine.bridge import (
    BridgeServer,
    BridgeSettings,
    Observation,
    TurnEnergy,
    format_action,
    format_observation,
    load_policy,
    nearest_enemy_policy,
    parse_hello,
    parse_observation,
)

HELLO = {"v": 2, "type": "hello", "token": "t0k", "name": "confront.BridgeBot* (1)",
         "team": "confront.BridgeBot* (2)", "round": 0, "rounds": 3, "width": 800.0, "height": 600.0}
SCAN_WALLS = "sample.Walls;6;0;0.5;300.0;1.0;-8.0;80.0;400.0;200.0"
SCAN_MATE = "confront.BridgeBot* (2);5;1;0.1;50.0;2.0;0.0;100.0;105.0;250.0"


def obs_line(turn: int = 7, heat: float = 2.3, scans: str = f"{SCAN_WALLS}|{SCAN_MATE}",
             events: str = '[{"type":"hit_wall"}]', history: str = "") -> str:
    return f"O 0 {turn} 100.0 200.0 0.0 0.5 1.0 8.0 99.5 {heat} 2 12.0\t{scans}\t{events}\t{history}"


def test_parse_observation_values() -> None:
    obs = parse_observation(obs_line(), parse_hello(json.dumps(HELLO), "t0k"))
    assert (obs.robot, obs.teammates, obs.turn, obs.others) == ("confront.BridgeBot* (1)",
                                                                ("confront.BridgeBot* (2)",), 7, 2)
    assert (obs.x, obs.y, obs.energy, obs.gun_heat, obs.width) == (100.0, 200.0, 99.5, 2.3, 800.0)
    assert [s.name for s in obs.enemies()] == ["sample.Walls"]
    assert obs.events == ({"type": "hit_wall"},) and obs.history == ()


def test_history_records_round_trip() -> None:
    line = obs_line(history="5;99.5;sample.Walls;80.0;77.0|6;97.25;;0.0;0.0")
    obs = parse_observation(line, HELLO)
    assert obs.history == (TurnEnergy(5, 99.5, "sample.Walls", 80.0, 77.0), TurnEnergy(6, 97.25, "", 0.0, 0.0))
    assert parse_observation(format_observation(obs), HELLO) == obs


@pytest.mark.parametrize(
    "line",
    [
        obs_line().replace("O 0", "X 0"),
        obs_line().replace(" 12.0\t", "\t"),
        obs_line().replace("99.5", "nan"),
        obs_line().replace("O 0 7", "O 0 7.5"),
        obs_line(scans="sample.Walls;6;2;0;0;0;0;0;0;0"),
        obs_line(scans="sample.Walls;6;0;0.5"),
        obs_line(events='{"type":"x"}'),
        obs_line().split("\t")[0],
        obs_line().rsplit("\t", 1)[0],
        obs_line(history="5;99.5;sample.Walls;80.0"),
        obs_line(history="5;inf;sample.Walls;80.0;77.0"),
    ],
)
def test_bad_observations_rejected(line: str) -> None:
    with pytest.raises(ValueError):
        parse_observation(line, HELLO)


def test_bad_hello_rejected() -> None:
    with pytest.raises(ValueError, match="token"):
        parse_hello(json.dumps(HELLO), "other")
    with pytest.raises(ValueError, match="version"):
        parse_hello(json.dumps({**HELLO, "v": 1}), "t0k")


def test_hello_reply_carries_interval_and_controller() -> None:
    assert BridgeSettings().hello_reply() == "OK 2 1 0 0 0\n"
    assert BridgeSettings(4, history=True, lead=3).hello_reply() == "OK 2 4 3 1 0\n"
    ctl = ControlConfig(power_near=2.5, fire=False)
    lines = BridgeSettings(10, ctl).hello_reply().splitlines()
    n = len(fields(ControlConfig))
    assert lines[0] == f"OK 2 10 0 0 {n}" and len(lines) == n + 1
    assert "power_near 2.5" in lines and "fire 0" in lines and "near_distance 150.0" in lines
    assert f"turn_angle {math.radians(45.0)!r}" in lines
    with pytest.raises(ValueError, match="every"):
        BridgeSettings(0)
    with pytest.raises(ValueError, match="lead"):
        BridgeSettings(4, lead=4)


def test_format_action() -> None:
    assert format_action(7, (10.0, math.nan, -0.25, 1, 0)) == "A 7 10.0 NaN -0.25 1.0 0.0\n"
    with pytest.raises(ValueError, match="5 values"):
        format_action(1, (1.0, 2.0))
    with pytest.raises(ValueError, match="fire"):
        format_action(1, (0, 0, 0, 0, 3.5))
    with pytest.raises(ValueError, match="finite"):
        format_action(1, (math.inf, 0, 0, 0, 0))


def test_reference_policy_aims_at_nearest_enemy() -> None:
    obs = parse_observation(obs_line(heat=0.0), HELLO)
    ahead, body, gun, radar, fire = nearest_enemy_policy(obs)
    # enemy due east (bearing pi/2), gun at 0.5 rad: turn gun by pi/2 - 0.5
    assert gun == pytest.approx(math.pi / 2 - 0.5)
    assert body == pytest.approx(-math.pi)  # perpendicular to the enemy: absolute pi/2 + pi/2, wrapped
    assert fire == 0.0  # not aligned yet
    assert load_policy("confront.engine.bridge:nearest_enemy_policy") is nearest_enemy_policy
    with pytest.raises(ValueError, match="module:function"):
        load_policy("nocolon")


def _lines(sock: socket.socket, n: int) -> list[str]:
    buf = b""
    while buf.count(b"\n") < n:
        chunk = sock.recv(4096)
        if not chunk:
            break
        buf += chunk
    return buf.decode().splitlines()


def test_server_round_trip_on_loopback() -> None:
    seen: list[Observation] = []

    def policy(obs: Observation) -> tuple[float, ...]:
        seen.append(obs)
        return (obs.turn * 1.0, math.nan, 0.0, 0.0, 1.5)

    with BridgeServer(policy, token="t0k", settings=BridgeSettings(every=5)) as server:
        assert server.port > 0
        with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
            s.sendall((json.dumps(HELLO) + "\n").encode())
            assert _lines(s, 1) == ["OK 2 5 0 0 0"]
            s.sendall((obs_line() + "\n" + obs_line(turn=8, scans="", events="[]") + "\n").encode())
            assert _lines(s, 2) == ["A 7 7.0 NaN 0.0 0.0 1.5", "A 8 8.0 NaN 0.0 0.0 1.5"]
            s.sendall(b"E 0 9 death 0.0 2 300 1 9 450\t9;0.0;sample.Walls;50.0;50.0\n")
        with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
            s.sendall((json.dumps({**HELLO, "token": "bad"}) + "\n").encode())
            assert _lines(s, 1) == []  # closed without an answer
        deadline = time.monotonic() + 10  # the server threads finish their bookkeeping after closing
        while time.monotonic() < deadline and (not server.stats.rejected or not server.stats.rounds_ended):
            time.sleep(0.01)
    assert [o.turn for o in seen] == [7, 8] and seen[1].scans == () and seen[1].events == ()
    assert server.stats.decisions == 2 and server.stats.connections == 1 and server.stats.rounds_ended == 1
    assert server.stats.policy_s > 0 and server.stats.handling_s > 0
    st = server.stats
    assert (st.robot_decisions, st.rtt_total_us, st.rtt_over_1ms, st.robot_turns, st.work_us) == (2, 300, 1, 9, 450)
    assert st.errors == [] and st.rejected == {"wrong token": 1}
