"""Python side of the engine bridge: a loopback TCP server that answers BridgeBot's requests.

Protocol v2, one line per message (UTF-8). Robot -> Python:
- once per round and connection, JSON ``{"v": 2, "type": "hello", "token", "name", "team" (team-mates'
  names joined by ";"), "round", "rounds", "width", "height"}``;
- for the decision turns 1, 1 + EVERY, 1 + 2 EVERY, ... (sent LEAD turns before them, the first in turn 1)
  ``O ROUND TURN X Y HEADING GUN_HEADING RADAR_HEADING VELOCITY ENERGY GUN_HEAT OTHERS
  DISTANCE_REMAINING<TAB>SCANS<TAB>EVENTS<TAB>HISTORY``: SCANS is the latest sighting of each robot, joined
  by "|", each ``NAME;TIME;TEAMMATE(0/1);BEARING;DISTANCE;HEADING;VELOCITY;ENERGY;X;Y``; EVENTS a JSON list
  of the events since the last observation; HISTORY (empty unless asked for) one
  ``TIME;ENERGY;TARGET;TARGET_PREVIOUS;TARGET_ENERGY`` record per turn since the last observation, joined by
  "|" (:class:`TurnEnergy`); TURN is the engine turn the answer takes effect in; when the robot acts on its own
  (ACTING below) a fifth field<TAB>MOVE;BEHIND;AHEAD carries the move (0-3) it took in that turn, how many of
  its observations were still unacknowledged when it chose it and counted for that move (WAIT below; 0: its
  copy had every update up to its last observation that could change the move) and how many more were
  unacknowledged but could not change it (the robot went on without waiting for them), and nothing is answered;
- ``E ROUND TIME HOW ENERGY DECISIONS RTT_TOTAL_US RTT_OVER_1MS TURNS WORK_US<TAB>HISTORY`` at death or
  round end: the round's decisions, the time the robot was held up by their round trips and how many took
  over 1 ms, the turns played and the robot's own time outside ``execute()`` (deciding and the controller),
  and the history records since the last observation.
Python -> robot: ``OK 2 EVERY LEAD HISTORY(0/1) N [M]`` after a valid hello (:class:`BridgeSettings`), followed
by N ``key value`` lines: the parameters of the fixed gun/radar controller
(:class:`~confront.arena.control.ControlConfig`) that the robot then runs in Java every turn (N = 0: no
controller, the answers' gun, radar and fire are used); then, when M is given, M lines: ``acting EXPLORE
PARAM SEED MAX_LAG WAIT FIXED`` and the policy file of the robot's own copy of the policy (PolicyModel's, e.g. the
learner's current Q table), with which the robot then picks its moves itself (:class:`RobotActing`).
``A TURN AHEAD TURN GUN RADAR FIRE`` per observation when Python decides (radians, + clockwise; ``NaN`` keeps
the remaining value; fire 0 = no shot). When the robot acts: ``K TURN`` acknowledges its observation of TURN
once the policy has taken it in (the robot stops and waits, at most its timeout, when MAX_LAG observations
are unacknowledged; with WAIT ``row`` only those whose update could change the move it draws count,
:class:`RobotActing`), and at any time, to every acting robot of the battle, ``Q STATE V0 V1 V2 V3`` (a row
of the Q table changed) and ``X PARAM FIXED`` (the exploration parameter now; FIXED 1: it no longer changes,
as in the hello's acting line). Between decisions
the robot's commands keep running (remaining distance and turns) with no round trip. A compact text line
instead of JSON keeps the cost low (measured: docs/engine.md). A robot whose Python side fails (no answer
within its timeout, closed socket, bad line) plays a built-in behaviour for the rest of the round and
reports ``bridge-failed``; the runner collects those reports.

Against other local users: the robots get the token from the engine's environment (``CONFRONT_BRIDGE_TOKEN``,
readable only by its user), the server reads hellos with a bounded buffer, a deadline and a cap on waiting
connections, lines of a session up to ``MAX_LINE`` bytes, and checks a robot's end-of-round statistics before
they are counted (:class:`BridgeServer`, :func:`parse_end`).
"""

from __future__ import annotations

import contextlib
import importlib
import json
import math
import os
import secrets
import selectors
import socket
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

from confront.arena.control import ControlConfig

