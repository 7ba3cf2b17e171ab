"""The sample team sampleteam.MyFirstTeam: MyFirstLeader scans and tells its droids where the enemy is,
MyFirstDroid fires where it is told."""

from __future__ import annotations

import math

from numba import njit

from ..kernel_cache import install
from ..kernels import ALIVE, GH, TEAM, H, X, Y
from ..rules import java_atan2
from . import common as c
from .common import KERNEL_INLINE, Robot, add_message, deg, handler_op, heading_deg, normal_relative_deg, rad, run_op

LEADER_KIND, DROID_KIND = 10, 11
LEADER = Robot("MyFirstLeader", LEADER_KIND, advanced=True)
DROID = Robot("MyFirstDroid", DROID_KIND, advanced=True, droid=True)


@njit(**KERNEL_INLINE)
def leader_act(kind, mem, b, i, ev, s):
    """run(): setTurnRadarRight(10000), then ahead(100), back(100). onScannedRobot (an enemy): broadcast its
    position to the team. onHitByBullet: turnLeft(90 - bearing)."""
    if kind != LEADER_KIND:
        return
    if ev.prio == c.P_RUN:
        run_op(mem, b, i, c.O_SETRADAR, rad(10000.0))
        run_op(mem, b, i, c.O_MOVE, 100.0)
        run_op(mem, b, i, c.O_MOVE, -100.0)
    elif ev.prio == c.P_BULLET:  # turnLeft(90 - e.getBearing())
        handler_op(mem, b, i, c.O_TURN, -rad(90 - deg(ev.bearing)))
    elif ev.prio == c.P_SCAN:
        j = ev.j
        if (int(mem[b, i, c.M_MATES]) >> j) & 1:  # isTeammate(e.getName())
            return
        rf, rb, ri = s.robots
        eb = heading_deg(rf[b, H, i]) + deg(ev.bearing)
        ex = rf[b, X, i] + ev.dist * math.sin(rad(eb))
        ey = rf[b, Y, i] + ev.dist * math.cos(rad(eb))
        for d in range(rf.shape[2]):  # broadcastMessage(new Point(ex, ey)) to the droids
            if d != i and s.kinds[d] == DROID_KIND and ri[b, TEAM, d] == ri[b, TEAM, i] and rb[b, ALIVE, d]:
                add_message(mem, b, d, mem[b, i, c.M_CLOCK] + 1, ex, ey)


@njit(**KERNEL_INLINE)
def droid_act(kind, mem, b, i, ev, s):
    """run() returns at once; the robot then executes every turn, handling events. onMessageReceived(Point):
    aim the gun at the point, fire(3)."""
    if kind != DROID_KIND:
        return
    if ev.prio == c.P_RUN:
        run_op(mem, b, i, c.O_EXECUTE, 0.0)
    elif ev.prio == c.P_MESSAGE:
        rf = s.robots.f
        theta = java_atan2(ev.bearing - rf[b, X, i], ev.dist - rf[b, Y, i]) * c.RAD_TO_DEG
        handler_op(mem, b, i, c.O_GUN, rad(normal_relative_deg(theta - deg(rf[b, GH, i]))))
        handler_op(mem, b, i, c.O_FIRE, 3.0)


install(globals())
