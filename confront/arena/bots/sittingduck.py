"""SittingDuck (sample.SittingDuck): sits still and does nothing (the controller skips it: see registry.PASSIVE)."""

from __future__ import annotations

from numba import njit

from ..kernel_cache import install
from .common import KERNEL_INLINE, Robot

KIND = 1
ROBOT = Robot("SittingDuck", KIND, advanced=True)


@njit(**KERNEL_INLINE)
def act(kind, mem, b, i, ev, s):
    """Nothing: it never moves, turns or fires."""
    return


install(globals())