PROTOCOL_VERSION = 2
LOOPBACK = "127.0.0.1"
TOKEN_ENV = "CONFRONT_BRIDGE_TOKEN"  # how the robots get the token: the engine's environment, not its command line
MAX_LINE = 1 << 20  # longest line of a robot that presented the token (bytes); longer: the connection is dropped
MAX_HELLO = 1 << 14  # longest hello line (bytes), read before the token is known
HELLO_TIMEOUT_S = 5.0  # a connection that has not sent a complete hello by then is dropped
MAX_PENDING = 64  # connections waiting for their hello; a newer one beyond this drops the oldest
MAX_ROBOTS = 256  # robot sessions (connections that presented the token) at once; more are refused
MAX_ERRORS = 100  # error messages kept (the rest are only counted)
MAX_NAMES = 1000  # characters of a hello's name and team fields
BATTLEFIELD = (400.0, 5000.0)  # Robocode's battlefield width and height range [BattlefieldSpecification]
_STAT_MAX = 1 << 53  # robot-reported counters above this are not believed


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
class TurnEnergy:
    """One turn's energies for the paper's per-turn reward (Eq. 35): own, and the target's (the nearest enemy
    by last scans, "" if none) at the previous record and now."""

    time: int
    energy: float
    target: str
    target_previous: float
    target_energy: float


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
    events: tuple[dict[str, Any], ...] = ()
    history: tuple[TurnEnergy, ...] = ()  # with BridgeSettings.history: each turn since the last observation
    action: int = -1  # the move the robot took itself (BridgeSettings.acting); -1: the policy decides
    behind: int = 0  # acting: the robot's observations not yet acknowledged when it chose that move (that count)
    ahead: int = 0  # acting, WAIT row: and those not yet acknowledged whose update could not change that move

    def enemies(self) -> tuple[Scan, ...]:
        """Scans of robots that are not team-mates."""
        return tuple(s for s in self.scans if not s.teammate)


Action = Sequence[float]
Policy = Callable[[Observation], Action]


EXPLORE_KINDS = ("first", "greedy", "boltzmann", "egreedy")
WAIT_KINDS = ("all", "row")


@dataclass(frozen=True)
class RobotActing:
    """The robots pick their moves themselves from their own copy of the policy; Python only learns.

    ``model()``: the current policy file (PolicyModel's format: ``ExportedPolicy.to_text()``), sent in each
    hello reply (a new robot object every round gets the policy as it is then). ``explore``: how the robot picks
    from the move values: ``first`` (the first maximum, as the exported robot), ``greedy`` (a maximum, ties at
    random), ``boltzmann`` (softmax at temperature ``param()``), ``egreedy`` (greedy with probability
    ``param()``, else uniform). ``seed()``: the robot's random generator per connection. ``updates()``: the
    lines (``Q STATE V0 V1 V2 V3``, ``X PARAM FIXED``) that bring every connected robot's copy up to date, drained
    after each message the policy took in. ``max_lag``: a robot waits (at most its timeout) when this many of its
    observations are not yet acknowledged, so its copy is never more than ``max_lag`` observations behind; with
    ``wait="row"`` only the observations count whose update could change the move the robot is drawing: those
    whose learned SMDP step starts in the state it decides in (a learner learns, at a robot's observation k, the
    step from its decision k - 1, i.e. that state's row), and every one while the exploration parameter may still
    change (``fixed()`` False; FIXED in the ``X`` lines: 1 once the parameter no longer changes). The rows the
    others change are not read by that move, so with ``max_lag`` = 1 each move is still drawn from exactly what a
    copy with every update up to the robot's previous observation holds, and the robot waits far less often.
    """

    model: Callable[[], str]
    explore: str = "first"
    param: Callable[[], float] = lambda: 0.0
    seed: Callable[[], int] = lambda: 0
    updates: Callable[[], list[str]] = list
    max_lag: int = 4
    wait: str = "all"
    fixed: Callable[[], bool] = lambda: False

    def __post_init__(self) -> None:
        if self.explore not in EXPLORE_KINDS:
            raise ValueError(f"explore must be one of {EXPLORE_KINDS}, got {self.explore!r}")
        if self.wait not in WAIT_KINDS:
            raise ValueError(f"wait must be one of {WAIT_KINDS}, got {self.wait!r}")
        if not 1 <= self.max_lag <= 1000:
            raise ValueError(f"max_lag must be in [1, 1000], got {self.max_lag}")

    def hello_lines(self) -> list[str]:
        """``acting EXPLORE PARAM SEED MAX_LAG WAIT FIXED`` and the policy file's lines."""
        param = float(self.param())
        if not (param > 0 if self.explore == "boltzmann" else 0 <= param <= 1) or not math.isfinite(param):
            raise ValueError(f"exploration parameter must be finite and a temperature > 0 (boltzmann) or a "
                             f"threshold in [0, 1], got {param} for {self.explore}")
        seed = int(self.seed()) & ((1 << 63) - 1)
        fixed = int(bool(self.fixed()))
        return [f"acting {self.explore} {param!r} {seed} {self.max_lag} {self.wait} {fixed}",
                *self.model().splitlines()]


