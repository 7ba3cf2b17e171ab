"""Battles in the real engine where the project's BridgeBot tanks take their decisions from a Python policy."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace

from confront.arena.control import ControlConfig
from confront.engine.battle import BattleSpec
from confront.engine.bridge import TOKEN_ENV, BridgeServer, BridgeSettings, Policy, RobotActing
from confront.engine.runner import EngineOptions, EngineRun, run_battle

BRIDGE_BOT = "confront.BridgeBot*"
# robot time per turn for bridged battles. 100 bridged rounds on our loaded 2-core machine skipped 10-35 turns
# at 30 ms and 2 at 100 ms (docs/engine.md); a larger value costs almost nothing: the round-start wait is
# capped at 10 s per occurrence from 34 ms on (robocode-facts.md section 10)
BRIDGE_CPU_CONSTANT_MS = 100.0


def bridge_timeout_ms(cpu_constant_ms: float) -> int:
    """How long a robot waits for Python before falling back: 20 engine turns of robot time.

    The engine stops a robot after 30 skipped turns in a row [RobotPeer], so a stall must be noticed sooner.
    """
    return max(50, int(20 * cpu_constant_ms))


def bridge_options(options: EngineOptions, port: int, token: str, timeout_ms: int) -> EngineOptions:
    """Engine options for a bridged battle: sandbox off (sockets), where and how long to wait as system
    properties (the decision interval and the controller come from the server's hello reply), and the token in
    the engine's environment (``CONFRONT_BRIDGE_TOKEN``): the command line is visible to every local user, a
    process's environment only to its own."""
    if timeout_ms <= 0:
        raise ValueError(f"timeout_ms must be > 0, got {timeout_ms}")
    props = (f"-Dconfront.bridge.port={port}", f"-Dconfront.bridge.timeoutMs={timeout_ms}")
    return replace(options, nosecurity=True, extra_jvm_args=options.extra_jvm_args + props,
                   env=(*options.env, (TOKEN_ENV, token)))


@dataclass(frozen=True)
class BridgedRun:
    """An engine run plus what the bridge saw: decisions served, errors, robots that fell back, and times.

    Per decision, means in microseconds: ``rtt_mean_us`` the time a robot was held up by the round trip
    (sending, and waiting for the answer; with ``lead`` = 0 the whole round trip) as the robots timed it,
    ``policy_us`` inside the policy, ``handling_us`` the server's own work (parse, format, send); per robot
    turn ``work_us_per_turn`` the robots' own time outside execute() (deciding, round trips included, and the
    controller); ``behind``: decisions that robots acting themselves took from a copy of the policy that still
    lacked an update of their earlier observations that could change the move (``RobotActing.wait``);
    ``ahead``: decisions they took without waiting for the acknowledgement of observations whose updates could
    not change the move (``wait="row"``). Statistics of a round that a robot played in fallback are
    lost with its connection.
    """

    run: EngineRun
    decisions: int
    connections: int
    server_errors: tuple[str, ...]
    failures: tuple[str, ...]
    rejected: int = 0  # connections dropped before a valid hello (wrong token, no hello, too long, ...)
    rtt_mean_us: float = float("nan")
    rtt_over_1ms: int = 0
    work_us_per_turn: float = float("nan")
    policy_us: float = float("nan")
    handling_us: float = float("nan")
    behind: int = 0  # acting robots: decisions taken before an observation that counts was acknowledged
    ahead: int = 0  # acting robots: decisions taken ahead of acknowledgements that could not change them

    @property
    def ok(self) -> bool:
        """True when no robot fell back to its built-in behaviour."""
        return not self.failures and not self.server_errors


def bridge_failures(run: EngineRun) -> tuple[str, ...]:
    """The robots' 'bridge-failed' reports collected by the runner."""
    return tuple(r for r in run.summary.get("robot_reports", []) if "bridge-failed" in r)


def run_bridged_battle(
    spec: BattleSpec,
    policy: Policy,
    options: EngineOptions | None = None,
    timeout_ms: int | None = None,
    workdir: str | os.PathLike[str] | None = None,
    every: int = 1,
    extra_robots: Sequence[str | os.PathLike[str]] = (),
    controller: ControlConfig | None = None,
    history: bool = False,
    lead: int = 0,
    acting: RobotActing | None = None,
) -> BridgedRun:
    """Run ``spec`` (whose contestants include BridgeBot tanks) with ``policy`` deciding for every BridgeBot.

    The robots connect before their first action and ask ``policy`` in turns 1, 1 + every, ... (the paper's
    SMDP step T); the commands keep running in between. ``controller``: the robots run this fixed gun/radar
    controller themselves every turn (the answers' gun, radar and fire are then ignored), so a policy that
    only picks moves costs one round trip per ``every`` turns. ``history``: the robots send every turn's
    energies with the next observation and at the round's end; ``lead``: they ask that many turns ahead (see
    ``BridgeSettings``). ``acting``: the robots pick their moves from their own copy of the policy and send
    each observation with the move taken, without waiting for an answer (:class:`RobotActing`; needs
    ``controller``). ``extra_robots``: robot jars or folders to add (e.g. exported PolicyBot opponents).
    """
    opts = options or EngineOptions(cpu_constant_ms=BRIDGE_CPU_CONSTANT_MS)
    tmo = timeout_ms if timeout_ms is not None else bridge_timeout_ms(opts.cpu_constant_ms)
    with BridgeServer(policy, settings=BridgeSettings(every, controller, history, lead, acting)) as server:
        run = run_battle(spec, bridge_options(opts, server.port, server.token, tmo), workdir=workdir,
                         extra_robots=extra_robots)
    st = server.stats
    nan = float("nan")
    return BridgedRun(run=run, decisions=st.decisions, connections=st.connections,
                      server_errors=tuple(st.errors), failures=bridge_failures(run),
                      rejected=sum(st.rejected.values()),
                      rtt_mean_us=st.rtt_total_us / st.robot_decisions if st.robot_decisions else nan,
                      rtt_over_1ms=st.rtt_over_1ms,
                      work_us_per_turn=st.work_us / st.robot_turns if st.robot_turns else nan,
                      policy_us=1e6 * st.policy_s / st.decisions if st.decisions else nan,
                      handling_us=1e6 * st.handling_s / st.decisions if st.decisions else nan,
                      behind=st.behind, ahead=st.ahead)
