"""Crazy (sample.Crazy): drives in curves, reversing at walls and after ramming, fires 1 at what it scans."""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from . import common as c
from .common import KERNEL_INLINE, Robot, handler_op, run_op

KIND = 8
ROBOT = Robot("Crazy", KIND, advanced=True)
FORWARD = c.M_VAR + 4  # movingForward


@njit(**KERNEL_INLINE)
def reverse(mem, b, i, cmd):
    """Crazy.reverseDirection: setBack/setAhead(40000)."""
    if mem[b, i, FORWARD] == 1.0:
        cmd[b, i, 0] = -40000.0
        mem[b, i, FORWARD] = 0.0
    else:
        cmd[b, i, 0] = 40000.0
        mem[b, i, FORWARD] = 1.0


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """run(): setAhead(40000), movingForward = true, setTurnRight(90), waitFor(turn complete),
    setTurnLeft(180), wait, setTurnRight(180), wait. onHitWall, onHitRobot (its fault): reverse.
    onScannedRobot: fire(1)."""
    if kind != KIND:
        return
    if ev.prio == c.P_RUN:
        run_op(mem, b, i, c.O_SETMOVE, 40000.0)
        run_op(mem, b, i, c.O_SETMAXV, -6.0)  # movingForward = true
        run_op(mem, b, i, c.O_SETTURN, 90 * c.DEG)
        run_op(mem, b, i, c.O_WAITTURN, 0.0)
        run_op(mem, b, i, c.O_SETTURN, -180 * c.DEG)
        run_op(mem, b, i, c.O_WAITTURN, 0.0)
        run_op(mem, b, i, c.O_SETTURN, 180 * c.DEG)
        run_op(mem, b, i, c.O_WAITTURN, 0.0)
    elif ev.prio == c.P_MARK:
        mem[b, i, FORWARD] = 1.0
    elif ev.prio == c.P_ROBOT:
        if ev.aux == 1.0:
            reverse(mem, b, i, s.cmd)
    elif ev.prio == c.P_WALL:
        reverse(mem, b, i, s.cmd)
    elif ev.prio == c.P_SCAN:
        handler_op(mem, b, i, c.O_FIRE, 1.0)


install(globals())
