"""The scripted robots by kind: their descriptions (:data:`ROBOTS`) and the compiled dispatch to their ``act``.

Registering a robot: import its module here, add its ``ROBOT`` to :data:`ROBOTS` and its ``act`` to :func:`act`
(the package docstring has the whole recipe).
"""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from . import corners, crazy, fire, myfirstteam, ramfire, sittingduck, spinbot, tracker, trackfire, walls
from .common import KERNEL_INLINE, Robot

ROBOTS: tuple[Robot, ...] = (sittingduck.ROBOT, spinbot.ROBOT, walls.ROBOT, tracker.ROBOT, ramfire.ROBOT, fire.ROBOT,
                             corners.ROBOT, crazy.ROBOT, trackfire.ROBOT, myfirstteam.LEADER, myfirstteam.DROID)
BY_NAME = {r.name: r for r in ROBOTS}
N_KINDS = max(r.kind for r in ROBOTS) + 1
# per kind code (0 = none): an AdvancedRobot (no fire assist); passive (the controller skips it: it never acts)
ADVANCED = tuple(any(r.advanced for r in ROBOTS if r.kind == k) for k in range(N_KINDS))
PASSIVE = tuple(k == sittingduck.KIND for k in range(N_KINDS))


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """Robot i of battle b acts on ``ev`` (an Event: a Robocode event or run()'s next pass): each robot's ``act``
    runs when ``kind`` is its own."""
    if kind <= 6:
        sittingduck.act(kind, mem, b, i, ev, s)
        spinbot.act(kind, mem, b, i, ev, s)
        walls.act(kind, mem, b, i, ev, s)
        tracker.act(kind, mem, b, i, ev, s)
        ramfire.act(kind, mem, b, i, ev, s)
        fire.act(kind, mem, b, i, ev, s)
    else:
        corners.act(kind, mem, b, i, ev, s)
        crazy.act(kind, mem, b, i, ev, s)
        trackfire.act(kind, mem, b, i, ev, s)
        myfirstteam.leader_act(kind, mem, b, i, ev, s)
        myfirstteam.droid_act(kind, mem, b, i, ev, s)


install(globals())
