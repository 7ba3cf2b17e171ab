"""The controller of the scripted robots: Robocode's event manager and blocking calls, played turn by turn.

A plain ``Robot`` blocks on every call; here each robot has a small state machine in its memory row
(:mod:`.common`'s layout):

- execution levels: ``run()``'s loop (level 0) and one level per handler priority (scanned robot 10, hit
  by bullet 20, hit wall 30, hit robot 40, message 75, win 100), each a queue of operations; a handler nests
  only handlers of higher priority, and when it returns the level below resumes its blocking call (finished if
  the remaining value is 0 by then: Robocode's ``do { execute() } while (remaining != 0)``).
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

What each robot does (its ``run()`` passes and handlers) is its module's ``act``, reached through
:func:`.registry.act` by the robot's kind.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .. import kernels as K
from ..kernel_cache import install
from ..rules import java_atan2, java_hypot, normal_absolute_angle, normal_relative_angle
from ..state import HIT_BY_BULLET_SLOTS, HIT_ROBOT_SLOTS
from .common import (
    E_AUX,
    E_BEAR,
    E_DIST,
    E_EN,
    E_J,
    E_PRIO,
    E_SEQ,
    E_SIZE,
    E_TIME,
    KERNEL,
    KERNEL_INLINE,
    LEVEL_PRIORITY,
    LV_LEN,
    LV_OPS,
    LV_POS,
    LV_SIZE,
    LV_START,
    M_CLOCK,
    M_EVQ,
    M_INTR,
    M_INTR_ORIG,
    M_LV,
    M_NEV,
    M_PHASE,
    M_SAVE,
    M_STATIC,
    M_STOPPED,
    M_TOPB,
    M_TOPSCAN,
    M_TOPT,
    M_WON,
    MAX_EVENT_STACK,
    N_EVQ,
    O_EXECUTE,
    O_FIRE,
    O_FIREASSIST,
    O_FIRECOOL,
    O_GUN,
    O_MOVE,
    O_RADAR,
    O_RESUME,
    O_SCAN,
    O_SETMAXV,
    O_SETMOVE,
    O_SETRADAR,
    O_SETTURN,
    O_STOP,
    O_TURN,
    O_WAITTURN,
    P_BULLET,
    P_DEATH,
    P_MARK,
    P_ROBOT,
    P_RUN,
    P_SCAN,
    P_WALL,
    P_WIN,
    Event,
    Scene,
    clear_level,
    level_of,
    top_level,
)
from .registry import ADVANCED, PASSIVE, act

__all__ = ["BotState", "bots_step", "play_range", "clear_memory"]


class BotState(NamedTuple):
    """The scripted robots' state: each robot's kind (R,) (0: not scripted), their memory rows (B, R, M), and the
    four remaining values a call reads (4,) (scratch: one per thread)."""

    kinds: np.ndarray
    mem: np.ndarray
    rem: np.ndarray


@njit(**KERNEL)
def refill_main(kind, mem, b, i, s):
    """Next pass of run(): the set-up part once per round (``aux`` 1.0), then the loop body."""
    clear_level(mem, b, i, np.int64(0), 1.0)
    first = mem[b, i, M_PHASE] == 0
    mem[b, i, M_PHASE] = 1
    act(kind, mem, b, i, Event(P_RUN, np.int64(-1), 0.0, 0.0, 0.0, 1.0 if first else 0.0), s)


@njit(**KERNEL)
def mark(kind, mem, b, i, code, s):
    """Bookkeeping steps of run() written as pseudo-operations (negative SETMAXV values)."""
    act(kind, mem, b, i, Event(P_MARK, np.int64(-1), 0.0, 0.0, 0.0, code), s)


@njit(**KERNEL_INLINE)
def op_done(op, started, rem_d, rem_b, rem_g, rem_r):
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


@njit(**KERNEL_INLINE)
def issue(kind, mem, b, i, op, val, s, rem):
    """Write an operation's commands; True if it takes the turn (blocking)."""
    rf, rb, _ = s.robots
    cmd = s.cmd
    if op == O_EXECUTE:
        return True
    if op == O_SETRADAR:
        cmd[b, i, 3] = val
        return False
    if op == O_FIRECOOL:  # TrackFire: if (getGunHeat() == 0) fire(min(val, getEnergy() - .1))
        if rf[b, K.HEAT, i] > 0.0:
            return False
        cmd[b, i, 4] = max(min(val, rf[b, K.E, i] - 0.1), 0.1)  # setFire clamps the power up to 0.1
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
        if not ADVANCED[kind] and mem[b, i, M_TOPSCAN] == 1.0 and rf[b, K.GH, i] == rf[b, K.RH, i] \
                and mem[b, i, M_TOPT] == mem[b, i, M_CLOCK]:
            rf[b, K.ASSIST, i] = normal_absolute_angle(rf[b, K.H, i] + mem[b, i, M_TOPB])
        return True
    if op == O_SCAN:
        rb[b, K.SCANREQ, i] = True
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
            rf[b, K.MAXV, i] = val
        else:
            mark(kind, mem, b, i, val, s)
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
def _head(mem, b, i):
    """Index of the first queued event in Robocode's order (-1: empty)."""
    best = np.int64(-1)  # not a literal -1: _dispatch(k) is then compiled once, for int64
    for k in range(int(mem[b, i, M_NEV])):
        if mem[b, i, M_EVQ + k * E_SIZE + E_TIME] > mem[b, i, M_CLOCK]:
            continue  # a team message sent this turn: delivered in the next one
        if best < 0 or _before(mem, b, i, k, best):
            best = k
    return best



