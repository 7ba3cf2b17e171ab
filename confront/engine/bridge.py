"""Python side of the engine bridge: a loopback TCP server that answers BridgeBot's per-turn requests.

Protocol v1 (one line per message). Robot -> Python: JSON objects, ``{"v": 1, "type": "hello", "token",
"name", "team", "round", "rounds", "width", "height"}`` once per round and connection, then ``"obs"``
every turn (own state, latest scans, events since the last turn), ``"end"`` at death or round end.
Python -> robot: ``OK 1`` after a valid hello, ``A TURN AHEAD TURN GUN RADAR FIRE`` per obs (radians,
+ clockwise; ``NaN`` keeps the remaining value; fire 0 = no shot). A robot whose Python side fails
(no answer within its timeout, closed socket, bad line) plays a built-in behaviour for the rest of the
round and reports ``bridge-failed``; the runner collects those reports.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import math
import secrets
import selectors
import socket
import sys
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

PROTOCOL_VERSION = 1
LOOPBACK = "127.0.0.1"
MAX_LINE = 1 << 20


@dataclass(frozen=True)
class Scan:
    """The latest radar sighting of another robot (absolute x, y computed by the robot)."""

    name: str
    time: int
    teammate: bool
    bearing: float
    distance: float
    heading: float
    velocity: float
    energy: float
    x: float
    y: float


@dataclass(frozen=True)
class Observation:
    """What a bridged tank knows when it decides the commands for engine turn ``turn``."""

    robot: str
    teammates: tuple[str, ...]
    round: int
    turn: int
    x: float
    y: float
    heading: float
    gun_heading: float
    radar_heading: float
    velocity: float
    energy: float
    gun_heat: float
    others: int
    distance_remaining: float
    width: float
    height: float
    scans: tuple[Scan, ...] = ()
    events: tuple[dict, ...] = ()

    def enemies(self) -> tuple[Scan, ...]:
        """Scans of robots that are not team-mates."""
        return tuple(s for s in self.scans if not s.teammate)


Action = Sequence[float]
Policy = Callable[[Observation], Action]

_FLOATS = ("x", "y", "heading", "gun_heading", "radar_heading", "velocity", "energy", "gun_heat",
           "distance_remaining")
_SCAN_FLOATS = ("bearing", "distance", "heading", "velocity", "energy", "x", "y")


def _num(d: dict, key: str) -> float:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ValueError(f"bad or missing number {key!r}: {v!r}")
    return float(v)


def _int(d: dict, key: str) -> int:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, int):
        raise ValueError(f"bad or missing integer {key!r}: {v!r}")
    return v


def _check_version(msg: dict, kind: str) -> None:
    if msg.get("v") != PROTOCOL_VERSION:
        raise ValueError(f"protocol version {msg.get('v')!r} != {PROTOCOL_VERSION}")
    if msg.get("type") != kind:
        raise ValueError(f"expected a {kind!r} message, got type {msg.get('type')!r}")


def parse_hello(line: str, token: str) -> dict:
    """Validate a hello line; returns the message."""
    msg = json.loads(line)
    if not isinstance(msg, dict):
        raise ValueError("hello is not a JSON object")
    _check_version(msg, "hello")
    if not secrets.compare_digest(str(msg.get("token", "")), token):
        raise ValueError("hello with a wrong token")
    if not isinstance(msg.get("name"), str) or not isinstance(msg.get("team"), str):
        raise ValueError("hello without robot name/team")
    for key in ("width", "height"):
        _num(msg, key)
    return msg


def parse_observation(line: str | dict, hello: dict) -> Observation:
    """Validate one obs line (from the robot introduced by ``hello``) into an :class:`Observation`."""
    msg = json.loads(line) if isinstance(line, str) else line
    if not isinstance(msg, dict):
        raise ValueError("observation is not a JSON object")
    _check_version(msg, "obs")
    scans_raw = msg.get("scans")
    events = msg.get("events")
    if not isinstance(scans_raw, list) or not isinstance(events, list):
        raise ValueError("observation needs lists 'scans' and 'events'")
    scans = []
    for s in scans_raw:
        if not isinstance(s, dict) or not isinstance(s.get("name"), str):
            raise ValueError(f"bad scan {s!r}")
        scans.append(Scan(s["name"], _int(s, "time"), bool(s.get("teammate")),
                          *(_num(s, k) for k in _SCAN_FLOATS)))
    floats = {k: _num(msg, k) for k in _FLOATS}
    team = tuple(t for t in hello["team"].split(";") if t)
    return Observation(
        robot=hello["name"], teammates=team, round=_int(msg, "round"), turn=_int(msg, "turn"),
        others=_int(msg, "others"), width=float(hello["width"]), height=float(hello["height"]),
        scans=tuple(scans), events=tuple(e for e in events if isinstance(e, dict)), **floats,
    )


def format_action(turn: int, action: Action) -> str:
    """The answer line for ``turn``; NaN = keep the remaining value; fire outside [0, 3] is an error."""
    vals = [float(v) for v in action]
    if len(vals) != 5:
        raise ValueError(f"action must have 5 values (ahead, turn, gun, radar, fire), got {len(vals)}")
    if any(math.isinf(v) for v in vals):
        raise ValueError(f"action values must be finite or NaN, got {vals}")
    if not math.isnan(vals[4]) and not 0.0 <= vals[4] <= 3.0:
        raise ValueError(f"fire power must be 0 (no shot) or in [0.1, 3], got {vals[4]}")
    return "A " + str(turn) + " " + " ".join("NaN" if math.isnan(v) else repr(v) for v in vals) + "\n"


@dataclass
class BridgeStats:
    """Counters of one server's life."""

    connections: int = 0
    decisions: int = 0
    rounds_ended: int = 0
    errors: list[str] = field(default_factory=list)


