"""One CPU for each engine process, claimed so that concurrent engine runs take different ones.

Every turn Robocode's battle thread wakes each robot's thread in turn and waits until it has acted
(``Battle.wakeupSerial``). When those threads run on different CPUs every hand-off is a cross-CPU wake-up, which
costs tens of microseconds on a virtual machine; on one CPU it is a plain thread switch. On the project's
2-CPU machine an engine process held to one CPU played battles 1.2-2.5x faster (docs/engine.md, "One CPU per
engine process"); the engine's own thread races (a dead robot's last turn) may then go the other way, so it is
used for training in the engine, not for comparisons with the simulator. The JVM then compiles with C1 only
(``-XX:TieredStopAtLevel=1``, :data:`ONE_CPU_JVM_FLAGS`): with C2 on that CPU battles were slower and part from
the unpinned ones more often.

A claim is an exclusive ``flock`` on ``<cache>/cpus/cpu<N>.lock``, held while the engine runs: another confront
process (a parallel test worker, a sweep) takes another CPU, and when every CPU is claimed the engine runs
unpinned. Among free CPUs the most idle one over a 20 ms sample of ``/proc/stat`` is taken.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import time
from collections.abc import Iterator
from pathlib import Path

from confront.engine.java_build import cache_root

ONE_CPU_JVM_FLAGS: tuple[str, ...] = ("-XX:TieredStopAtLevel=1",)
SAMPLE_S = 0.02  # how long the CPUs' idle time is sampled before choosing one


def _idle_ticks() -> dict[int, int]:
    """Idle + iowait ticks per CPU from /proc/stat ({} when it cannot be read)."""
    out: dict[int, int] = {}
    try:
        lines = Path("/proc/stat").read_text().splitlines()
    except OSError:
        return out
    for line in lines:
        name, *fields = line.split()
        if name.startswith("cpu") and name[3:].isdigit() and len(fields) >= 5:
            out[int(name[3:])] = int(fields[3]) + int(fields[4])
    return out


def idlest_first(cpus: list[int], sample_s: float = SAMPLE_S) -> list[int]:
    """``cpus`` ordered by idle time over ``sample_s`` seconds, most idle first (ties: as given)."""
    before = _idle_ticks()
    time.sleep(sample_s)
    after = _idle_ticks()
    return sorted(cpus, key=lambda c: -(after.get(c, 0) - before.get(c, 0)))


@contextlib.contextmanager
def claimed_cpu(enabled: bool = True, folder: Path | None = None) -> Iterator[int | None]:
    """Claim one CPU of this process's allowed set for as long as the block runs; None: run unpinned (not
    enabled, fewer than two CPUs, no way to set affinity, no writable lock folder, or every CPU claimed by other
    engine runs)."""
    if not enabled or not hasattr(os, "sched_setaffinity"):
        yield None
        return
    cpus = sorted(os.sched_getaffinity(0))
    if len(cpus) < 2:
        yield None
        return
    folder = folder if folder is not None else cache_root() / "cpus"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:  # no writable cache: no claims, so no pinning either
        yield None
        return
    for cpu in idlest_first(cpus):
        try:
            lock = open(folder / f"cpu{cpu}.lock", "a")  # held open for the claim
        except OSError:
            continue
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            continue
        try:
            yield cpu
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
            lock.close()
        return
    yield None