@njit(**KERNEL_INLINE)
def enqueue(mem, b, i, robots, radar):
    """Queue the last turn's events, then drop those older than MAX_EVENT_STACK turns.

    The scans in the order of the robot's own random list of that turn (``scan_order``, the arena's): where
    two distances differ by under 1 px, the one first in that list is handled first."""
    rf, rb, ri = robots
    scanned, scan_order = radar.scanned, radar.scan_order
    n = rf.shape[2]
    # one HitRobotEvent per collision, in the engine's order (RobotPeer.checkRobotCollision)
    for k in range(min(int(rf[b, K.EVROBN, i]), HIT_ROBOT_SLOTS)):
        r0 = K.EVROB0 + 4 * k
        _add_event(mem, b, i, P_ROBOT, rf[b, r0, i], rf[b, r0 + 1, i], 0.0, rf[b, r0 + 3, i], rf[b, r0 + 2, i])
    if rb[b, K.EVWALL, i]:
        _add_event(mem, b, i, P_WALL, -1.0, 0.0, 0.0, 0.0, 0.0)
    # one HitByBulletEvent per bullet, in the engine's bullet order (BulletPeer.checkRobotCollision); the event
    # carries the bullet's own heading (Bullet.getHeadingRadians)
    for k in range(min(int(rf[b, K.EVBULN, i]), HIT_BY_BULLET_SLOTS)):
        _add_event(mem, b, i, P_BULLET, -1.0, rf[b, K.EVBUL0 + 2 * k, i], 0.0, 0.0, rf[b, K.EVBUL0 + 2 * k + 1, i])
    x, y, energy, alive, team = rf[b, K.X], rf[b, K.Y], rf[b, K.E], rb[b, K.ALIVE], ri[b, K.TEAM]
    for q in range(n):
        j2 = int(scan_order[b, i, q])
        if scanned[b, i, j2] and alive[j2]:
            dx = x[j2] - x[i]
            dy = y[j2] - y[i]
            bearing = normal_relative_angle(java_atan2(dx, dy) - rf[b, K.H, i])  # Java's atan2 and hypot (fdlibm)
            _add_event(mem, b, i, P_SCAN, float(j2), bearing, java_hypot(dx, dy), energy[j2], 0.0)
    if mem[b, i, M_WON] == 0.0 and alive[i]:
        won = True
        for j2 in range(n):
            if alive[j2] and team[j2] != team[i]:
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


@njit(**KERNEL_INLINE)
def dispatch(kind, mem, b, i, k, s):
    """Start the handler of queued event k (removed from the queue): its level and operations."""
    e = M_EVQ + k * E_SIZE
    prio = mem[b, i, e + E_PRIO]
    ev = Event(prio, int(mem[b, i, e + E_J]), mem[b, i, e + E_BEAR], mem[b, i, e + E_DIST], mem[b, i, e + E_EN],
               mem[b, i, e + E_AUX])
    mem[b, i, M_TOPT] = mem[b, i, e + E_TIME]
    mem[b, i, M_TOPSCAN] = 1.0 if prio == P_SCAN else 0.0
    mem[b, i, M_TOPB] = ev.bearing
    _remove_event(mem, b, i, k)
    clear_level(mem, b, i, level_of(prio), 1.0)
    act(kind, mem, b, i, ev, s)