@dataclass
class _Conn:
    sock: socket.socket
    buf: bytes = b""
    hello: dict | None = None


class BridgeServer:
    """Serves one policy to every BridgeBot of a battle (team-mates share it) on 127.0.0.1."""

    def __init__(self, policy: Policy, token: str | None = None, port: int = 0) -> None:
        self.policy = policy
        self.token = token if token is not None else secrets.token_hex(16)
        self.stats = BridgeStats()
        self.on_hello: Callable[[dict], None] | None = None
        self._listener = socket.create_server((LOOPBACK, port))
        self._listener.setblocking(False)
        self.port: int = self._listener.getsockname()[1]
        self._sel = selectors.DefaultSelector()
        self._sel.register(self._listener, selectors.EVENT_READ, None)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> BridgeServer:
        """Serve in a daemon thread."""
        self._thread = threading.Thread(target=self.serve_forever, name="confront-bridge", daemon=True)
        self._thread.start()
        return self

    def serve_forever(self) -> None:
        """Accept robots and answer their lines until :meth:`stop`."""
        while not self._stop.is_set():
            for key, _ in self._sel.select(timeout=0.1):
                if key.data is None:
                    self._accept()
                else:
                    self._read(key.data)
        for key in list(self._sel.get_map().values()):
            with contextlib.suppress(OSError):
                key.fileobj.close()  # type: ignore[union-attr]
        self._sel.close()

    def stop(self) -> None:
        """Stop serving and close every socket."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)

    def __enter__(self) -> BridgeServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _accept(self) -> None:
        try:
            sock, _ = self._listener.accept()
        except BlockingIOError:
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.stats.connections += 1
        self._sel.register(sock, selectors.EVENT_READ, _Conn(sock))

    def _drop(self, conn: _Conn, reason: str | None) -> None:
        if reason:
            self.stats.errors.append(reason)
        with contextlib.suppress(KeyError, ValueError):
            self._sel.unregister(conn.sock)
        conn.sock.close()

    def _read(self, conn: _Conn) -> None:
        try:
            data = conn.sock.recv(65536)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as err:
            self._drop(conn, f"recv: {err}")
            return
        if not data:
            self._drop(conn, None)
            return
        conn.buf += data
        if len(conn.buf) > MAX_LINE:
            self._drop(conn, "line too long")
            return
        while b"\n" in conn.buf:
            line, conn.buf = conn.buf.split(b"\n", 1)
            try:
                reply = self._handle(conn, line.decode("utf-8"))
                if reply:
                    conn.sock.setblocking(True)
                    conn.sock.sendall(reply.encode())
                    conn.sock.setblocking(False)
            except Exception as err:  # a bad message or a failing policy ends this robot's session
                name = conn.hello["name"] if conn.hello else "?"
                self._drop(conn, f"{name}: {type(err).__name__}: {err}")
                return

    def _handle(self, conn: _Conn, line: str) -> str | None:
        if conn.hello is None:
            conn.hello = parse_hello(line, self.token)
            if self.on_hello is not None:
                self.on_hello(conn.hello)
            return f"OK {PROTOCOL_VERSION}\n"
        msg = json.loads(line)
        if isinstance(msg, dict) and msg.get("type") == "end":
            _check_version(msg, "end")
            self.stats.rounds_ended += 1
            return None
        obs = parse_observation(msg, conn.hello)
        action = self.policy(obs)
        self.stats.decisions += 1
        return format_action(obs.turn, action)


def nearest_enemy_policy(obs: Observation) -> Action:
    """A simple reference policy: radar sweeps, gun aims at the nearest seen enemy, circle it, fire."""
    enemies = obs.enemies()
    radar = 2 * math.pi if not enemies else math.nan
    if not enemies:
        return (100.0 if obs.distance_remaining == 0 else math.nan, math.nan, math.nan, radar, 0.0)
    e = min(enemies, key=lambda s: s.distance)
    absolute = math.atan2(e.x - obs.x, e.y - obs.y)  # Robocode bearing: 0 = north, clockwise
    gun = (absolute - obs.gun_heading + math.pi) % (2 * math.pi) - math.pi
    body = (absolute + math.pi / 2 - obs.heading + math.pi) % (2 * math.pi) - math.pi
    radar_turn = (absolute - obs.radar_heading + math.pi) % (2 * math.pi) - math.pi
    radar_turn += math.copysign(0.3, radar_turn) if radar_turn else 0.3
    fire = 2.0 if abs(gun) < 0.1 and obs.gun_heat == 0 and obs.energy > 2 else 0.0
    ahead = 80.0 if (obs.turn // 40) % 2 == 0 else -80.0
    return (ahead, body, gun, radar_turn, fire)


def load_policy(ref: str) -> Policy:
    """A policy from 'package.module:function'."""
    mod, sep, name = ref.partition(":")
    if not sep or not mod or not name:
        raise ValueError(f"policy must be 'module:function', got {ref!r}")
    return getattr(importlib.import_module(mod), name)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m confront.engine.bridge PORT TOKEN [module:function]``: serve in this process."""
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) not in (2, 3):
        print(main.__doc__)
        return 2
    policy = load_policy(args[2]) if len(args) == 3 else nearest_enemy_policy
    server = BridgeServer(policy, token=args[1], port=int(args[0]))
    server.on_hello = lambda h: print(f"hello {h['name']} round {h['round']}", flush=True)
    print(f"ready {server.port}", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
