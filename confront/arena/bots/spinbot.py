"""SpinBot (sample.SpinBot): circles at speed 5 turning right, fires 3 at whatever it scans or rams head-on."""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from . import common as c
from .common import KERNEL_INLINE, Robot, deg, handler_op, rad, run_op

KIND = 2
ROBOT = Robot("SpinBot", KIND, advanced=True)


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """run(): setTurnRight(10000), setMaxVelocity(5), ahead(10000); onScannedRobot: fire(3); onHitRobot: fire(3)
    when the robot is ahead (|bearing| < 10), turnRight(10) when it was its fault."""
    if kind != KIND:
        return
    if ev.prio == c.P_RUN:
        run_op(mem, b, i, c.O_SETTURN, 10000 * c.DEG)
        run_op(mem, b, i, c.O_SETMAXV, 5.0)
        run_op(mem, b, i, c.O_MOVE, 10000.0)
    elif ev.prio == c.P_ROBOT:
        bdeg = deg(ev.bearing)
        if -10 < bdeg < 10:
            handler_op(mem, b, i, c.O_FIRE, 3.0)
        if ev.aux == 1.0:
            handler_op(mem, b, i, c.O_TURN, rad(10.0))
    elif ev.prio == c.P_SCAN:
        handler_op(mem, b, i, c.O_FIRE, 3.0)


install(globals())
