"""A bridged battle in the real engine while another local process attacks the bridge: a 300 MB line, 500 idle
connections and a flood of hellos with a wrong token. The server's memory stays within +50 MB, the battle plays
every round, and nothing from a connection without the token reaches the learner."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

import pytest

from confront.engine.battle import BattleSpec
from confront.engine.bridge import BridgeServer, BridgeSettings, Observation, nearest_enemy_policy
from confront.engine.bridged import BRIDGE_BOT, BRIDGE_CPU_CONSTANT_MS, bridge_failures, bridge_options
from confront.engine.runner import EngineOptions, run_battle

pytestmark = pytest.mark.engine

ATTACKER = r'''
import json, socket, sys, threading, time
port, seconds = int(sys.argv[1]), float(sys.argv[2])
stop = time.monotonic() + seconds
counts = {"long_sent_mb": 0, "idle": 0, "flood": 0}

def long_line():
    chunk = b"x" * (1 << 20)
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        try:
            for _ in range(300):
                s.sendall(chunk)
                counts["long_sent_mb"] += 1
        except OSError:
            pass

def idle():
    socks = []
    for _ in range(500):
        try:
            socks.append(socket.create_connection(("127.0.0.1", port), timeout=10))
            counts["idle"] += 1
        except OSError:
            pass
    time.sleep(max(0.0, stop - time.monotonic()))
    for s in socks:
        s.close()

def flood():
    hello = {"v": 2, "type": "hello", "token": "guess", "name": "intruder", "team": "", "round": 0,
             "rounds": 3, "width": 800.0, "height": 600.0}
    obs = "O 0 1 4242.0 4242.0 0.0 0.0 0.0 0.0 100.0 0.0 1 0.0\t\t[]\t"
    end = "E 0 9 death 0.0 999 999 0 999 999\t"
    while time.monotonic() < stop:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=2) as s:
                s.sendall((json.dumps(hello) + "\n" + obs + "\n" + end + "\n").encode())
                s.recv(100)
                counts["flood"] += 1
        except OSError:
            pass
        time.sleep(0.002)

threads = [threading.Thread(target=f) for f in (long_line, idle, flood)]
for t in threads:
    t.start()
for t in threads:
    t.join()
print(json.dumps(counts), flush=True)
'''


def _rss_mb() -> float:
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmRSS")) / 1024


def test_battle_survives_a_hostile_local_user(install) -> None:
    seen: list[Observation] = []
    ends: list[str] = []

    class Learner:
        def __call__(self, obs: Observation):
            seen.append(obs)
            return nearest_enemy_policy(obs)

        def end_episode(self, robot: str, round_: int) -> None:
            ends.append(robot)

    rounds = 3
    peak = [0.0]
    done = threading.Event()

    def sample() -> None:
        while not done.is_set():
            peak[0] = max(peak[0], _rss_mb())
            time.sleep(0.02)

    with BridgeServer(Learner(), settings=BridgeSettings(every=5)) as server:
        base = _rss_mb()
        sampler = threading.Thread(target=sample, daemon=True)
        sampler.start()
        attacker = subprocess.Popen([sys.executable, "-c", ATTACKER, str(server.port), "40"],
                                    stdout=subprocess.PIPE, text=True)
        try:
            opts = bridge_options(EngineOptions(seed=3, cpu_constant_ms=BRIDGE_CPU_CONSTANT_MS), server.port,
                                  server.token, 2000)
            run = run_battle(BattleSpec((BRIDGE_BOT, "SittingDuck"), rounds=rounds), opts)
            out, _ = attacker.communicate(timeout=120)
        finally:
            attacker.kill()
            attacker.wait()
            done.set()
            sampler.join()
    counts = __import__("json").loads(out)
    st = server.stats
    print(f"\nserver RSS {base:.1f} MB, peak +{peak[0] - base:.1f} MB; attacker {counts}; rejected {st.rejected}; "
          f"decisions {st.decisions}; failures {bridge_failures(run)}")
    assert peak[0] - base < 50
    assert counts["idle"] == 500 and counts["flood"] > 100 and counts["long_sent_mb"] < 300
    assert run.results.rounds == rounds and len(run.round_turns) == rounds
    assert st.rejected.get("wrong token", 0) >= counts["flood"] - 5
    assert all(o.robot != "intruder" and o.x != 4242.0 for o in seen) and "intruder" not in ends
    assert st.connections == rounds and st.robot_decisions <= st.robot_turns  # only the robot's own sessions
