"""Scripted robots that behave like Robocode's sample robots, compiled and batched.

SittingDuck, SpinBot, Walls, Tracker, RamFire, Fire, Corners and Crazy, written from their observable
behaviour (main loop of blocking calls, event handlers). A plain ``Robot`` blocks on every call; here
each robot has a small state machine in a per-robot memory row:

- execution levels: ``run()``'s loop (level 0) and one level per handler priority (scanned robot 10, hit
  by bullet 20, hit wall 30, hit robot 40), each a queue of operations; a handler nests only handlers of
  higher priority, and when it returns the level below resumes its blocking call (finished if the
  remaining value is 0 by then: Robocode's ``do { execute() } while (remaining != 0)``).
- operations: blocking move / body / gun / radar turns (done when the remaining value is 0, after
  at least one turn), ``fire`` / ``scan`` / ``stop`` / ``resume`` (one turn each), setters that do
  not block (``setAhead``, ``setTurnRight``, ``setMaxVelocity``) and ``waitFor(turn complete)``.
- events: Robocode's EventManager. Each turn's events are queued with a copy of their data (bearing,
  distance, energy as of that turn); older than 2 turns they are dropped. Between two turns a robot first
  runs processEvents: the head event (oldest first, then higher priority, nearer scan, own-fault ram) is
  dispatched while its priority is above the running level's; an equal one stops the loop, unless the
  running handler waits in ``scan()``, which it then aborts (EventInterruptedException).
- a plain Robot's ``fire`` uses Robocode's fire assist when its top event is a scan of the same turn and
  gun and radar point the same way: the bullet heads at heading + the event's bearing.

Usage: ``bots = ScriptedBots(arena, ["SpinBot", None, ...])`` (a name per robot, None = driven by
someone else), then every turn ``bots.commands(cmd)`` fills those robots' rows of ``cmd``. A new
round (``state.round`` changed) clears the memory of that battle's bots by itself.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numba import njit

from . import _kernels as K
from .core import Arena, _pool
from .kernel_cache import install
from .rules import java_atan2, java_hypot, normal_absolute_angle, normal_relative_angle
from .scenarios import Scenario
from .state import HIT_BY_BULLET_SLOTS, HIT_ROBOT_SLOTS

__all__ = ["BOT_NAMES", "ADVANCED_BOTS", "ScriptedBots", "bot_kind", "bot_battle"]

BOT_NAMES = ("SittingDuck", "SpinBot", "Walls", "Tracker", "RamFire", "Fire", "Corners", "Crazy", "TrackFire",
             "MyFirstLeader", "MyFirstDroid")
# AdvancedRobots (TeamRobot included); the others are plain Robots
ADVANCED_BOTS = frozenset({"SittingDuck", "SpinBot", "Crazy", "MyFirstLeader", "MyFirstDroid"})
K_NONE, K_DUCK, K_SPIN, K_WALLS, K_TRACKER, K_RAMFIRE, K_FIRE, K_CORNERS, K_CRAZY, K_TRACKFIRE, K_LEADER, \
    K_DROID = range(12)

# operation codes
O_MOVE, O_TURN, O_GUN, O_RADAR, O_FIRE, O_SCAN, O_STOP, O_RESUME, O_SETMAXV, O_SETMOVE, O_SETTURN, \
    O_WAITTURN, O_FIREASSIST, O_EXECUTE, O_SETRADAR, O_FIRECOOL = np.arange(1, 17, dtype=np.int64)
Q = 8  # operations per queue
# memory layout (per robot)
M_VAR = 0  # 8 bot variables
M_STOPPED = 12  # movement saved by stop() and not yet resumed
M_PHASE = 13  # run()'s set-up part done
M_CLOCK = 14  # decisions made this round = time of the turn whose events are being delivered
M_NEV = 15  # queued events
M_TOPT, M_TOPSCAN, M_TOPB = 16, 17, 18  # the current top event (time, is a scan, bearing) for fire assist
M_WON = 19  # the WinEvent of this round was queued
# execution levels: 0 = run(), then one per handler priority (a handler nests only higher ones): scanned
# robot 10, hit by bullet 20, hit wall 30, hit robot 40, message 75, win 100
LV_ACTIVE, LV_LEN, LV_POS, LV_START, LV_OPS = 0, 1, 2, 3, 4
LV_SIZE = LV_OPS + 2 * Q
LEVEL_PRIORITY = (-1.0, 10.0, 20.0, 30.0, 40.0, 75.0, 100.0)
N_LEVELS = len(LEVEL_PRIORITY)
M_LV = 20
# event queue: time, priority, robot, bearing, distance, energy, aux (fault / bullet heading), sequence
E_TIME, E_PRIO, E_J, E_BEAR, E_DIST, E_EN, E_AUX, E_SEQ = range(8)
E_SIZE = 8
N_EVQ = 24
M_EVQ = M_LV + N_LEVELS * LV_SIZE
M_STATIC = M_EVQ + N_EVQ * E_SIZE  # kept across rounds: Corners' corner, then the next two
# EventManager's interruptible flag of the scanned-robot priority and the value rescan() restores: the event
# manager outlives the round (EventManager.reset leaves the flags), so a robot that died in scan() inside its
# onScannedRobot starts the next round with the flag set
M_INTR, M_INTR_ORIG = M_STATIC + 1, M_STATIC + 2
M_SAVE = M_STATIC + 3  # stop(): saved distance, body, gun, radar remaining (proxy fields: kept across rounds)
M_MATES = M_STATIC + 7  # bit j set: isTeammate(name of robot j) is true for this robot (see teammate_masks)
M_SIZE = M_STATIC + 8
M_ROUND_START = ((M_STOPPED, 1.0), (M_TOPT, -1.0))  # per-round memory that does not start at 0
MAX_EVENT_STACK = 2  # Robocode EventManager: events older than 2 turns are dropped

# play(): battle chunks per worker thread (a thread on a free core takes more when the other core is busy)
_CHUNKS_PER_THREAD = 4
P_SCAN, P_BULLET, P_WALL, P_ROBOT, P_MESSAGE, P_WIN = 10.0, 20.0, 30.0, 40.0, 75.0, 100.0
DEG = math.pi / 180.0  # == Math.toRadians(1) (java.lang.Math.DEGREES_TO_RADIANS)
RAD_TO_DEG = 57.29577951308232  # java.lang.Math.RADIANS_TO_DEGREES (Math.toDegrees)


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _deg(r):
    """Radians as the robot API reports degrees (ScannedRobotEvent.getBearing, Robot.getGunHeading: r*180/PI)."""
    return r * 180.0 / math.pi


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _heading_deg(h):
    """Robot.getHeading(): 180*h/PI, wrapped into [0, 360)."""
    d = 180.0 * h / math.pi
    while d < 0:
        d += 360.0
    while d >= 360.0:
        d -= 360.0
    return d


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _rad(d):
    """Math.toRadians: the degree methods (turnRight, turnGunRight, ...) hand the peer d * DEGREES_TO_RADIANS."""
    return d * DEG


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _normal_relative_deg(a):
    """Utils.normalRelativeAngleDegrees: a % 360 into [-180, 180)."""
    if -180.0 <= a < 180.0:  # fmod leaves these unchanged and the result is a itself; skip the slow call
        return a
    a = np.fmod(a, 360.0)
    if a >= 0:
        return a if a < 180 else a - 360
    return a if a >= -180 else a + 360


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _level_of(prio):
    """Execution level of a handler priority."""
    for lv in range(1, N_LEVELS):
        if LEVEL_PRIORITY[lv] == prio:
            return lv
    return 0


def teammate_masks(names: list[str | None], teams: list[int]) -> list[int]:
    """Per robot, the robots whose name its ``isTeammate`` accepts (bit j), as the engine names them.

    Battle.createPeers names a robot "class (robot index + 1)" when its class occurs more than once in the
    battle, but lists team members as "class (count of that class so far)": with several robots of one class
    the two disagree, so a leader can take some of its own droids for enemies (MyFirstTeam: the droid at
    battle index 4 is "MyFirstDroid (5)", its team lists "(1)" to "(4)").
    """
    cls = [n or f"?{i}" for i, n in enumerate(names)]
    total = {c: cls.count(c) for c in cls}
    own = [c + (f" ({i + 1})" if total[c] > 1 else "") for i, c in enumerate(cls)]
    listed = [f"{c} ({cls[:i + 1].count(c)})" for i, c in enumerate(cls)]
    masks = []
    for i in range(len(cls)):
        mates = {listed[m] for m in range(len(cls)) if teams[m] == teams[i] and listed[m] != own[i]}
        masks.append(sum(1 << j for j in range(len(cls)) if own[j] == own[i] or own[j] in mates))
    return masks


def bot_kind(name: str | None) -> int:
    """Kind code of a bot name (0 for None)."""
    if name is None:
        return K_NONE
    if name not in BOT_NAMES:
        raise ValueError(f"unknown bot {name!r}; known: {', '.join(BOT_NAMES)}")
    return BOT_NAMES.index(name) + 1


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _top_level(mem, b, i):
    """The running execution level: the highest active handler, else run() (0)."""
    for lv in range(N_LEVELS - 1, 0, -1):
        if mem[b, i, M_LV + lv * LV_SIZE + LV_ACTIVE] == 1.0:
            return lv
    return 0


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _push(mem, b, i, lv, op, val):
    """Append an operation to level lv's queue."""
    base = M_LV + lv * LV_SIZE
    n = int(mem[b, i, base + LV_LEN])
    if n < Q:
        mem[b, i, base + LV_OPS + 2 * n] = op
        mem[b, i, base + LV_OPS + 2 * n + 1] = val
        mem[b, i, base + LV_LEN] = n + 1


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _clear_level(mem, b, i, lv, active):
    base = M_LV + lv * LV_SIZE
    mem[b, i, base + LV_ACTIVE] = active
    mem[b, i, base + LV_LEN] = 0
    mem[b, i, base + LV_POS] = 0
    mem[b, i, base + LV_START] = 0


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _h(mem, b, i, op, val):
    """Append an operation to the handler being dispatched (the top level)."""
    _push(mem, b, i, _top_level(mem, b, i), op, val)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _m(mem, b, i, op, val):
    _push(mem, b, i, np.int64(0), op, val)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _refill_main(kind, mem, b, i, heading, width, height, others):
    """Next pass of run(): the set-up part once per round, then the loop body."""
    _clear_level(mem, b, i, np.int64(0), 1.0)
    first = mem[b, i, M_PHASE] == 0
    mem[b, i, M_PHASE] = 1
    if kind == K_SPIN:
        _m(mem, b, i, O_SETTURN, 10000 * DEG)
        _m(mem, b, i, O_SETMAXV, 5.0)
        _m(mem, b, i, O_MOVE, 10000.0)
    elif kind == K_WALLS:
        amount = max(width, height)
        if first:
            mem[b, i, M_VAR] = 0.0  # peek
            _m(mem, b, i, O_TURN, -_rad(np.fmod(_heading_deg(heading), 90.0)))  # turnLeft(getHeading() % 90)
            _m(mem, b, i, O_MOVE, amount)
            _m(mem, b, i, O_SETMAXV, -1.0)  # marker: peek = true
            _m(mem, b, i, O_GUN, 90 * DEG)
            _m(mem, b, i, O_TURN, 90 * DEG)
        else:
            _m(mem, b, i, O_SETMAXV, -1.0)  # peek = true
            _m(mem, b, i, O_MOVE, amount)
            _m(mem, b, i, O_SETMAXV, -2.0)  # peek = false
            _m(mem, b, i, O_TURN, 90 * DEG)
    elif kind == K_TRACKER:
        if first:
            mem[b, i, M_VAR] = 0.0  # count
            mem[b, i, M_VAR + 1] = 10.0  # gunTurnAmt (deg)
            mem[b, i, M_VAR + 2] = -1.0  # tracked robot
        _m(mem, b, i, O_GUN, _rad(mem[b, i, M_VAR + 1]))
        _m(mem, b, i, O_SETMAXV, -3.0)  # marker: count bookkeeping after the turn
    elif kind == K_RAMFIRE:
        if first:
            mem[b, i, M_VAR] = 1.0  # turnDirection
        _m(mem, b, i, O_TURN, _rad(5 * mem[b, i, M_VAR]))
    elif kind == K_FIRE:
        if first:
            mem[b, i, M_VAR] = 50.0  # dist
        _m(mem, b, i, O_GUN, 5 * DEG)
    elif kind == K_CORNERS:
        if first:
            mem[b, i, M_VAR] = 0.0  # stopWhenSeeRobot
            mem[b, i, M_VAR + 1] = 3.0  # gunIncrement
            mem[b, i, M_VAR + 2] = others
            corner = mem[b, i, M_STATIC]
            _m(mem, b, i, O_TURN, _rad(_normal_relative_deg(corner - _heading_deg(heading))))
            _m(mem, b, i, O_SETMAXV, -4.0)  # stopWhenSeeRobot = true
            _m(mem, b, i, O_MOVE, 5000.0)
            _m(mem, b, i, O_TURN, -90 * DEG)
            _m(mem, b, i, O_MOVE, 5000.0)
            _m(mem, b, i, O_GUN, -90 * DEG)
        else:
            # 30 x turnGunLeft(gunIncrement) as one gun op of 90 deg would differ in scan timing only
            # slightly; keep the 3-degree steps through a counter
            _m(mem, b, i, O_GUN, -_rad(mem[b, i, M_VAR + 1]))
            _m(mem, b, i, O_SETMAXV, -5.0)  # marker: count the step, flip after 30
    elif kind == K_CRAZY:
        _m(mem, b, i, O_SETMOVE, 40000.0)
        _m(mem, b, i, O_SETMAXV, -6.0)  # movingForward = true
        _m(mem, b, i, O_SETTURN, 90 * DEG)
        _m(mem, b, i, O_WAITTURN, 0.0)
        _m(mem, b, i, O_SETTURN, -180 * DEG)
        _m(mem, b, i, O_WAITTURN, 0.0)
        _m(mem, b, i, O_SETTURN, 180 * DEG)
        _m(mem, b, i, O_WAITTURN, 0.0)
    elif kind == K_TRACKFIRE:
        _m(mem, b, i, O_GUN, 10 * DEG)
    elif kind == K_LEADER:
        _m(mem, b, i, O_SETRADAR, _rad(10000.0))
        _m(mem, b, i, O_MOVE, 100.0)
        _m(mem, b, i, O_MOVE, -100.0)
    elif kind == K_DROID:  # run() returns at once; the robot then executes every turn, handling events
        _m(mem, b, i, O_EXECUTE, 0.0)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _marker(kind, mem, b, i, code):
    """Bookkeeping steps of run() written as pseudo-operations (negative SETMAXV values)."""
    if code == -1.0:
        mem[b, i, M_VAR] = 1.0
    elif code == -2.0:
        mem[b, i, M_VAR] = 0.0
    elif code == -3.0:  # Tracker's count
        c = mem[b, i, M_VAR] + 1
        mem[b, i, M_VAR] = c
        if c > 2:
            mem[b, i, M_VAR + 1] = -10.0
        if c > 5:
            mem[b, i, M_VAR + 1] = 10.0
        if c > 11:
            mem[b, i, M_VAR + 2] = -1.0
    elif code == -4.0:
        mem[b, i, M_VAR] = 1.0
    elif code == -5.0:  # Corners: flip the gun direction every 30 steps
        mem[b, i, M_VAR + 3] += 1
        if mem[b, i, M_VAR + 3] >= 30:
            mem[b, i, M_VAR + 3] = 0
            mem[b, i, M_VAR + 1] *= -1
    elif code == -6.0:
        mem[b, i, M_VAR + 4] = 1.0  # Crazy movingForward
    elif code == -7.0:  # Tracker.onWin: for (i = 0; i < 50; i++) { turnRight(30); turnLeft(30); }
        mem[b, i, M_VAR + 5] += 1
        if mem[b, i, M_VAR + 5] < 50:
            base = M_LV + (N_LEVELS - 1) * LV_SIZE  # the win handler's level: its loop body again
            mem[b, i, base + LV_POS] = 0
            mem[b, i, base + LV_START] = 0


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _reverse(mem, b, i, cmd):
    """Crazy.reverseDirection: setBack/setAhead(40000)."""
    if mem[b, i, M_VAR + 4] == 1.0:
        cmd[b, i, 0] = -40000.0
        mem[b, i, M_VAR + 4] = 0.0
    else:
        cmd[b, i, 0] = 40000.0
        mem[b, i, M_VAR + 4] = 1.0


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _op_done(op, started, rem_d, rem_b, rem_g, rem_r):
    """A started operation is finished (blocking ops: remaining value 0)."""
    if not started:
        return False
    if op == O_MOVE:
        return rem_d == 0.0
    if op == O_TURN:
        return rem_b == 0.0
    if op == O_GUN:
        return rem_g == 0.0
    if op == O_RADAR:
        return rem_r == 0.0
    if op == O_WAITTURN:
        return rem_b == 0.0
    return True


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _issue(kind, mem, b, i, op, val, cmd, maxv, assist, scan_req, heading, rem, gun_eq_radar, heat, energy):
    """Write an operation's commands; True if it takes the turn (blocking)."""
    if op == O_EXECUTE:
        return True
    if op == O_SETRADAR:
        cmd[b, i, 3] = val
        return False
    if op == O_FIRECOOL:  # TrackFire: if (getGunHeat() == 0) fire(min(val, getEnergy() - .1))
        if heat > 0.0:
            return False
        cmd[b, i, 4] = max(min(val, energy - 0.1), 0.1)  # setFire clamps the power up to 0.1
        return True
    if op == O_MOVE:
        cmd[b, i, 0] = val
        return True
    if op == O_TURN:
        cmd[b, i, 1] = val
        return True
    if op == O_GUN:
        cmd[b, i, 2] = val
        return True
    if op == O_RADAR:
        cmd[b, i, 3] = val
        return True
    if op == O_FIRE or op == O_FIREASSIST:
        cmd[b, i, 4] = val
        # fire assist (BasicRobotProxy.setFireImpl): a plain Robot whose top event is a scan of this very
        # turn, gun and radar pointing the same way, fires at heading + the event's bearing
        if kind != K_SPIN and kind != K_CRAZY and mem[b, i, M_TOPSCAN] == 1.0 and gun_eq_radar \
                and mem[b, i, M_TOPT] == mem[b, i, M_CLOCK]:
            assist[b, i] = normal_absolute_angle(heading + mem[b, i, M_TOPB])
        return True
    if op == O_SCAN:
        scan_req[b, i] = True
        return True
    if op == O_STOP:  # stop(): saves the movement unless some is saved already, then halts
        if mem[b, i, M_STOPPED] == 0.0:
            for k in range(4):
                mem[b, i, M_SAVE + k] = rem[k]
            mem[b, i, M_STOPPED] = 1.0
        for k in range(4):
            cmd[b, i, k] = 0.0
        return True
    if op == O_RESUME:
        if mem[b, i, M_STOPPED] == 1.0:
            for k in range(4):
                cmd[b, i, k] = mem[b, i, M_SAVE + k]
            mem[b, i, M_STOPPED] = 0.0
        return True
    if op == O_SETMAXV:
        if val >= 0.0:
            maxv[b, i] = val
        else:
            _marker(kind, mem, b, i, val)
        return False
    if op == O_SETMOVE:
        cmd[b, i, 0] = val
        return False
    if op == O_SETTURN:
        cmd[b, i, 1] = val
        return False
    if op == O_WAITTURN:
        return True
    return False


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _add_event(mem, b, i, prio, j, bearing, dist, energy, aux):
    """Queue an event of this turn (EventManager.add; a full queue drops it)."""
    n = int(mem[b, i, M_NEV])
    if n >= N_EVQ:
        return
    e = M_EVQ + n * E_SIZE
    mem[b, i, e + E_TIME] = mem[b, i, M_CLOCK]
    mem[b, i, e + E_PRIO] = prio
    mem[b, i, e + E_J] = j
    mem[b, i, e + E_BEAR] = bearing
    mem[b, i, e + E_DIST] = dist
    mem[b, i, e + E_EN] = energy
    mem[b, i, e + E_AUX] = aux
    mem[b, i, e + E_SEQ] = n + mem[b, i, M_CLOCK] * N_EVQ
    mem[b, i, M_NEV] = n + 1


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _remove_event(mem, b, i, k):
    n = int(mem[b, i, M_NEV])
    for m in range(k, n - 1):
        for f in range(E_SIZE):
            mem[b, i, M_EVQ + m * E_SIZE + f] = mem[b, i, M_EVQ + (m + 1) * E_SIZE + f]
    mem[b, i, M_NEV] = n - 1


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _before(mem, b, i, k, m):
    """Event k sorts before event m (Event.compareTo: older first, then higher priority, then nearer scan /
    own-fault ram; equal ones keep their order)."""
    ek = M_EVQ + k * E_SIZE
    em = M_EVQ + m * E_SIZE
    if mem[b, i, ek + E_TIME] != mem[b, i, em + E_TIME]:
        return mem[b, i, ek + E_TIME] < mem[b, i, em + E_TIME]
    if mem[b, i, ek + E_PRIO] != mem[b, i, em + E_PRIO]:
        return mem[b, i, ek + E_PRIO] > mem[b, i, em + E_PRIO]
    if mem[b, i, ek + E_PRIO] == P_SCAN:
        dd = int(mem[b, i, ek + E_DIST] - mem[b, i, em + E_DIST])  # ScannedRobotEvent: (int) distance difference
        if dd != 0:
            return dd < 0
    elif mem[b, i, ek + E_PRIO] == P_ROBOT and mem[b, i, ek + E_AUX] != mem[b, i, em + E_AUX]:
        return mem[b, i, ek + E_AUX] > mem[b, i, em + E_AUX]
    return mem[b, i, ek + E_SEQ] < mem[b, i, em + E_SEQ]


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _enqueue(mem, b, i, x, y, h, energy, alive, team, scanned, ev_wall, ev_robot, ev_robot_bearing, ev_fault,
             ev_hitby, ev_hitby_bearing, ev_hitby_heading, hr, hb, has_hr, scan_order):
    """Queue the last turn's events, then drop those older than MAX_EVENT_STACK turns.

    The scans in the order of the robot's own random list of that turn (``scan_order``, the arena's): where
    two distances differ by under 1 px, the one first in that list is handled first."""
    n = x.shape[1]
    if has_hr:  # one HitRobotEvent per collision, in the engine's order (RobotPeer.checkRobotCollision)
        for k in range(min(int(hr[b, 0, i]), HIT_ROBOT_SLOTS)):
            _add_event(mem, b, i, P_ROBOT, hr[b, 1 + 4 * k, i], hr[b, 2 + 4 * k, i], 0.0, hr[b, 4 + 4 * k, i],
                       hr[b, 3 + 4 * k, i])
    else:
        j = ev_robot[b, i]
        if j >= 0:
            _add_event(mem, b, i, P_ROBOT, float(j), ev_robot_bearing[b, i], 0.0, energy[b, j],
                       1.0 if ev_fault[b, i] else 0.0)
    if ev_wall[b, i]:
        _add_event(mem, b, i, P_WALL, -1.0, 0.0, 0.0, 0.0, 0.0)
    if has_hr:  # one HitByBulletEvent per bullet, in the engine's bullet order (BulletPeer.checkRobotCollision)
        for k in range(min(int(hb[b, 0, i]), HIT_BY_BULLET_SLOTS)):
            _add_event(mem, b, i, P_BULLET, -1.0, hb[b, 1 + 2 * k, i], 0.0, 0.0, hb[b, 2 + 2 * k, i])
    elif ev_hitby[b, i] > 0:
        # the event carries the bullet's own heading (Bullet.getHeadingRadians; BulletPeer's heading), not
        # bearing + body heading - pi, which can be an ulp off
        _add_event(mem, b, i, P_BULLET, -1.0, ev_hitby_bearing[b, i], 0.0, 0.0, ev_hitby_heading[b, i])
    for q in range(n):
        j2 = int(scan_order[b, i, q])
        if scanned[b, i, j2] and alive[b, j2]:
            dx = x[b, j2] - x[b, i]
            dy = y[b, j2] - y[b, i]
            bearing = normal_relative_angle(java_atan2(dx, dy) - h[b, i])  # Java's atan2 and hypot (fdlibm)
            _add_event(mem, b, i, P_SCAN, float(j2), bearing, java_hypot(dx, dy), energy[b, j2], 0.0)
    if mem[b, i, M_WON] == 0.0 and alive[b, i]:
        won = True
        for j2 in range(n):
            if alive[b, j2] and team[b, j2] != team[b, i]:
                won = False
        if won:  # Battle.shutdownTurn: the survivors get a WinEvent in the turn the round is decided
            mem[b, i, M_WON] = 1.0
            _add_event(mem, b, i, P_WIN, -1.0, 0.0, 0.0, 0.0, 0.0)
    old = mem[b, i, M_CLOCK] - MAX_EVENT_STACK
    k = np.int64(0)
    while k < int(mem[b, i, M_NEV]):
        if mem[b, i, M_EVQ + k * E_SIZE + E_TIME] <= old:
            _remove_event(mem, b, i, k)
        else:
            k += 1


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _add_message(mem, b, d, time, px, py):
    """A team message (a Point) for robot d, delivered at ``time`` (sent in one turn, read in the next)."""
    n = int(mem[b, d, M_NEV])
    if n >= N_EVQ:
        return
    e = M_EVQ + n * E_SIZE
    mem[b, d, e + E_TIME] = time
    mem[b, d, e + E_PRIO] = P_MESSAGE
    mem[b, d, e + E_J] = -1
    mem[b, d, e + E_BEAR] = px
    mem[b, d, e + E_DIST] = py
    mem[b, d, e + E_EN] = 0.0
    mem[b, d, e + E_AUX] = 0.0
    mem[b, d, e + E_SEQ] = n + time * N_EVQ
    mem[b, d, M_NEV] = n + 1


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _head(mem, b, i):
    """Index of the first queued event in Robocode's order (-1: empty)."""
    best = np.int64(-1)  # not a literal -1: _dispatch(k) is then compiled once, for int64
    for k in range(int(mem[b, i, M_NEV])):
        if mem[b, i, M_EVQ + k * E_SIZE + E_TIME] > mem[b, i, M_CLOCK]:
            continue  # a team message sent this turn: delivered in the next one
        if best < 0 or _before(mem, b, i, k, best):
            best = k
    return best


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _dispatch(kind, mem, b, i, k, x, y, h, gh, rh, energy, alive, team, kinds, cmd):
    """Start the handler of queued event k (removed from the queue): its level and operations."""
    e = M_EVQ + k * E_SIZE
    prio = mem[b, i, e + E_PRIO]
    j = int(mem[b, i, e + E_J])
    bearing = mem[b, i, e + E_BEAR]
    dist = mem[b, i, e + E_DIST]
    e_energy = mem[b, i, e + E_EN]
    aux = mem[b, i, e + E_AUX]
    mem[b, i, M_TOPT] = mem[b, i, e + E_TIME]
    mem[b, i, M_TOPSCAN] = 1.0 if prio == P_SCAN else 0.0
    mem[b, i, M_TOPB] = bearing
    _remove_event(mem, b, i, k)
    _clear_level(mem, b, i, _level_of(prio), 1.0)
    hb = h[b, i]
    bdeg = _deg(bearing)  # e.getBearing()
    if prio == P_WIN:
        if kind == K_TRACKER:  # onWin: 50 x (turnRight(30); turnLeft(30))
            mem[b, i, M_VAR + 5] = 0.0
            _h(mem, b, i, O_TURN, _rad(30.0))
            _h(mem, b, i, O_TURN, -_rad(30.0))
            _h(mem, b, i, O_SETMAXV, -7.0)
        elif kind == K_TRACKFIRE:  # onWin: turnRight(36000)
            _h(mem, b, i, O_TURN, _rad(36000.0))
    elif prio == P_MESSAGE:
        if kind == K_DROID:  # onMessageReceived(Point): aim the gun at the point, fire(3)
            theta = java_atan2(bearing - x[b, i], dist - y[b, i]) * RAD_TO_DEG
            _h(mem, b, i, O_GUN, _rad(_normal_relative_deg(theta - _deg(gh[b, i]))))
            _h(mem, b, i, O_FIRE, 3.0)
    elif prio == P_ROBOT:
        fault = aux == 1.0
        if kind == K_SPIN:
            if -10 < bdeg < 10:
                _h(mem, b, i, O_FIRE, 3.0)
            if fault:
                _h(mem, b, i, O_TURN, _rad(10.0))
        elif kind == K_WALLS:
            _h(mem, b, i, O_MOVE, -100.0 if -90 < bdeg < 90 else 100.0)
        elif kind == K_TRACKER:
            mem[b, i, M_VAR + 2] = j
            amt = _normal_relative_deg(bdeg + (_heading_deg(hb) - _deg(rh[b, i])))
            mem[b, i, M_VAR + 1] = amt
            _h(mem, b, i, O_GUN, _rad(amt))
            _h(mem, b, i, O_FIRE, 3.0)
            _h(mem, b, i, O_MOVE, -50.0)
        elif kind == K_RAMFIRE:
            mem[b, i, M_VAR] = 1.0 if bdeg >= 0 else -1.0
            _h(mem, b, i, O_TURN, _rad(bdeg))
            if e_energy > 16:
                _h(mem, b, i, O_FIRE, 3.0)
            elif e_energy > 10:
                _h(mem, b, i, O_FIRE, 2.0)
            elif e_energy > 4:
                _h(mem, b, i, O_FIRE, 1.0)
            elif e_energy > 2:
                _h(mem, b, i, O_FIRE, 0.5)
            elif e_energy > 0.4:
                _h(mem, b, i, O_FIRE, 0.1)
            _h(mem, b, i, O_MOVE, 40.0)
        elif kind == K_FIRE:
            _h(mem, b, i, O_GUN, _rad(_normal_relative_deg(bdeg + _heading_deg(hb) - _deg(gh[b, i]))))
            _h(mem, b, i, O_FIRE, 3.0)
        elif kind == K_CRAZY and fault:
            _reverse(mem, b, i, cmd)
    elif prio == P_WALL:
        if kind == K_CRAZY:
            _reverse(mem, b, i, cmd)
    elif prio == P_BULLET:
        if kind == K_LEADER:  # turnLeft(90 - e.getBearing())
            _h(mem, b, i, O_TURN, -_rad(90 - bdeg))
        if kind == K_FIRE:  # turn perpendicular to the bullet, move, scan
            _h(mem, b, i, O_TURN, _rad(_normal_relative_deg(90 - (_heading_deg(hb) - aux * RAD_TO_DEG))))
            _h(mem, b, i, O_MOVE, mem[b, i, M_VAR])
            mem[b, i, M_VAR] *= -1
            _h(mem, b, i, O_SCAN, 0.0)
    else:  # scanned robot
        if kind == K_SPIN or kind == K_CRAZY:
            _h(mem, b, i, O_FIRE, 3.0 if kind == K_SPIN else 1.0)
        elif kind == K_WALLS:
            _h(mem, b, i, O_FIREASSIST, 2.0)
            if mem[b, i, M_VAR] == 1.0:
                _h(mem, b, i, O_SCAN, 0.0)
        elif kind == K_TRACKER:
            track = int(mem[b, i, M_VAR + 2])
            if track >= 0 and j != track:
                return
            mem[b, i, M_VAR + 2] = j
            mem[b, i, M_VAR] = 0.0
            amt = _normal_relative_deg(bdeg + (_heading_deg(hb) - _deg(rh[b, i])))
            mem[b, i, M_VAR + 1] = amt
            _h(mem, b, i, O_GUN, _rad(amt))
            if dist > 150:
                _h(mem, b, i, O_TURN, _rad(bdeg))
                _h(mem, b, i, O_MOVE, dist - 140)
            else:
                _h(mem, b, i, O_FIREASSIST, 3.0)
                if dist < 100:
                    _h(mem, b, i, O_MOVE, -40.0 if -90 < bdeg <= 90 else 40.0)
                _h(mem, b, i, O_SCAN, 0.0)
        elif kind == K_TRACKFIRE:
            bfg = _normal_relative_deg(_heading_deg(hb) + bdeg - _deg(gh[b, i]))  # bearing from the gun
            _h(mem, b, i, O_GUN, _rad(bfg))
            if abs(bfg) <= 3:
                _h(mem, b, i, O_FIRECOOL, 3 - abs(bfg))
            if bfg == 0:
                _h(mem, b, i, O_SCAN, 0.0)
        elif kind == K_LEADER:
            if (int(mem[b, i, M_MATES]) >> j) & 1:  # isTeammate(e.getName())
                return
            eb = _heading_deg(hb) + bdeg
            ex = x[b, i] + dist * math.sin(_rad(eb))
            ey = y[b, i] + dist * math.cos(_rad(eb))
            for d in range(x.shape[1]):  # broadcastMessage(new Point(ex, ey)) to the droids
                if d != i and kinds[d] == K_DROID and team[b, d] == team[b, i] and alive[b, d]:
                    _add_message(mem, b, d, mem[b, i, M_CLOCK] + 1, ex, ey)
        elif kind == K_RAMFIRE:
            mem[b, i, M_VAR] = 1.0 if bdeg >= 0 else -1.0
            _h(mem, b, i, O_TURN, _rad(bdeg))
            _h(mem, b, i, O_MOVE, dist + 5)
            _h(mem, b, i, O_SCAN, 0.0)
        elif kind == K_FIRE:
            _h(mem, b, i, O_FIREASSIST, 3.0 if dist < 50 and energy[b, i] > 50 else 1.0)
            _h(mem, b, i, O_SCAN, 0.0)
        elif kind == K_CORNERS:
            p = 1.0 if (dist > 200 or energy[b, i] < 15) else (2.0 if dist > 50 else 3.0)
            if mem[b, i, M_VAR] == 1.0:
                _h(mem, b, i, O_STOP, 0.0)
                _h(mem, b, i, O_FIREASSIST, p)
                _h(mem, b, i, O_SCAN, 0.0)
                _h(mem, b, i, O_RESUME, 0.0)
            else:
                _h(mem, b, i, O_FIREASSIST, p)


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _bots_battle(b, kinds, mem, x, y, h, gh, rh, energy, alive, team, dist_rem, body_rem, gun_rem, radar_rem, maxv,
                 assist, scan_req, scanned, ev_wall, ev_robot, ev_robot_bearing, ev_fault, ev_hitby,
                 ev_hitby_bearing, ev_hitby_heading, ev_died, width, height, cmd, rem, hr, hb, has_hr, heat,
                 scan_order):
    """One decision of battle b's scripted robots (their robot time between two turns).

    Each robot resumes inside the execute() of its running blocking call: EventManager.processEvents first
    (dispatch the head event while its priority is above the running level's; an equal one stops the loop
    unless the scanned-robot priority is interruptible, i.e. the handler waits in scan(): it is then aborted),
    then the call's remaining-value test, then the code after it up to the next blocking call. A disabled
    robot (energy 0) runs on: its moves and body turns are refused by the engine, the rest works.
    """
    n = x.shape[1]
    others = 0
    for i in range(n):
        others += 1 if alive[b, i] else 0
    for i in range(n):
        kind = kinds[i]
        if kind == K_CORNERS and ev_died[b, i]:
            # Corners.onDeath: a poor round (under 75 % of the others killed) moves to the next corner
            start = mem[b, i, M_VAR + 2]
            if start > 0 and (start - others) / start < 0.75:
                c = mem[b, i, M_STATIC] + 90
                mem[b, i, M_STATIC] = -90.0 if c == 270 else c
        if kind == K_NONE or kind == K_DUCK or not (alive[b, i] or ev_died[b, i]):
            mem[b, i, M_CLOCK] += 1
            continue
        # a robot that died this turn still wakes once: its blocking call returns and its code runs on to the
        # next one, which throws DeathException (RobotPeer.executeImpl); commands of the dead are ignored
        rem[0] = dist_rem[b, i]
        rem[1] = body_rem[b, i]
        rem[2] = gun_rem[b, i]
        rem[3] = radar_rem[b, i]
        _enqueue(mem, b, i, x, y, h, energy, alive, team, scanned, ev_wall, ev_robot, ev_robot_bearing, ev_fault,
                 ev_hitby, ev_hitby_bearing, ev_hitby_heading, hr, hb, has_hr, scan_order)
        lv = _top_level(mem, b, i)
        process = True
        for _ in range(48):
            base = M_LV + lv * LV_SIZE
            if process:
                k = _head(mem, b, i)
                if k < 0:
                    process = False
                    continue
                prio = mem[b, i, M_EVQ + k * E_SIZE + E_PRIO]
                cur = LEVEL_PRIORITY[lv]
                if prio < cur:
                    process = False
                elif prio == cur:
                    if lv == 1 and mem[b, i, M_INTR] == 1.0:
                        # interruptible (the handler waits in scan(), or the flag survived the last round):
                        # EventInterruptedException ends the handler
                        mem[b, i, M_INTR] = 0.0
                        _clear_level(mem, b, i, lv, 0.0)
                        mem[b, i, M_TOPT] = -1.0
                        mem[b, i, M_TOPSCAN] = 0.0
                        lv = _top_level(mem, b, i)
                    else:
                        process = False
                else:
                    _dispatch(kind, mem, b, i, k, x, y, h, gh, rh, energy, alive, team, kinds, cmd)
                    lv = _level_of(prio)
                    process = False
                continue
            pos = int(mem[b, i, base + LV_POS])
            if pos >= int(mem[b, i, base + LV_LEN]):
                if lv == 0:
                    _refill_main(kind, mem, b, i, h[b, i], width, height, others - 1)
                else:  # the handler returns into the processEvents loop of the level below
                    if lv == 1:
                        mem[b, i, M_INTR] = 0.0  # processEvents: setInterruptible(priority, false)
                    _clear_level(mem, b, i, lv, 0.0)
                    lv = _top_level(mem, b, i)
                    process = True
                continue
            op = mem[b, i, base + LV_OPS + 2 * pos]
            val = mem[b, i, base + LV_OPS + 2 * pos + 1]
            if mem[b, i, base + LV_START] == 1:
                if _op_done(op, True, rem[0], rem[1], rem[2], rem[3]):
                    if op == O_SCAN and lv == 1:
                        mem[b, i, M_INTR] = mem[b, i, M_INTR_ORIG]  # rescan() restores the flag it found
                    mem[b, i, base + LV_POS] = pos + 1
                    mem[b, i, base + LV_START] = 0
                    continue
                break  # still running: execute() again
            mem[b, i, base + LV_START] = 1
            if op == O_SCAN and lv == 1:  # rescan() inside onScannedRobot: interruptible while it executes
                mem[b, i, M_INTR_ORIG] = mem[b, i, M_INTR]
                mem[b, i, M_INTR] = 1.0
            if _issue(kind, mem, b, i, op, val, cmd, maxv, assist, scan_req, h[b, i], rem, gh[b, i] == rh[b, i],
                      heat[b, i], energy[b, i]):
                break
        mem[b, i, M_CLOCK] += 1


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy", nogil=True)
def bots_step(kinds, mem, x, y, h, gh, rh, energy, alive, team, dist_rem, body_rem, gun_rem, radar_rem, maxv,
              assist, scan_req, scanned, ev_wall, ev_robot, ev_robot_bearing, ev_fault, ev_hitby,
              ev_hitby_bearing, ev_hitby_heading, ev_died, width, height, cmd, rem, hit_robots, hit_by_bullets,
              heat, scan_order):
    """One decision of every scripted robot (their robot time between two turns).

    ``hit_robots``: the arena's per-collision HitRobot rows (``rf[:, EVROBN:EVROBN + 1 + 4 * HIT_ROBOT_SLOTS]``);
    ``hit_by_bullets``: its per-bullet HitByBullet rows (``rf[:, EVBULN:EVBULN + 1 + 2 * HIT_BY_BULLET_SLOTS]``);
    ``heat``: the gun heats (TrackFire reads them); ``scan_order``: each robot's scan list of the last turn in
    the engine's random order (the arena's ``scan_order``). One call signature only: each variant is a compile.
    """
    for b in range(x.shape[0]):
        _bots_battle(b, kinds, mem, x, y, h, gh, rh, energy, alive, team, dist_rem, body_rem, gun_rem,
                     radar_rem, maxv, assist, scan_req, scanned, ev_wall, ev_robot, ev_robot_bearing, ev_fault,
                     ev_hitby, ev_hitby_bearing, ev_hitby_heading, ev_died, width, height, cmd, rem, hit_robots,
                     hit_by_bullets, True, heat, scan_order)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _clear_memory(mem, b):
    """A new round: forget battle b's per-round bot memory (statics such as Corners' corner stay)."""
    for i in range(mem.shape[1]):
        for k in range(M_STATIC):
            mem[b, i, k] = 0.0
        mem[b, i, M_TOPT] = -1.0
        mem[b, i, M_STOPPED] = 1.0  # the proxy starts each round as stopped: stop() saves nothing, resume() zeros


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy", nogil=True)
def play_range(b0, b1, turns, kinds, mem, rounds, rf, rb, ri, bi, bf, bb, kf, ki, scanned, scan_time, scan_order,
               ledger,
               score, score_total, placements, placements_total, cmd, params, scratch_i, scratch_f, fixed,
               has_fixed, width, height, rem):
    """``turns`` turns of battles b0..b1-1, each as ``commands``, ``Arena.step``, ``Arena.reset(done)``.

    Battles are independent, so each runs all its turns before the next (its data stays in cache).
    Returns the robots alive after each turn, summed (alive robot-turns).
    """
    n = rf.shape[2]
    k = kf.shape[2]
    x, y, h, gh, rh, energy = rf[:, K.X], rf[:, K.Y], rf[:, K.H], rf[:, K.GH], rf[:, K.RH], rf[:, K.E]
    dist, body, gun, radar = rf[:, K.DIST], rf[:, K.BODYREM], rf[:, K.GUNREM], rf[:, K.RADREM]
    maxv, assist, ev_robb, ev_bulb = rf[:, K.MAXV], rf[:, K.ASSIST], rf[:, K.EVROBB], rf[:, K.EVBULB]
    ev_bulh = rf[:, K.EVBULH]
    alive, scan_req, ev_wall, ev_fault, ev_died = rb[:, K.ALIVE], rb[:, K.SCANREQ], rb[:, K.EVWALL], \
        rb[:, K.EVFAULT], rb[:, K.EVDIED]
    hr, heat = rf[:, K.EVROBN:K.EVROB0 + 4 * HIT_ROBOT_SLOTS], rf[:, K.HEAT]
    hb = rf[:, K.EVBULN:K.EVBUL0 + 2 * HIT_BY_BULLET_SLOTS]
    team, ev_robot, ev_hitby = ri[:, K.TEAM], ri[:, K.EVROBOT], ri[:, K.EVHITBY]
    total = 0
    for b in range(b0, b1):
        for _ in range(turns):
            if rounds[b] != bi[b, K.ROUND]:  # sync_rounds: a round started since the bots last acted
                _clear_memory(mem, b)
                rounds[b] = bi[b, K.ROUND]
            for i in range(n):
                if kinds[i] != K_NONE:
                    for c in range(4):
                        cmd[b, i, c] = math.nan
                    cmd[b, i, 4] = 0.0
            _bots_battle(b, kinds, mem, x, y, h, gh, rh, energy, alive, team, dist, body, gun, radar, maxv, assist,
                         scan_req, scanned, ev_wall, ev_robot, ev_robb, ev_fault, ev_hitby, ev_bulb, ev_bulh, ev_died,
                         width, height, cmd, rem, hr, hb, True, heat, scan_order)
            if not bb[b, K.DONE]:
                K.step_battle_at(b, rf, rb, ri, bi, bf, bb, kf, ki, scanned, scan_time, scan_order, ledger, score,
                                 score_total,
                                 placements, placements_total, cmd, params, scratch_i, scratch_f, n, k)
            for i in range(n):
                total += 1 if rb[b, K.ALIVE, i] else 0
            if bb[b, K.DONE]:
                K.reset_battle(b, rf, rb, ri, bi, bf, bb, kf, ki, scanned, scan_time, ledger, score, placements,
                               params, fixed, has_fixed, scratch_i)
    return total


