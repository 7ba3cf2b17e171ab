"""Walls (sample.Walls): runs along the walls, gun pointing in, fires 2 at what it scans."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..kernel_cache import install
from ..kernels import H
from . import common as c
from .common import KERNEL_INLINE, Robot, deg, handler_op, heading_deg, rad, run_op

KIND = 3
ROBOT = Robot("Walls", KIND, advanced=False)
PEEK = c.M_VAR  # peek: scan() after firing (set while moving along a wall, not while turning)


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """run(): turnLeft(heading % 90), ahead(max side), peek, turnGunRight(90), turnRight(90); then the loop
    peek, ahead(max side), no peek, turnRight(90). onHitRobot: back off 100 (or ahead 100 from behind);
    onScannedRobot: fire(2), scan() while peeking."""
    if kind != KIND:
        return
    if ev.prio == c.P_RUN:
        amount = max(s.width, s.height)
        if ev.aux == 1.0:
            mem[b, i, PEEK] = 0.0
            heading = s.robots.f[b, H, i]
            run_op(mem, b, i, c.O_TURN, -rad(np.fmod(heading_deg(heading), 90.0)))  # turnLeft(getHeading() % 90)
            run_op(mem, b, i, c.O_MOVE, amount)
            run_op(mem, b, i, c.O_SETMAXV, -1.0)  # marker: peek = true
            run_op(mem, b, i, c.O_GUN, 90 * c.DEG)
            run_op(mem, b, i, c.O_TURN, 90 * c.DEG)
        else:
            run_op(mem, b, i, c.O_SETMAXV, -1.0)  # peek = true
            run_op(mem, b, i, c.O_MOVE, amount)
            run_op(mem, b, i, c.O_SETMAXV, -2.0)  # peek = false
            run_op(mem, b, i, c.O_TURN, 90 * c.DEG)
    elif ev.prio == c.P_MARK:
        mem[b, i, PEEK] = 1.0 if ev.aux == -1.0 else 0.0
    elif ev.prio == c.P_ROBOT:
        bdeg = deg(ev.bearing)
        handler_op(mem, b, i, c.O_MOVE, -100.0 if -90 < bdeg < 90 else 100.0)
    elif ev.prio == c.P_SCAN:
        handler_op(mem, b, i, c.O_FIREASSIST, 2.0)
        if mem[b, i, PEEK] == 1.0:
            handler_op(mem, b, i, c.O_SCAN, 0.0)


install(globals())
