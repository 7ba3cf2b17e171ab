"""The bridge server against a hostile local user: bounded reads, hello deadline, connection cap, token checks,
robot statistics validated (no engine needed)."""

from __future__ import annotations

import json
import math
import socket
import threading
import time

import pytest

from confront.engine import bridge
from confront.engine.bridge import BridgeServer, Observation, parse_end, parse_hello

HELLO = {"v": 2, "type": "hello", "token": "t0k", "name": "confront.BridgeBot* (1)", "team": "", "round": 0,
         "rounds": 3, "width": 800.0, "height": 600.0}
OBS = "O 0 7 100.0 200.0 0.0 0.5 1.0 8.0 99.5 0.0 1 12.0\t\t[]\t"


def _rss_mb() -> float:
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmRSS")) / 1024


def _wait(cond, timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if cond():
            return True
        time.sleep(0.01)
    return cond()


class Recorder:
    def __init__(self) -> None:
        self.seen: list[Observation] = []
        self.ends: list[tuple[str, int]] = []

    def __call__(self, obs: Observation) -> tuple[float, ...]:
        self.seen.append(obs)
        return (0.0, 0.0, 0.0, 0.0, 0.0)

    def end_episode(self, robot: str, round_: int) -> None:
        self.ends.append((robot, round_))


def _stream(port: int, head: bytes, total: int) -> int:
    """Send ``head`` then ``total`` bytes of 'x' without a newline; the bytes the server took before closing."""
    sent = 0
    chunk = b"x" * (1 << 20)
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        try:
            s.sendall(head)
            while sent < total:
                s.sendall(chunk)
                sent += len(chunk)
        except OSError:
            pass
    return sent


def test_300_mb_line_before_and_after_the_hello_is_dropped_without_buffering() -> None:
    rec = Recorder()
    with BridgeServer(rec, token="t0k") as server:
        before = _rss_mb()
        sent_anon = _stream(server.port, b"", 300 << 20)
        sent_auth = _stream(server.port, (json.dumps(HELLO) + "\n").encode(), 300 << 20)
        grown = _rss_mb() - before
        assert _wait(lambda: server.stats.errors and server.stats.rejected)
    assert sent_anon < 64 << 20 and sent_auth < 64 << 20  # dropped long before 300 MB (kernel buffers aside)
    assert server.stats.rejected == {"hello line too long": 1}
    assert len(server.stats.errors) == 1 and "longer than" in server.stats.errors[0]
    assert grown < 50 and rec.seen == []


def test_idle_connections_are_capped_and_time_out(monkeypatch) -> None:
    monkeypatch.setattr(bridge, "HELLO_TIMEOUT_S", 0.5)
    threads = threading.active_count()
    with BridgeServer(Recorder(), token="t0k") as server:
        socks = [socket.create_connection(("127.0.0.1", server.port), timeout=10) for _ in range(200)]
        try:
            assert _wait(lambda: sum(server.stats.rejected.values()) >= 200 - bridge.MAX_PENDING)
            assert threading.active_count() <= threads + 1  # no thread per connection before the hello
            assert _wait(lambda: sum(server.stats.rejected.values()) == 200, timeout=5)
            assert server.stats.rejected["no hello in time"] <= bridge.MAX_PENDING
            for s in socks[-5:]:
                assert s.recv(10) == b""  # closed by the server
        finally:
            for s in socks:
                s.close()
        # a robot still gets served afterwards
        with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
            s.sendall((json.dumps(HELLO) + "\n" + OBS + "\n").encode())
            assert s.makefile().readline() == "OK 2 1 0 0 0\n"


def test_wrong_token_flood_reaches_nothing() -> None:
    rec = Recorder()
    with BridgeServer(rec, token="t0k") as server:
        for token in ["bad", "", "t0k ", "T0K", None, 5, ["t0k"]]:
            hello = {**HELLO, "token": token}
            with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
                s.sendall((json.dumps(hello) + "\n" + OBS + "\nE 0 9 death 0.0 1 1 0 9 1\t\n").encode())
                assert s.recv(100) == b""
        assert _wait(lambda: sum(server.stats.rejected.values()) == 7)
    assert rec.seen == [] and rec.ends == [] and server.stats.connections == 0 and server.stats.errors == []


def test_robot_statistics_are_validated() -> None:
    hello = parse_hello(json.dumps(HELLO), "t0k")
    assert parse_end("E 0 9 death 12.5 2 300 1 9 450\t", hello) == (0, (2, 300, 1, 9, 450), ())
    for bad in ["E 0 9 death 12.5 2 300 3 9 450\t",  # more slow round trips than decisions
                "E 0 9 death 12.5 20 300 1 9 450\t",  # more decisions than turns
                "E 0 9 death 12.5 2 -300 1 9 450\t", "E 0 9 death nan 2 300 1 9 450\t",
                "E 1 9 death 12.5 2 300 1 9 450\t",  # another round than the hello's
                "E 0 9 won 12.5 2 300 1 9 450\t", f"E 0 9 death 12.5 2 {2**60} 1 9 450\t",
                "E 0 9 death 12.5 2 300 1 9\t"]:
        with pytest.raises(ValueError):
            parse_end(bad, hello)
    for key, value in [("width", 20000.0), ("round", 3), ("rounds", -1), ("name", ""), ("name", "a\nb"),
                       ("width", math.inf), ("round", True)]:
        with pytest.raises(ValueError):
            parse_hello(json.dumps({**HELLO, key: value}), "t0k")


def test_invented_statistics_end_the_session_and_are_not_counted() -> None:
    rec = Recorder()
    with BridgeServer(rec, token="t0k") as server:
        with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
            s.sendall((json.dumps(HELLO) + "\nE 0 9 death 0.0 99999 1 0 9 1\t\n").encode())
            s.makefile().readline()
        assert _wait(lambda: server.stats.errors)
    assert server.stats.robot_decisions == 0 and server.stats.rounds_ended == 0 and rec.ends == []
    assert "impossible statistics" in server.stats.errors[0]


def test_error_messages_are_bounded() -> None:
    with BridgeServer(Recorder(), token="t0k") as server:
        for _ in range(bridge.MAX_ERRORS + 20):
            with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
                s.sendall((json.dumps(HELLO) + "\ngarbage\n").encode())
                s.makefile().readline()
        assert _wait(lambda: len(server.stats.errors) + server.stats.errors_dropped == bridge.MAX_ERRORS + 20)
    assert len(server.stats.errors) == bridge.MAX_ERRORS and server.stats.errors_dropped == 20


def test_stop_ends_the_server_and_closes_its_sockets() -> None:
    """stop() wakes the accepting thread (no waiting out its select), which closes the listener; a server that was
    never started closes its sockets too."""
    server = BridgeServer(Recorder(), token="t0k").start()
    thread, port = server._thread, server.port
    assert thread is not None and thread.is_alive()
    server.stop()
    assert not thread.is_alive()
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
    idle = BridgeServer(Recorder(), token="t0k")
    idle.stop()
    assert idle._listener.fileno() == -1 and idle._wake_r.fileno() == -1 and idle._wake_w.fileno() == -1