class ScriptedBots:
    """Sample-robot behaviour for some robots of an Arena (all battles)."""

    def __init__(self, arena: Arena, names: Sequence[str | None]) -> None:
        if len(names) != arena.n_robots:
            raise ValueError(f"names has {len(names)} entries, the arena has {arena.n_robots} robots")
        self.arena = arena
        self.names = list(names)
        self.kinds = np.array([bot_kind(n) for n in names], dtype=np.int64)
        self._bots = np.flatnonzero(self.kinds != K_NONE)
        self.mem = np.zeros((arena.n_battles, arena.n_robots, M_SIZE))
        self.mem[:, :, M_MATES] = teammate_masks(self.names, list(arena.state.team[0]))
        self._apply_flags()
        self._round = arena.state.round.copy()
        self._chunk_args()
        self.reset()

    def _apply_flags(self) -> None:
        s = self.arena.state
        for i, name in enumerate(self.names):
            if name is None:
                continue
            s.is_advanced[:, i] = name in ADVANCED_BOTS
            s.adjust_gun_for_body[:, i] = name == "Tracker"
            droid = name == "MyFirstDroid"
            if droid and not s.is_droid[0, i] and (s.time == 0).all():
                s.energy[:, i] += 20.0  # a droid starts with 120 (the round was placed before the flag)
            s.is_droid[:, i] = droid
            s.adjust_radar_for_body[:, i] = False
            s.adjust_radar_for_gun[:, i] = False

    def reset(self, mask: np.ndarray | None = None) -> None:
        """Clear the per-round memory of the masked battles (statics such as Corners' corner stay)."""
        idx = slice(None) if mask is None else np.asarray(mask, dtype=bool)
        keep = self.mem[idx, :, M_STATIC:].copy()
        self.mem[idx] = 0.0
        self.mem[idx, :, M_STATIC:] = keep
        for k, v in M_ROUND_START:
            self.mem[idx, :, k] = v
        self._round[idx] = self.arena.state.round[idx]

    def sync_rounds(self) -> None:
        """Clear the memory of every battle that started a new round since the bots last acted."""
        rnd = self.arena.state.round
        if not np.array_equal(rnd, self._round):
            self.reset(rnd != self._round)

    def state_dict(self) -> dict[str, np.ndarray]:
        """The bots' memory (data only), for checkpoints next to ``Arena.state_dict``."""
        return {"mem": self.mem.copy(), "round": self._round.copy()}

    def load_state_dict(self, d: dict[str, np.ndarray]) -> None:
        """Restore what :meth:`state_dict` wrote."""
        for key, dst in (("mem", self.mem), ("round", self._round)):
            if key not in d:
                raise ValueError(f"bots state dict lacks {key!r}")
            if np.shape(d[key]) != dst.shape:
                raise ValueError(f"bots state {key!r} has shape {np.shape(d[key])}, expected {dst.shape}")
            dst[...] = d[key]

    def commands(self, cmd: np.ndarray) -> np.ndarray:
        """Fill the scripted robots' rows of ``cmd`` (B, R, 5) in place for the next turn."""
        self.sync_rounds()
        cmd[:, self._bots, :4] = np.nan
        cmd[:, self._bots, 4] = 0.0
        if len(self._chunks) > 1:
            workers = self.arena.threads
            futures = [_pool(workers).submit(self._run, k, cmd) for k in range(len(self._chunks))]
            for f in futures:
                f.result()
        else:
            self._run(0, cmd)
        return cmd

    def play(self, turns: int, cmd: np.ndarray | None = None) -> int:
        """``turns`` times ``commands(cmd)``, ``arena.step(cmd)``, ``arena.reset(done)``, in compiled code.

        Gives the same states as that loop; battles run in parallel chunks, each its turns in a row. Robots
        without a bot keep their rows of ``cmd`` (default: idle). Returns the robots alive after each turn,
        summed over turns and battles (alive robot-turns).
        """
        if isinstance(turns, bool) or not isinstance(turns, int | np.integer) or turns < 0:
            raise ValueError(f"turns must be a non-negative integer, got {turns!r}")
        a = self.arena
        if cmd is None:
            cmd = a.idle_commands()
        if cmd.shape != (a.n_battles, a.n_robots, 5) or cmd.dtype != np.float64 or not cmd.flags.c_contiguous:
            raise ValueError(f"cmd must be a C-contiguous float64 array of shape ({a.n_battles}, {a.n_robots}, 5)")
        head, (params, scratch_i, scratch_f) = a._args
        sc = a.scenario
        tail = (cmd, params, scratch_i, scratch_f, a._fixed, a._has_fixed, float(sc.width), float(sc.height))
        nb, workers = a.n_battles, a.threads
        size = -(-nb // (_CHUNKS_PER_THREAD * workers)) if nb >= 2 * workers and workers > 1 else nb
        bounds = [(lo, min(nb, lo + size)) for lo in range(0, nb, size)]

        def run(lo: int, hi: int) -> int:
            return int(play_range(lo, hi, int(turns), self.kinds, self.mem, self._round, *head, *tail, np.zeros(4)))

        if len(bounds) == 1:
            return run(*bounds[0])
        return sum(f.result() for f in [_pool(workers).submit(run, lo, hi) for lo, hi in bounds])

    def _chunk_args(self) -> None:
        """Argument tuples of bots_step per battle chunk (views of the arena state: built once)."""
        s, nb, workers = self.arena.state, self.arena.n_battles, self.arena.threads
        size = -(-nb // workers) if nb >= 64 and workers > 1 else nb
        self._chunks = []
        for lo in range(0, nb, size):
            r = slice(lo, min(nb, lo + size))
            self._chunks.append((r, (
                self.kinds, self.mem[r], s.x[r], s.y[r], s.heading[r], s.gun_heading[r], s.radar_heading[r],
                s.energy[r], s.alive[r], s.team[r], s.distance_remaining[r], s.body_turn_remaining[r],
                s.gun_turn_remaining[r], s.radar_turn_remaining[r], s.max_velocity[r], s.fire_assist[r],
                s.scan_request[r], s.scanned[r], s.ev_hit_wall[r], s.ev_hit_robot[r], s.ev_hit_robot_bearing[r],
                s.ev_at_fault[r], s.ev_hit_by_bullet[r], s.ev_hit_by_bullet_bearing[r],
                s.ev_hit_by_bullet_heading[r], s.ev_died[r],
                float(self.arena.scenario.width), float(self.arena.scenario.height)), np.zeros(4),
                (s.packed["rf"][r, K.EVROBN:K.EVROB0 + 4 * HIT_ROBOT_SLOTS],
                 s.packed["rf"][r, K.EVBULN:K.EVBUL0 + 2 * HIT_BY_BULLET_SLOTS], s.gun_heat[r], s.scan_order[r])))

    def _run(self, k: int, cmd: np.ndarray) -> None:
        """bots_step on battle chunk k."""
        r, args, rem, tail = self._chunks[k]
        bots_step(*args, cmd[r], rem, *tail)


def bot_battle(names: list[str], rounds: int, seed: int = 0, n_battles: int = 20, turns_after_end: int = 150,
               scenario: Scenario | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Scripted robots over ``rounds`` rounds (spread over parallel battles); a free-for-all by default.

    ``names``: one bot per robot of ``scenario`` (default: a melee of ``len(names)`` single robots).
    Returns the score parts (R, 6) and placements (R, 3) summed over the rounds, robot order as
    ``names``; the score share of robot i is ``parts[i].sum() / parts.sum()``.
    """
    from .scenarios import get_scenario

    if rounds < 1:
        raise ValueError(f"rounds must be >= 1, got {rounds}")
    n_battles = min(n_battles, rounds)
    base = scenario if scenario is not None else get_scenario("melee").replace(teams=tuple(1 for _ in names))
    if base.n_robots != len(names):
        raise ValueError(f"scenario {base.name} has {base.n_robots} robots, got {len(names)} names")
    sc = base.replace(turns_after_end=turns_after_end, max_turns=100000)
    arena = Arena(sc, n_battles, seed=seed)
    bots = ScriptedBots(arena, list(names))
    quota = np.full(n_battles, rounds // n_battles)
    quota[: rounds % n_battles] += 1
    played = np.zeros(n_battles, dtype=np.int64)
    cmd = arena.idle_commands()
    s = arena.state
    while (played < quota).any():
        bots.commands(cmd)
        arena.step(cmd)
        done = s.done.copy()
        if done.any():
            played += done
            again = done & (played < quota)
            if again.any():
                arena.reset(again)
    return s.score_total.sum(axis=0), s.placements_total.sum(axis=0)


install(globals())
