"""Tracker (sample.Tracker): locks onto the first robot it sees, closes to 140 px and fires 3 when near."""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from ..kernels import RH, H
from . import common as c
from .common import KERNEL_INLINE, Robot, deg, handler_op, heading_deg, normal_relative_deg, rad, run_op

KIND = 4
ROBOT = Robot("Tracker", KIND, advanced=False, gun_for_body=True)
COUNT, GUN_TURN, TRACKED, WIN_TURNS = c.M_VAR, c.M_VAR + 1, c.M_VAR + 2, c.M_VAR + 5  # gunTurnAmt in degrees


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """run(): turnGunRight(gunTurnAmt) with the count bookkeeping (look the other way after 2 turns, back after
    5, forget the target after 11). onScannedRobot (the tracked robot, or any when none): aim the gun, turn and
    close to 140 px when farther than 150, else fire(3), back off under 100, scan(). onHitRobot: track it, aim,
    fire(3), back(50). onWin: 50 x (turnRight(30); turnLeft(30))."""
    if kind != KIND:
        return
    if ev.prio == c.P_RUN:
        if ev.aux == 1.0:
            mem[b, i, COUNT] = 0.0
            mem[b, i, GUN_TURN] = 10.0
            mem[b, i, TRACKED] = -1.0
        run_op(mem, b, i, c.O_GUN, rad(mem[b, i, GUN_TURN]))
        run_op(mem, b, i, c.O_SETMAXV, -3.0)  # marker: count bookkeeping after the turn
    elif ev.prio == c.P_MARK:
        if ev.aux == -3.0:  # the count
            count = mem[b, i, COUNT] + 1
            mem[b, i, COUNT] = count
            if count > 2:
                mem[b, i, GUN_TURN] = -10.0
            if count > 5:
                mem[b, i, GUN_TURN] = 10.0
            if count > 11:
                mem[b, i, TRACKED] = -1.0
        else:  # -7, onWin: for (i = 0; i < 50; i++) { turnRight(30); turnLeft(30); }
            mem[b, i, WIN_TURNS] += 1
            if mem[b, i, WIN_TURNS] < 50:
                base = c.M_LV + (c.N_LEVELS - 1) * c.LV_SIZE  # the win handler's level: its loop body again
                mem[b, i, base + c.LV_POS] = 0
                mem[b, i, base + c.LV_START] = 0
    elif ev.prio == c.P_WIN:
        mem[b, i, WIN_TURNS] = 0.0
        handler_op(mem, b, i, c.O_TURN, rad(30.0))
        handler_op(mem, b, i, c.O_TURN, -rad(30.0))
        handler_op(mem, b, i, c.O_SETMAXV, -7.0)
    elif ev.prio == c.P_ROBOT:
        rf = s.robots.f
        bdeg = deg(ev.bearing)
        mem[b, i, TRACKED] = ev.j
        amt = normal_relative_deg(bdeg + (heading_deg(rf[b, H, i]) - deg(rf[b, RH, i])))
        mem[b, i, GUN_TURN] = amt
        handler_op(mem, b, i, c.O_GUN, rad(amt))
        handler_op(mem, b, i, c.O_FIRE, 3.0)
        handler_op(mem, b, i, c.O_MOVE, -50.0)
    elif ev.prio == c.P_SCAN:
        rf = s.robots.f
        bdeg = deg(ev.bearing)
        track = int(mem[b, i, TRACKED])
        if track >= 0 and ev.j != track:
            return
        mem[b, i, TRACKED] = ev.j
        mem[b, i, COUNT] = 0.0
        amt = normal_relative_deg(bdeg + (heading_deg(rf[b, H, i]) - deg(rf[b, RH, i])))
        mem[b, i, GUN_TURN] = amt
        handler_op(mem, b, i, c.O_GUN, rad(amt))
        if ev.dist > 150:
            handler_op(mem, b, i, c.O_TURN, rad(bdeg))
            handler_op(mem, b, i, c.O_MOVE, ev.dist - 140)
        else:
            handler_op(mem, b, i, c.O_FIREASSIST, 3.0)
            if ev.dist < 100:
                handler_op(mem, b, i, c.O_MOVE, -40.0 if -90 < bdeg <= 90 else 40.0)
            handler_op(mem, b, i, c.O_SCAN, 0.0)


install(globals())
