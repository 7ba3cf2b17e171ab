"""Fire (sample.Fire): sits and turns its gun, fires at what it scans, moves aside when hit."""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from ..kernels import GH, E, H
from . import common as c
from .common import KERNEL_INLINE, Robot, deg, handler_op, heading_deg, normal_relative_deg, rad, run_op

KIND = 6
ROBOT = Robot("Fire", KIND, advanced=False)
DIST = c.M_VAR  # the next sidestep (50, alternating sign)


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """run(): turnGunRight(5). onScannedRobot: fire(3) when near (< 50) with energy over 50, else fire(1);
    scan(). onHitByBullet: turn perpendicular to the bullet, ahead(dist), dist = -dist, scan().
    onHitRobot: aim the gun at it, fire(3)."""
    if kind != KIND:
        return
    if ev.prio == c.P_RUN:
        if ev.aux == 1.0:
            mem[b, i, DIST] = 50.0
        run_op(mem, b, i, c.O_GUN, 5 * c.DEG)
    elif ev.prio == c.P_ROBOT:
        rf = s.robots.f
        bdeg = deg(ev.bearing)
        handler_op(mem, b, i, c.O_GUN, rad(normal_relative_deg(bdeg + heading_deg(rf[b, H, i]) - deg(rf[b, GH, i]))))
        handler_op(mem, b, i, c.O_FIRE, 3.0)
    elif ev.prio == c.P_BULLET:  # turn perpendicular to the bullet, move, scan
        hb = s.robots.f[b, H, i]
        handler_op(mem, b, i, c.O_TURN, rad(normal_relative_deg(90 - (heading_deg(hb) - ev.aux * c.RAD_TO_DEG))))
        handler_op(mem, b, i, c.O_MOVE, mem[b, i, DIST])
        mem[b, i, DIST] *= -1
        handler_op(mem, b, i, c.O_SCAN, 0.0)
    elif ev.prio == c.P_SCAN:
        handler_op(mem, b, i, c.O_FIREASSIST, 3.0 if ev.dist < 50 and s.robots.f[b, E, i] > 50 else 1.0)
        handler_op(mem, b, i, c.O_SCAN, 0.0)


install(globals())
