"""TrackFire (sample.TrackFire): stands still, turns its gun to what it scans and fires when it points there."""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from ..kernels import GH, H
from . import common as c
from .common import KERNEL_INLINE, Robot, deg, handler_op, heading_deg, normal_relative_deg, rad, run_op

KIND = 9
ROBOT = Robot("TrackFire", KIND, advanced=False)


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """run(): turnGunRight(10). onScannedRobot: turn the gun to it; within 3 degrees, fire(3 - the angle) when the
    gun is cold; scan() when it points exactly at it. onWin: turnRight(36000)."""
    if kind != KIND:
        return
    if ev.prio == c.P_RUN:
        run_op(mem, b, i, c.O_GUN, 10 * c.DEG)
    elif ev.prio == c.P_WIN:
        handler_op(mem, b, i, c.O_TURN, rad(36000.0))
    elif ev.prio == c.P_SCAN:
        rf = s.robots.f
        bfg = normal_relative_deg(heading_deg(rf[b, H, i]) + deg(ev.bearing) - deg(rf[b, GH, i]))  # from the gun
        handler_op(mem, b, i, c.O_GUN, rad(bfg))
        if abs(bfg) <= 3:
            handler_op(mem, b, i, c.O_FIRECOOL, 3 - abs(bfg))
        if bfg == 0:
            handler_op(mem, b, i, c.O_SCAN, 0.0)


install(globals())
