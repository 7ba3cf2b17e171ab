"""What a scripted robot's module uses: its description, the operations it queues, its memory row, its events.

A robot is written as Robocode code runs: ``run()``'s loop and the ``onXxx`` handlers queue *operations* (a
blocking ``ahead`` / ``turnRight`` / ``turnGunRight`` / ``turnRadarRight``, ``fire``, ``scan``, ``stop``,
``resume``, setters that do not block, ``execute``) that :mod:`.controller` plays turn by turn. Each robot keeps
a memory row ``mem[b, i]`` (float64): the controller's part (levels, event queue), 8 variables ``M_VAR..`` that a
new round clears, a few statics kept across the rounds of a battle (``M_STATIC``, Corners' corner), then
the robot's own ``Robot.memory`` floats at ``M_OWN``, kept across the rounds of a battle (its per-battle
memory: GuessFactor bins, waves; clear what must start afresh each round at the round's first ``P_RUN``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..kernel_cache import install
from ..state import Robots

__all__ = ["Robot", "Event", "Scene", "KERNEL", "KERNEL_INLINE"]

# numba options of the bot kernels (no reference counting: they only index arrays; numpy's error model)
KERNEL = {"cache": True, "forceinline": False, "_nrt": False, "error_model": "numpy"}
KERNEL_INLINE = dict(KERNEL, forceinline=True)


class Robot(NamedTuple):
    """A scripted robot as Python sees it (the registry's entry; its compiled code is its module's ``act``)."""

    name: str  # the sample robot's class name, as scenarios and opponents name it
    kind: int  # its code in the ``kinds`` arrays (unique, > 0)
    advanced: bool  # an AdvancedRobot (TeamRobot included): no fire assist, wall damage
    gun_for_body: bool = False  # setAdjustGunForRobotTurn(true) (Tracker)
    droid: bool = False  # a Droid: 120 energy, no radar
    memory: int = 0  # floats of its own at mem[b, i, M_OWN:], kept across the rounds of a battle


class Event(NamedTuple):
    """What ``act`` is called for: a queued Robocode event (its priority; the other robot, its bearing (rad), the
    distance, its energy, ``aux``: at fault (1.0) for a ram, the bullet's heading for a hit by bullet), or a
    pseudo-event: P_RUN (the next pass of run(); ``aux`` 1.0 in the round's first), P_MARK (a bookkeeping step
    queued as ``O_SETMAXV`` with a negative code in ``aux``), P_DEATH (the robot died; ``dist``: robots alive)."""

    prio: float
    j: int
    bearing: float
    dist: float
    energy: float
    aux: float


class Scene(NamedTuple):
    """What a robot sees of battle b while it acts: the arena's robots (kernels' field positions X, Y, H, ...), each
    robot's kind, the commands of this turn (B, R, 5), the field, the robots alive."""

    robots: Robots
    kinds: np.ndarray
    cmd: np.ndarray
    width: float
    height: float
    others: int  # robots alive (the robot itself included) as the battle's decisions start


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
M_OWN = M_STATIC + 8  # the robot's own memory (Robot.memory floats)
M_SIZE = M_OWN  # the row without any robot's own memory
M_ROUND_START = ((M_STOPPED, 1.0), (M_TOPT, -1.0))  # per-round memory that does not start at 0
MAX_EVENT_STACK = 2  # Robocode EventManager: events older than 2 turns are dropped

# event priorities (Robocode's), and the pseudo-events of Event
P_SCAN, P_BULLET, P_WALL, P_ROBOT, P_MESSAGE, P_WIN = 10.0, 20.0, 30.0, 40.0, 75.0, 100.0
P_RUN, P_MARK, P_DEATH = -1.0, -2.0, -3.0
DEG = math.pi / 180.0  # == Math.toRadians(1) (java.lang.Math.DEGREES_TO_RADIANS)
RAD_TO_DEG = 57.29577951308232  # java.lang.Math.RADIANS_TO_DEGREES (Math.toDegrees)


@njit(**KERNEL_INLINE)
def deg(r):
    """Radians as the robot API reports degrees (ScannedRobotEvent.getBearing, Robot.getGunHeading: r*180/PI)."""
    return r * 180.0 / math.pi


@njit(**KERNEL_INLINE)
def heading_deg(h):
    """Robot.getHeading(): 180*h/PI, wrapped into [0, 360)."""
    d = 180.0 * h / math.pi
    while d < 0:
        d += 360.0
    while d >= 360.0:
        d -= 360.0
    return d


@njit(**KERNEL_INLINE)
def rad(d):
    """Math.toRadians: the degree methods (turnRight, turnGunRight, ...) hand the peer d * DEGREES_TO_RADIANS."""
    return d * DEG


@njit(**KERNEL_INLINE)
def normal_relative_deg(a):
    """Utils.normalRelativeAngleDegrees: a % 360 into [-180, 180)."""
    if -180.0 <= a < 180.0:  # fmod leaves these unchanged and the result is a itself; skip the slow call
        return a
    a = np.fmod(a, 360.0)
    if a >= 0:
        return a if a < 180 else a - 360
    return a if a >= -180 else a + 360


@njit(**KERNEL_INLINE)
def level_of(prio):
    """Execution level of a handler priority."""
    for lv in range(1, N_LEVELS):
        if LEVEL_PRIORITY[lv] == prio:
            return lv
    return 0


@njit(**KERNEL_INLINE)
def top_level(mem, b, i):
    """The running execution level: the highest active handler, else run() (0)."""
    for lv in range(N_LEVELS - 1, 0, -1):
        if mem[b, i, M_LV + lv * LV_SIZE + LV_ACTIVE] == 1.0:
            return lv
    return 0


@njit(**KERNEL_INLINE)
def push(mem, b, i, lv, op, val):
    """Append an operation to level lv's queue."""
    base = M_LV + lv * LV_SIZE
    n = int(mem[b, i, base + LV_LEN])
    if n < Q:
        mem[b, i, base + LV_OPS + 2 * n] = op
        mem[b, i, base + LV_OPS + 2 * n + 1] = val
        mem[b, i, base + LV_LEN] = n + 1


@njit(**KERNEL_INLINE)
def clear_level(mem, b, i, lv, active):
    base = M_LV + lv * LV_SIZE
    mem[b, i, base + LV_ACTIVE] = active
    mem[b, i, base + LV_LEN] = 0
    mem[b, i, base + LV_POS] = 0
    mem[b, i, base + LV_START] = 0


@njit(**KERNEL)
def handler_op(mem, b, i, op, val):
    """Append an operation to the handler being dispatched (the top level)."""
    push(mem, b, i, top_level(mem, b, i), op, val)


@njit(**KERNEL)
def run_op(mem, b, i, op, val):
    """Append an operation to run()'s queue (level 0)."""
    push(mem, b, i, np.int64(0), op, val)


@njit(**KERNEL_INLINE)
def add_message(mem, b, d, time, px, py):
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


install(globals())
