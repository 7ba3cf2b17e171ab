"""Corners (sample.Corners): goes to a corner and sweeps its gun; moves to the next corner after a poor round."""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from ..kernels import E, H
from . import common as c
from .common import KERNEL_INLINE, Robot, handler_op, heading_deg, normal_relative_deg, rad, run_op

KIND = 7
ROBOT = Robot("Corners", KIND, advanced=False)
STOP_WHEN_SEE, GUN_STEP, START_OTHERS, STEPS = c.M_VAR, c.M_VAR + 1, c.M_VAR + 2, c.M_VAR + 3
CORNER = c.M_STATIC  # the corner's heading (static: kept across rounds), 0 at first


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """run(): turn to the corner, ahead(5000), turnLeft(90), ahead(5000), turnGunLeft(90); then 30 x
    turnGunLeft(3), 30 x turnGunRight(3), ... onScannedRobot: when stopWhenSeeRobot, stop, fire by distance
    and energy, scan, resume; else fire. onDeath: under 75 % of the others killed: the next corner."""
    if kind != KIND:
        return
    if ev.prio == c.P_RUN:
        if ev.aux == 1.0:
            mem[b, i, STOP_WHEN_SEE] = 0.0
            mem[b, i, GUN_STEP] = 3.0
            mem[b, i, START_OTHERS] = s.others - 1
            corner = mem[b, i, CORNER]
            run_op(mem, b, i, c.O_TURN, rad(normal_relative_deg(corner - heading_deg(s.robots.f[b, H, i]))))
            run_op(mem, b, i, c.O_SETMAXV, -4.0)  # stopWhenSeeRobot = true
            run_op(mem, b, i, c.O_MOVE, 5000.0)
            run_op(mem, b, i, c.O_TURN, -90 * c.DEG)
            run_op(mem, b, i, c.O_MOVE, 5000.0)
            run_op(mem, b, i, c.O_GUN, -90 * c.DEG)
        else:
            # 30 x turnGunLeft(gunIncrement) as one gun op of 90 deg would differ in scan timing only
            # slightly; keep the 3-degree steps through a counter
            run_op(mem, b, i, c.O_GUN, -rad(mem[b, i, GUN_STEP]))
            run_op(mem, b, i, c.O_SETMAXV, -5.0)  # marker: count the step, flip after 30
    elif ev.prio == c.P_MARK:
        if ev.aux == -4.0:
            mem[b, i, STOP_WHEN_SEE] = 1.0
        else:  # -5: flip the gun direction every 30 steps
            mem[b, i, STEPS] += 1
            if mem[b, i, STEPS] >= 30:
                mem[b, i, STEPS] = 0
                mem[b, i, GUN_STEP] *= -1
    elif ev.prio == c.P_DEATH:  # onDeath: a poor round (under 75 % of the others killed): the next corner
        start = mem[b, i, START_OTHERS]
        if start > 0 and (start - s.others) / start < 0.75:
            corner = mem[b, i, CORNER] + 90
            mem[b, i, CORNER] = -90.0 if corner == 270 else corner
    elif ev.prio == c.P_SCAN:
        dist = ev.dist
        p = 1.0 if (dist > 200 or s.robots.f[b, E, i] < 15) else (2.0 if dist > 50 else 3.0)
        if mem[b, i, STOP_WHEN_SEE] == 1.0:
            handler_op(mem, b, i, c.O_STOP, 0.0)
            handler_op(mem, b, i, c.O_FIREASSIST, p)
            handler_op(mem, b, i, c.O_SCAN, 0.0)
            handler_op(mem, b, i, c.O_RESUME, 0.0)
        else:
            handler_op(mem, b, i, c.O_FIREASSIST, p)


install(globals())
