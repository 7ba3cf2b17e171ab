"""Battles in the real engine where the project's BridgeBot tanks take their decisions from a Python policy."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace

from confront.engine.battle import BattleSpec
from confront.engine.bridge import BridgeServer, Policy
from confront.engine.runner import EngineOptions, EngineRun, run_battle

BRIDGE_BOT = "confront.BridgeBot*"
# robot time per turn for bridged battles: no skipped turns in 100 rounds at 30 ms on our 2-core machine
# (11 at 10 ms), see docs/engine.md
BRIDGE_CPU_CONSTANT_MS = 30.0


def bridge_timeout_ms(cpu_constant_ms: float) -> int:
    """How long a robot waits for Python before falling back: 20 engine turns of robot time.

    The engine stops a robot after 30 skipped turns in a row [RobotPeer], so a stall must be noticed sooner.
    """
    return max(50, int(20 * cpu_constant_ms))


def bridge_options(
    options: EngineOptions, port: int, token: str, timeout_ms: int, every: int = 1
) -> EngineOptions:
    """Engine options for a bridged battle: sandbox off (sockets), bridge settings as system properties.

    ``every``: the robots ask Python in every ``every``-th turn (the paper's SMDP step T); in the turns
    between, their last commands keep running (remaining distance and turns; a shot is fired only once).
    """
    if timeout_ms <= 0:
        raise ValueError(f"timeout_ms must be > 0, got {timeout_ms}")
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    props = (f"-Dconfront.bridge.port={port}", f"-Dconfront.bridge.token={token}",
             f"-Dconfront.bridge.timeoutMs={timeout_ms}", f"-Dconfront.bridge.every={every}")
    return replace(options, nosecurity=True, extra_jvm_args=options.extra_jvm_args + props)


@dataclass(frozen=True)
class BridgedRun:
    """An engine run plus what the bridge saw: decisions served, errors, robots that fell back."""

    run: EngineRun
    decisions: int
    connections: int
    server_errors: tuple[str, ...]
    failures: tuple[str, ...]
    rtt_mean_us: float = float("nan")
    rtt_over_1ms: int = 0

    @property
    def ok(self) -> bool:
        """True when no robot fell back to its built-in behaviour."""
        return not self.failures and not self.server_errors


def bridge_failures(run: EngineRun) -> tuple[str, ...]:
    """The robots' 'bridge-failed' reports collected by the runner."""
    return tuple(r for r in run.summary.get("robot_reports", []) if "bridge-failed" in r)


def rtt_stats(run: EngineRun) -> tuple[float, int]:
    """Mean round trip (robot sends its observation .. reads the answer) in microseconds, and how many
    round trips took over 1 ms, from the robots' per-round 'bridge-stats' reports."""
    n = total = slow = 0
    for rep in run.summary.get("robot_reports", []):
        if "bridge-stats" in rep:
            fields = dict(kv.split("=") for kv in rep.split() if "=" in kv)
            n += int(fields["decisions"])
            total += int(fields["rtt_total_us"])
            slow += int(fields["rtt_over_1ms"])
    return (total / n if n else float("nan")), slow


def run_bridged_battle(
    spec: BattleSpec,
    policy: Policy,
    options: EngineOptions | None = None,
    timeout_ms: int | None = None,
    workdir: str | os.PathLike[str] | None = None,
    every: int = 1,
    extra_robots: Sequence[str | os.PathLike[str]] = (),
) -> BridgedRun:
    """Run ``spec`` (whose contestants include BridgeBot tanks) with ``policy`` deciding for every BridgeBot.

    The robots skip turn 1 (they act once before connecting) and then ask ``policy`` every ``every`` turns.
    ``extra_robots``: robot jars or folders to add (e.g. exported PolicyBot opponents).
    """
    opts = options or EngineOptions(cpu_constant_ms=BRIDGE_CPU_CONSTANT_MS)
    tmo = timeout_ms if timeout_ms is not None else bridge_timeout_ms(opts.cpu_constant_ms)
    with BridgeServer(policy) as server:
        run = run_battle(spec, bridge_options(opts, server.port, server.token, tmo, every), workdir=workdir,
                         extra_robots=extra_robots)
    mean_rtt, slow = rtt_stats(run)
    return BridgedRun(run=run, decisions=server.stats.decisions, connections=server.stats.connections,
                      server_errors=tuple(server.stats.errors), failures=bridge_failures(run),
                      rtt_mean_us=mean_rtt, rtt_over_1ms=slow)