@njit(**KERNEL_INLINE)
def battle_step(b, bots, robots, radar, cmd, width, height):
    """One decision of battle b's scripted robots (their robot time between two turns).

    Each robot resumes inside the execute() of its running blocking call: EventManager.processEvents first
    (dispatch the head event while its priority is above the running level's; an equal one stops the loop
    unless the scanned-robot priority is interruptible, i.e. the handler waits in scan(): it is then aborted),
    then the call's remaining-value test, then the code after it up to the next blocking call. A disabled
    robot (energy 0) runs on: its moves and body turns are refused by the engine, the rest works.
    """
    kinds, mem, rem = bots
    rf, rb, _ = robots
    n = rf.shape[2]
    others = 0
    for i in range(n):
        others += 1 if rb[b, K.ALIVE, i] else 0
    s = Scene(robots, kinds, cmd, width, height, others)
    for i in range(n):
        kind = kinds[i]
        if kind != 0 and rb[b, K.EVDIED, i]:  # onDeath
            act(kind, mem, b, i, Event(P_DEATH, np.int64(-1), 0.0, 0.0, 0.0, 0.0), s)
        if kind == 0 or PASSIVE[kind] or not (rb[b, K.ALIVE, i] or rb[b, K.EVDIED, i]):
            mem[b, i, M_CLOCK] += 1
            continue
        # a robot that died this turn still wakes once: its blocking call returns and its code runs on to the
        # next one, which throws DeathException (RobotPeer.executeImpl); commands of the dead are ignored
        rem[0] = rf[b, K.DIST, i]
        rem[1] = rf[b, K.BODYREM, i]
        rem[2] = rf[b, K.GUNREM, i]
        rem[3] = rf[b, K.RADREM, i]
        enqueue(mem, b, i, robots, radar)
        lv = top_level(mem, b, i)
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
                        clear_level(mem, b, i, lv, 0.0)
                        mem[b, i, M_TOPT] = -1.0
                        mem[b, i, M_TOPSCAN] = 0.0
                        lv = top_level(mem, b, i)
                    else:
                        process = False
                else:
                    dispatch(kind, mem, b, i, k, s)
                    lv = level_of(prio)
                    process = False
                continue
            pos = int(mem[b, i, base + LV_POS])
            if pos >= int(mem[b, i, base + LV_LEN]):
                if lv == 0:
                    refill_main(kind, mem, b, i, s)
                else:  # the handler returns into the processEvents loop of the level below
                    if lv == 1:
                        mem[b, i, M_INTR] = 0.0  # processEvents: setInterruptible(priority, false)
                    clear_level(mem, b, i, lv, 0.0)
                    lv = top_level(mem, b, i)
                    process = True
                continue
            op = mem[b, i, base + LV_OPS + 2 * pos]
            val = mem[b, i, base + LV_OPS + 2 * pos + 1]
            if mem[b, i, base + LV_START] == 1:
                if op_done(op, True, rem[0], rem[1], rem[2], rem[3]):
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
            if issue(kind, mem, b, i, op, val, s, rem):
                break
        mem[b, i, M_CLOCK] += 1


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy", nogil=True)
def bots_step(b0, b1, bots, robots, radar, cmd, width, height):
    """One decision of every scripted robot of battles b0..b1-1 (their robot time between two turns): their rows of
    ``cmd`` (B, R, 5), and the settings they change in ``robots`` (max velocity, fire assist, scan requests).
    One call signature only: each variant is a compile."""
    for b in range(b0, b1):
        battle_step(b, bots, robots, radar, cmd, width, height)


@njit(**KERNEL)
def clear_memory(mem, b):
    """A new round: forget battle b's per-round bot memory (statics such as Corners' corner stay)."""
    for i in range(mem.shape[1]):
        for k in range(M_STATIC):
            mem[b, i, k] = 0.0
        mem[b, i, M_TOPT] = -1.0
        mem[b, i, M_STOPPED] = 1.0  # the proxy starts each round as stopped: stop() saves nothing, resume() zeros


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy", nogil=True)
def play_range(b0, b1, turns, bots, rounds, robots, battles, bullets, radar, scores, cmd, settings, scratch):
    """``turns`` turns of battles b0..b1-1, each as ``commands``, ``Arena.step``, ``Arena.reset(done)``.

    Battles are independent, so each runs all its turns before the next (its data stays in cache).
    Returns the robots alive after each turn, summed (alive robot-turns).
    """
    kinds, mem = bots.kinds, bots.mem
    rb = robots.b
    bi, bb = battles.i, battles.b
    n = rb.shape[2]
    width, height = settings.params[K.P_W], settings.params[K.P_H]
    total = 0
    for b in range(b0, b1):
        for _ in range(turns):
            if rounds[b] != bi[b, K.ROUND]:  # sync_rounds: a round started since the bots last acted
                clear_memory(mem, b)
                rounds[b] = bi[b, K.ROUND]
            for i in range(n):
                if kinds[i] != 0:
                    for c in range(4):
                        cmd[b, i, c] = math.nan
                    cmd[b, i, 4] = 0.0
            battle_step(b, bots, robots, radar, cmd, width, height)
            if not bb[b, K.DONE]:
                K.step_battle_at(b, robots, battles, bullets, radar, scores, cmd, settings, scratch)
            for i in range(n):
                total += 1 if rb[b, K.ALIVE, i] else 0
            if bb[b, K.DONE]:
                K.reset_battle(b, robots, battles, bullets, radar, scores, settings)
    return total


install(globals())