@dataclass(frozen=True)
class BridgeSettings:
    """What the robots do on their own: how often they ask the policy, and whether they aim by themselves.

    ``every``: the robots ask in turns 1, 1 + every, ... (the paper's SMDP step T); the commands keep running
    in between. ``controller``: run this fixed gun/radar controller in Java every turn (PolicyModel's, the
    exported robot's), so a policy that decides only the move needs no round trip between decisions; None:
    the policy's gun, radar and fire answers are used (and hold between decisions). ``history``: the robots
    record every turn's energies (:class:`TurnEnergy`) and send them with the next observation
    (``Observation.history``) and at death or round end, where the policy's ``end_episode(robot, round,
    history)`` gets them (so per-turn rewards need no per-turn round trip). ``lead``: send the observation
    this many turns before its decision turn and read the answer in that turn, so the policy runs while the
    engine plays on (the decision then rests on a state ``lead`` turns old; the first of a round is taken in
    turn 1 as usual); 0 = ask and wait in the decision turn (what the exported robot and the simulator do).
    ``acting``: the robots pick their moves from their own copy of the policy and never wait for an answer
    (:class:`RobotActing`; needs the controller, no lead): the engine then runs at the exported robot's speed
    while Python learns from the observations, at the price of a copy that lags the learner by up to
    ``max_lag`` observations.
    """

    every: int = 1
    controller: ControlConfig | None = None
    history: bool = False
    lead: int = 0
    acting: RobotActing | None = None

    def __post_init__(self) -> None:
        if self.every < 1:
            raise ValueError(f"every must be >= 1, got {self.every}")
        if not 0 <= self.lead < self.every:
            raise ValueError(f"lead must be in [0, every) = [0, {self.every}), got {self.lead}")
        if self.acting is not None and (self.controller is None or self.lead):
            raise ValueError("robots that act themselves need the controller in Java and no lead")

    def hello_reply(self) -> str:
        """``OK 2 EVERY LEAD HISTORY N``, the controller's N ``key value`` lines (the policy file's); for robots
        that act themselves ``OK 2 EVERY LEAD HISTORY N M`` and after those the M lines of the robot's own policy
        (:meth:`RobotActing.hello_lines`)."""
        lines = controller_lines(self.controller) if self.controller is not None else []
        acting = self.acting.hello_lines() if self.acting is not None else []
        first = f"OK {PROTOCOL_VERSION} {self.every} {self.lead} {int(self.history)} {len(lines)}"
        first += f" {len(acting)}" if acting else ""
        return "".join(line + "\n" for line in [first, *lines, *acting])


def controller_lines(control: ControlConfig) -> list[str]:
    """The controller's parameters as the ``key value`` lines that PolicyModel.java reads."""
    out = []
    for f in fields(ControlConfig):
        v = getattr(control, f.name)
        out.append(f"{f.name} {int(v) if isinstance(v, bool) else repr(float(v))}")
    return out


def _num(d: dict[str, Any], key: str) -> float:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ValueError(f"bad or missing number {key!r}: {v!r}")
    return float(v)


def _check_version(msg: dict[str, Any], kind: str) -> None:
    if msg.get("v") != PROTOCOL_VERSION:
        raise ValueError(f"protocol version {msg.get('v')!r} != {PROTOCOL_VERSION}")
    if msg.get("type") != kind:
        raise ValueError(f"expected a {kind!r} message, got type {msg.get('type')!r}")


