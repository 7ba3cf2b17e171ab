"""RamFire (sample.RamFire): spins until it sees a robot, then rams it, firing by the target's energy."""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from . import common as c
from .common import KERNEL_INLINE, Robot, deg, handler_op, rad, run_op

KIND = 5
ROBOT = Robot("RamFire", KIND, advanced=False)
DIRECTION = c.M_VAR  # turnDirection: 1 right, -1 left


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """run(): turnRight(5 * turnDirection). onScannedRobot: turn to it, ahead(distance + 5), scan().
    onHitRobot: turn to it, fire by its energy (3 over 16, 2 over 10, 1 over 4, .5 over 2, .1 over .4), ahead(40)."""
    if kind != KIND:
        return
    if ev.prio == c.P_RUN:
        if ev.aux == 1.0:
            mem[b, i, DIRECTION] = 1.0
        run_op(mem, b, i, c.O_TURN, rad(5 * mem[b, i, DIRECTION]))
    elif ev.prio == c.P_ROBOT:
        bdeg = deg(ev.bearing)
        mem[b, i, DIRECTION] = 1.0 if bdeg >= 0 else -1.0
        handler_op(mem, b, i, c.O_TURN, rad(bdeg))
        e_energy = ev.energy
        if e_energy > 16:
            handler_op(mem, b, i, c.O_FIRE, 3.0)
        elif e_energy > 10:
            handler_op(mem, b, i, c.O_FIRE, 2.0)
        elif e_energy > 4:
            handler_op(mem, b, i, c.O_FIRE, 1.0)
        elif e_energy > 2:
            handler_op(mem, b, i, c.O_FIRE, 0.5)
        elif e_energy > 0.4:
            handler_op(mem, b, i, c.O_FIRE, 0.1)
        handler_op(mem, b, i, c.O_MOVE, 40.0)
    elif ev.prio == c.P_SCAN:
        bdeg = deg(ev.bearing)
        mem[b, i, DIRECTION] = 1.0 if bdeg >= 0 else -1.0
        handler_op(mem, b, i, c.O_TURN, rad(bdeg))
        handler_op(mem, b, i, c.O_MOVE, ev.dist + 5)
        handler_op(mem, b, i, c.O_SCAN, 0.0)


install(globals())