def parse_hello(line: str, token: str) -> dict[str, Any]:
    """Validate a hello line; returns the message. The token is checked before anything else is trusted."""
    msg = json.loads(line)
    if not isinstance(msg, dict):
        raise ValueError("hello is not a JSON object")
    if not isinstance(msg.get("token"), str) or not secrets.compare_digest(msg["token"].encode(), token.encode()):
        raise ValueError("hello with a wrong token")
    _check_version(msg, "hello")
    for key in ("name", "team"):
        if not isinstance(msg.get(key), str) or not 0 < len(msg[key]) <= MAX_NAMES or not msg[key].isprintable():
            if key == "team" and msg.get(key) == "":
                continue
            raise ValueError(f"hello without a printable robot {key} of at most {MAX_NAMES} characters")
    for key in ("width", "height"):
        if not BATTLEFIELD[0] <= _num(msg, key) <= BATTLEFIELD[1]:
            raise ValueError(f"hello {key} {msg[key]!r} outside Robocode's {BATTLEFIELD[0]}-{BATTLEFIELD[1]}")
    for key in ("round", "rounds"):
        if isinstance(msg.get(key), bool) or not isinstance(msg.get(key), int):
            raise ValueError(f"hello without an integer {key!r}")
    if not 0 <= msg["round"] < msg["rounds"]:
        raise ValueError(f"hello round {msg['round']} outside [0, rounds = {msg['rounds']})")
    return msg


def _finite(text: str, what: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ValueError(f"non-finite {what}: {text!r}")
    return v


_OBS_FIELDS = 13


def _floats(texts: Sequence[str], what: str) -> list[float]:
    vals = [float(v) for v in texts]
    if not all(map(math.isfinite, vals)):
        raise ValueError(f"non-finite {what}: {texts}")
    return vals


def parse_observation(line: str, hello: dict[str, Any], acting: bool = False) -> Observation:
    """Validate one ``O ...`` line (from the robot introduced by ``hello``) into an :class:`Observation`;
    ``acting``: the line must end with the move the robot took (0-3) and how far its copy was behind."""
    parts = line.split("\t")
    head = parts[0].split(" ")
    if len(parts) != 4 + acting or head[0] != "O" or len(head) != _OBS_FIELDS:
        raise ValueError(f"bad observation line: {line[:80]!r}")
    action, behind, ahead = -1, 0, 0
    if acting:
        move = parts[4].split(";")
        if len(move) != 3:
            raise ValueError(f"bad move field {parts[4][:40]!r}: MOVE;BEHIND;AHEAD")
        action, behind, ahead = int(move[0]), int(move[1]), int(move[2])
        if not 0 <= action < 4 or not 0 <= behind <= 1000 or not 0 <= ahead <= 1000 - behind:
            raise ValueError(f"bad move field {parts[4][:40]!r}: MOVE (0-3);BEHIND;AHEAD (together 0-1000)")
    rnd, turn, others = int(head[1]), int(head[2]), int(head[11])
    if rnd != hello["round"] or turn < 0 or others < 0:
        raise ValueError(f"observation of round {rnd}, turn {turn}, others {others} on the connection of round "
                         f"{hello['round']}")
    x, y, heading, gun, radar, vel, energy, heat = _floats(head[3:11], "state value")
    remaining = _finite(head[12], "distance_remaining")
    scans = []
    for item in parts[1].split("|") if parts[1] else ():
        f = item.split(";")
        if len(f) != 10 or f[2] not in ("0", "1"):
            raise ValueError(f"bad scan: {item[:80]!r}")
        scans.append(Scan(f[0], int(f[1]), f[2] == "1", *_floats(f[3:], "scan value")))
    events: tuple[dict[str, Any], ...] = ()
    if parts[2] != "[]":
        raw = json.loads(parts[2])
        if not isinstance(raw, list) or not all(isinstance(e, dict) for e in raw):
            raise ValueError(f"events must be a JSON list of objects: {parts[2][:80]!r}")
        events = tuple(raw)
    team = tuple(t for t in hello["team"].split(";") if t)
    return Observation(
        robot=hello["name"], teammates=team, round=rnd, turn=turn, x=x, y=y, heading=heading,
        gun_heading=gun, radar_heading=radar, velocity=vel, energy=energy, gun_heat=heat, others=others,
        distance_remaining=remaining, width=float(hello["width"]), height=float(hello["height"]),
        scans=tuple(scans), events=events, history=parse_history(parts[3]), action=action, behind=behind,
        ahead=ahead,
    )


def parse_history(text: str) -> tuple[TurnEnergy, ...]:
    """``TIME;ENERGY;TARGET;TARGET_PREVIOUS;TARGET_ENERGY`` records joined by "|" (empty: none)."""
    out = []
    isfinite = math.isfinite
    for item in text.split("|") if text else ():
        f = item.split(";")
        if len(f) != 5:
            raise ValueError(f"bad history record: {item[:80]!r}")
        own, prev, now = float(f[1]), float(f[3]), float(f[4])
        if not (isfinite(own) and isfinite(prev) and isfinite(now)):
            raise ValueError(f"non-finite history value: {item[:80]!r}")
        out.append(TurnEnergy(int(f[0]), own, f[2], prev, now))
    return tuple(out)


def format_observation(obs: Observation) -> str:
    """The ``O ...`` line of an observation (inverse of :func:`parse_observation`), e.g. to record it."""
    head = [obs.round, obs.turn, obs.x, obs.y, obs.heading, obs.gun_heading, obs.radar_heading, obs.velocity,
            obs.energy, obs.gun_heat, obs.others, obs.distance_remaining]
    scans = "|".join(
        ";".join([s.name, str(s.time), "1" if s.teammate else "0"]
                 + [repr(v) for v in (s.bearing, s.distance, s.heading, s.velocity, s.energy, s.x, s.y)])
        for s in obs.scans
    )
    history = "|".join(f"{h.time};{h.energy!r};{h.target};{h.target_previous!r};{h.target_energy!r}"
                       for h in obs.history)
    return ("O " + " ".join(repr(v) for v in head) + "\t" + scans + "\t" + json.dumps(list(obs.events)) + "\t"
            + history + ("" if obs.action < 0 else f"\t{obs.action};{obs.behind};{obs.ahead}"))


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


def parse_end(line: str, hello: dict[str, Any]) -> tuple[int, tuple[int, ...], tuple[TurnEnergy, ...]]:
    """Validate an ``E ...`` line: (round, (DECISIONS, RTT_TOTAL_US, RTT_OVER_1MS, TURNS, WORK_US), history).

    The statistics go into a run's files, so they must be what a robot can report: counters >= 0, at most as
    many slow round trips as decisions and as many decisions as turns, the round of the robot's hello."""
    tab = line.split("\t")
    parts = tab[0].split(" ")
    if len(parts) != 10 or len(tab) != 2 or parts[0] != "E" or parts[3] not in ("death", "round_end"):
        raise ValueError(f"bad end line: {line[:80]!r}")
    rnd, time_ = int(parts[1]), int(parts[2])
    if rnd != hello["round"]:
        raise ValueError(f"end line for round {rnd} on the connection of round {hello['round']}")
    energy = _finite(parts[4], "energy")
    n, rtt, slow, turns, work = (int(v) for v in parts[5:])
    if time_ < 0 or energy < 0 or not 0 <= slow <= n <= turns <= _STAT_MAX or not 0 <= rtt <= _STAT_MAX \
            or not 0 <= work <= _STAT_MAX:
        raise ValueError(f"end line with impossible statistics: {tab[0][:120]!r}")
    return rnd, (n, rtt, slow, turns, work), parse_history(tab[1])


@dataclass
class BridgeStats:
    """Counters of one server's life. ``errors`` are the sessions of robots that presented the token (at most
    ``MAX_ERRORS`` kept, ``errors_dropped`` counts the rest); connections that never did are only counted in
    ``rejected`` by reason, and nothing they sent reaches the policy."""

    connections: int = 0
    decisions: int = 0
    rounds_ended: int = 0
    errors: list[str] = field(default_factory=list)
    errors_dropped: int = 0
    resets: int = 0  # sessions the robot's side reset: the engine stops robot threads at a round's end
    rejected: dict[str, int] = field(default_factory=dict)
    behind: int = 0  # acting robots: decisions taken while some of the robot's own observations that count for the
    # move (WAIT) were unacknowledged
    ahead: int = 0  # acting robots, WAIT row: decisions taken without waiting for acknowledgements that did not count
    policy_s: float = 0.0  # time inside the policy
    handling_s: float = 0.0  # the server's own time per decision: parse, format, send (policy excluded)
    parse_s: float = 0.0  # of which parsing the observation
    send_s: float = 0.0  # of which sending the answer
    # as the robots measured them (sums over the rounds they ended while connected)
    robot_decisions: int = 0
    rtt_total_us: int = 0
    rtt_over_1ms: int = 0
    robot_turns: int = 0
    work_us: int = 0

    def add_round_end(self, fields: Sequence[int]) -> None:
        """Add a robot's round statistics (validated by :func:`parse_end`): DECISIONS RTT_TOTAL_US RTT_OVER_1MS
        TURNS WORK_US."""
        n, rtt, slow, turns, work = fields
        self.robot_decisions += n
        self.rtt_total_us += rtt
        self.rtt_over_1ms += slow
        self.robot_turns += turns
        self.work_us += work


class LineReader:
    """Lines from a socket with a bounded buffer: a line longer than ``limit`` bytes raises ValueError as soon
    as the buffer passes the limit (nothing beyond it is kept)."""

    def __init__(self, sock: socket.socket, limit: int = MAX_LINE, first: bytes = b"") -> None:
        self.sock, self.limit = sock, limit
        self.buf = bytearray(first)

    def readline(self) -> str | None:
        """The next line without its newline (UTF-8), or None when the peer closed the connection."""
        while True:
            i = self.buf.find(b"\n")
            if i >= 0:
                line = bytes(self.buf[:i])
                del self.buf[: i + 1]
                return line.decode("utf-8")
            if len(self.buf) > self.limit:
                raise ValueError(f"line longer than {self.limit} bytes")
            chunk = self.sock.recv(1 << 16)
            if not chunk:
                return None
            self.buf += chunk


@dataclass
class _Pending:
    deadline: float
    buf: bytearray = field(default_factory=bytearray)


class BridgeServer:
    """Serves one policy to every BridgeBot of a battle (team-mates share it) on 127.0.0.1.

    One thread accepts connections and reads their hellos without blocking: a hello must be complete within
    ``HELLO_TIMEOUT_S`` and ``MAX_HELLO`` bytes, at most ``MAX_PENDING`` connections wait for theirs (a newer
    one drops the oldest), and only a hello with the token starts a session. Each session is served by its own
    thread with blocking reads (the fewest system calls per turn) of lines up to ``MAX_LINE`` bytes; policy
    calls are serialised by a lock, so the policy need not be thread-safe.
    """

    def __init__(
        self, policy: Policy, token: str | None = None, port: int = 0, settings: BridgeSettings | None = None
    ) -> None:
        self.policy = policy
        self.settings = settings or BridgeSettings()
        self._reply = self.settings.hello_reply().encode()
        self.token = token if token is not None else secrets.token_hex(16)
        self.stats = BridgeStats()
        self.on_hello: Callable[[dict], None] | None = None
        self._listener = socket.create_server((LOOPBACK, port), backlog=256)
        self._listener.setblocking(False)
        self.port: int = self._listener.getsockname()[1]
        self._stop = threading.Event()
        self._wake_r, self._wake_w = socket.socketpair()  # stop() wakes the accepting thread's select at once
        self._lock = threading.Lock()
        self._conns: set[socket.socket] = set()
        self._acting: dict[socket.socket, str] = {}  # robots that act themselves: their update streams
        self._sessions: list[threading.Thread] = []
        self._thread: threading.Thread | None = None

    def start(self) -> BridgeServer:
        """Accept robots in a daemon thread."""
        self._thread = threading.Thread(target=self.serve_forever, name="confront-bridge", daemon=True)
        self._thread.start()
        return self

    def serve_forever(self) -> None:
        """Accept robots and read their hellos until :meth:`stop`; each session runs in its own thread."""
        sel = selectors.DefaultSelector()
        sel.register(self._listener, selectors.EVENT_READ)
        sel.register(self._wake_r, selectors.EVENT_READ)
        pending: dict[socket.socket, _Pending] = {}  # insertion order: oldest first
        try:
            while not self._stop.is_set():
                ready = sel.select(timeout=0.1)
                listening = False
                for key, _ in ready:  # hellos first, so a burst of new connections cannot push them out
                    if key.fileobj is self._listener:
                        listening = True
                    elif key.fileobj is self._wake_r:
                        continue  # stop() was called: the loop's test ends it
                    else:
                        self._read_hello(key.fileobj, pending, sel)  # type: ignore[arg-type]
                if listening:
                    self._accept(pending, sel)
                now = time.monotonic()
                for sock in [s for s, p in pending.items() if p.deadline < now]:
                    self._drop(sock, pending, sel, "no hello in time")
        finally:
            for sock in list(pending):
                self._drop(sock, pending, sel, None)
            sel.close()
            self._listener.close()
            self._wake_r.close()

    def _accept(self, pending: dict[socket.socket, _Pending], sel: selectors.BaseSelector) -> None:
        for _ in range(16):  # a few per pass, then the pending hellos are read again
            try:
                sock, _ = self._listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as err:  # e.g. out of file descriptors: keep serving, try again in the next pass
                if not self._stop.is_set():
                    with self._lock:
                        reason = f"accept failed: {err.strerror}"
                        self.stats.rejected[reason] = self.stats.rejected.get(reason, 0) + 1
                    time.sleep(0.01)  # the listener stays readable: do not spin
                return
            sock.setblocking(False)
            while len(pending) >= MAX_PENDING:
                self._drop(next(iter(pending)), pending, sel, "too many connections without a hello")
            pending[sock] = _Pending(time.monotonic() + HELLO_TIMEOUT_S)
            sel.register(sock, selectors.EVENT_READ)
            self._read_hello(sock, pending, sel)  # a robot sends its hello right after connecting

    def _drop(self, sock: socket.socket, pending: dict[socket.socket, _Pending], sel: selectors.BaseSelector,
              reason: str | None) -> None:
        pending.pop(sock, None)
        with contextlib.suppress(KeyError, ValueError):
            sel.unregister(sock)
        sock.close()
        if reason is not None:
            with self._lock:
                self.stats.rejected[reason] = self.stats.rejected.get(reason, 0) + 1

    def _read_hello(self, sock: socket.socket, pending: dict[socket.socket, _Pending],
                    sel: selectors.BaseSelector) -> None:
        p = pending.get(sock)
        if p is None:
            return
        try:
            chunk = sock.recv(MAX_HELLO + 1 - len(p.buf))
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._drop(sock, pending, sel, "connection error before the hello")
            return
        if not chunk:
            self._drop(sock, pending, sel, "closed before the hello")
            return
        p.buf += chunk
        end = p.buf.find(b"\n")
        if end < 0:
            if len(p.buf) > MAX_HELLO:
                self._drop(sock, pending, sel, "hello line too long")
            return
        try:
            hello = parse_hello(p.buf[:end].decode("utf-8"), self.token)
        except (ValueError, RecursionError) as err:  # JSON and Unicode errors are ValueErrors
            self._drop(sock, pending, sel, "wrong token" if "token" in str(err) else "bad hello")
            return
        rest = bytes(p.buf[end + 1:])
        pending.pop(sock)
        sel.unregister(sock)
        with self._lock:
            if len(self._conns) >= MAX_ROBOTS:
                full = True
            else:
                full = False
                self._conns.add(sock)
                self.stats.connections += 1
        if full:
            sock.close()
            self._error(f"{hello['name']}: refused, {MAX_ROBOTS} robots already connected")
            return
        thread = threading.Thread(target=self._serve, args=(sock, hello, rest), daemon=True)
        with self._lock:
            self._sessions = [t for t in self._sessions if t.is_alive()] + [thread]
        thread.start()

    def stop(self, drain_s: float = 5.0) -> None:
        """Stop serving and close every socket. Sessions first get up to ``drain_s`` seconds to take in what
        their robot sent before it closed its end: a robot's last end line may still be unread when the engine
        exits (robots acting themselves do not even wait for their last observations to be read)."""
        self._stop.set()
        with contextlib.suppress(OSError):
            self._wake_w.send(b"\0")
        self._wake_w.close()
        if self._thread is not None:
            self._thread.join(timeout=5)
        else:  # never started: serve_forever did not run to close these
            self._wake_r.close()
            self._listener.close()
        deadline = time.monotonic() + drain_s
        with self._lock:
            sessions = list(self._sessions)
        for thread in sessions:
            thread.join(timeout=max(0.0, deadline - time.monotonic()))
        with self._lock:
            for sock in self._conns:
                with contextlib.suppress(OSError):
                    sock.shutdown(socket.SHUT_RDWR)
                sock.close()

    def __enter__(self) -> BridgeServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _error(self, text: str) -> None:
        with self._lock:
            self._error_locked(text)

    def _error_locked(self, text: str) -> None:
        if len(self.stats.errors) < MAX_ERRORS:
            self.stats.errors.append(text[:500])
        else:
            self.stats.errors_dropped += 1

    def _broadcast(self, lines: list[str], owner: socket.socket | None, ack: str) -> None:
        """Send update ``lines`` to every acting robot and ``ack`` to ``owner`` (lock held). Never blocks: a
        robot whose buffer is full (it stopped reading) is cut off, and its robot falls back."""
        text = "".join(line + "\n" for line in lines)
        for sock, name in list(self._acting.items()):
            data = (text + ack if sock is owner else text).encode()
            if not data:
                continue
            try:
                if sock.send(data, socket.MSG_DONTWAIT) == len(data):
                    continue
            except BlockingIOError:
                pass
            except OSError:  # the robot closed its end (its round is over): its own session ends it
                del self._acting[sock]
                continue
            del self._acting[sock]  # its buffer is full: it stopped reading, so its copy cannot be kept current
            self._error_locked(f"{name}: stopped reading its policy updates; connection closed")
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)

    def _serve(self, sock: socket.socket, hello: dict[str, Any], rest: bytes) -> None:
        """One robot's session after a valid hello: observations answered, one end line, then the socket closes."""
        ended = False
        try:
            sock.settimeout(HELLO_TIMEOUT_S)  # the reply is small; a robot that does not read it is dropped
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            if self.on_hello is not None:
                self.on_hello(hello)
            acting = self.settings.acting
            if acting is None:
                sock.sendall(self._reply)
            else:
                with self._lock:  # the policy as it is now, and from now on every update to it
                    sock.sendall(self.settings.hello_reply().encode())
                    self._acting[sock] = hello["name"]
            sock.settimeout(None)
            lines = LineReader(sock, MAX_LINE, rest)
            while (line := lines.readline()) is not None:
                if line.startswith("E "):
                    if ended:
                        raise ValueError("a second end line on one connection")
                    ended = True
                    rnd, numbers, history = parse_end(line, hello)
                    with self._lock:
                        self._acting.pop(sock, None)
                        self.stats.rounds_ended += 1
                        self.stats.add_round_end(numbers)
                        end = getattr(self.policy, "end_episode", None)
                        if end is not None and self.settings.history:
                            end(hello["name"], rnd, history)
                        elif end is not None:  # e.g. a learner's last SMDP step of the round
                            end(hello["name"], rnd)
                        if acting is not None:
                            self._broadcast(acting.updates(), None, "")
                else:
                    if ended:
                        raise ValueError("an observation after the end line")
                    t0 = time.perf_counter()
                    obs = parse_observation(line, hello, acting is not None)
                    parsed = time.perf_counter()
                    with self._lock:  # waiting here (team-mates' decisions) is counted nowhere
                        t1 = time.perf_counter()
                        action = self.policy(obs)
                        t2 = time.perf_counter()
                        if acting is not None:  # the robot has moved already: bring every copy up to date
                            self._broadcast(acting.updates(), sock, f"K {obs.turn}\n")
                    t25 = t3 = time.perf_counter()
                    if acting is None:
                        data = format_action(obs.turn, action).encode()
                        t25 = time.perf_counter()
                        sock.sendall(data)
                        t3 = time.perf_counter()
                    with self._lock:
                        self.stats.behind += obs.behind > 0
                        self.stats.ahead += obs.ahead > 0
                        self.stats.parse_s += parsed - t0
                        self.stats.send_s += t3 - t25
                        self.stats.decisions += 1
                        self.stats.policy_s += t2 - t1
                        self.stats.handling_s += (parsed - t0) + (t3 - t2)
        except ConnectionResetError:  # Robocode stopped the robot's thread mid-exchange (a round's end): counted
            with self._lock:
                self.stats.resets += 1
        except OSError as err:
            if not self._stop.is_set():
                self._error(f"{hello['name']}: connection: {err}")
        except Exception as err:  # a bad message or a failing policy ends this robot's session
            self._error(f"{hello['name']}: {type(err).__name__}: {err}")
        finally:
            with self._lock:
                self._conns.discard(sock)
                self._acting.pop(sock, None)
            sock.close()


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
    """``python -m confront.engine.bridge PORT [module:function]``: serve in this process; the token is read
    from the environment variable CONFRONT_BRIDGE_TOKEN (never from the command line, which every user sees)."""
    args = list(sys.argv[1:] if argv is None else argv)
    token = os.environ.get(TOKEN_ENV, "")
    if len(args) not in (1, 2) or not token:
        print(main.__doc__, file=sys.stderr)
        return 2

    def refuse(text: str) -> int:
        print(f"error: {' '.join(text.split())[:300]}", file=sys.stderr)
        return 2

    if not args[0].isascii() or not args[0].isdigit() or not 0 <= int(args[0]) <= 65535:
        return refuse(f"PORT must be a number from 0 to 65535 (0: any free port), got {args[0][:40]!r}")
    try:
        policy = load_policy(args[1]) if len(args) == 2 else nearest_enemy_policy
    except (ImportError, AttributeError, ValueError) as exc:
        return refuse(f"policy {args[1][:100]!r} cannot be loaded (give module:function): {exc}")
    if not callable(policy):
        return refuse(f"policy {args[1][:100]!r} is not a function")
    try:
        server = BridgeServer(policy, token=token, port=int(args[0]))
    except OSError as exc:
        return refuse(f"cannot listen on port {args[0]}: {exc.strerror or exc}")
    server.on_hello = lambda h: print(f"hello {h['name']} round {h['round']}", flush=True)
    print(f"ready {server.port}", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
