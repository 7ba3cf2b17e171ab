"""Running one battle in the real engine, headless, through the project's control-API runner."""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import tempfile
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from confront.engine.affinity import ONE_CPU_JVM_FLAGS, claimed_cpu
from confront.engine.battle import BattleSpec
from confront.engine.install import HEADLESS, JVM_FLAGS, EngineInstall, find_engine, require_display
from confront.engine.java_build import compile_java
from confront.engine.workdir import prepare_workdir, write_robot_data
from confront.results import BattleResults, ScoreRow, parse_results_text

RUNNER_CLASS = "confront.ConfrontRunner"


VISIBLE_TIMEOUT_S = 86400.0  # a visible battle plays at display speed while somebody watches


@dataclass(frozen=True)
class EngineOptions:
    """How the engine process runs: seed, robot time per turn, sandbox, memory, time limit."""

    seed: int | None = 0
    cpu_constant_ms: float = 10.0
    nosecurity: bool = False
    max_heap_mb: int = 512
    timeout_s: float = 900.0
    extra_jvm_args: tuple[str, ...] = ()
    # extra environment variables of the engine process (e.g. the bridge token: unlike the command line, a
    # process's environment is readable only by its user); kept out of repr
    env: tuple[tuple[str, str], ...] = field(default=(), repr=False)
    round_start_fix: bool = True  # RoundStartAgent: no lost wake-up wait at round start (docs/engine.md)
    # run the engine process on one claimed CPU with the C1 compiler only (confront.engine.affinity): 1.2-2.5x
    # faster on the project's machine, but the engine's thread races may then go the other way (docs/engine.md,
    # "One CPU per engine process"), so it is for training in the engine, not for comparisons with the simulator
    one_cpu: bool = False
    # show Robocode's battle window while the battle runs (needs a display: DISPLAY set, e.g. under xvfb-run);
    # the window plays at Robocode's display speed (its TPS slider), so the time limit is then at least a day
    visible: bool = False

    def __post_init__(self) -> None:
        if self.seed is not None and not -(2**63) <= self.seed < 2**63:
            raise ValueError(f"seed must fit in a Java long, got {self.seed}")
        if not self.cpu_constant_ms > 0:
            raise ValueError(f"cpu_constant_ms must be > 0, got {self.cpu_constant_ms}")
        if not self.timeout_s > 0:
            raise ValueError(f"timeout_s must be > 0, got {self.timeout_s}")


@dataclass(frozen=True)
class EngineRun:
    """What one engine run produced: the results table and the run's diagnostics.

    ``results_text`` is the engine's own results file ("" when the battle was stopped at ``max_turns``).
    """

    results: BattleResults
    results_text: str
    turns: int
    robot_turns: int
    elapsed_s: float
    setup_s: float
    round_turns: tuple[int, ...]
    skipped_turns: dict[str, int]
    errors: tuple[str, ...] = ()
    trace: Path | None = None
    stopped_at_turn: int = -1
    summary: dict[str, Any] = field(default_factory=dict, repr=False)
    cpu: int | None = None  # the one CPU the engine process ran on (EngineOptions.one_cpu), None: unpinned


def java_command(install: EngineInstall, classes: Path, workdir: Path, opts: EngineOptions,
                 one_cpu: bool = False) -> list[str]:
    """The JVM command line for the runner (flags from robocode-facts.md section 0; ``one_cpu``: the process
    will run on one CPU, so it compiles with C1 only)."""
    flags = ([f for f in JVM_FLAGS if f != HEADLESS] + ["-Dconfront.visible=true"]) if opts.visible else list(JVM_FLAGS)
    cmd = [install.java, f"-Xmx{opts.max_heap_mb}M", f"-DWORKINGDIRECTORY={workdir}", *flags]
    if one_cpu:
        cmd += list(ONE_CPU_JVM_FLAGS)
    if opts.seed is not None:
        cmd.append(f"-DRANDOMSEED={opts.seed}")  # repeatable random order and start positions
    if opts.nosecurity:
        cmd.append("-DNOSECURITY=true")  # robots may open loopback sockets (bridge)
    cmd += list(opts.extra_jvm_args)
    if opts.round_start_fix:
        cmd.append(f"-javaagent:{agent_jar(classes)}")
    cmd += ["-cp", f"{install.classpath}{os.pathsep}{classes}", RUNNER_CLASS]
    return cmd


def agent_jar(classes: Path) -> Path:
    """The jar of ``RoundStartAgent`` (made once next to the compiled classes)."""
    jar = classes / "roundstart-agent.jar"
    if not jar.is_file():
        tmp = classes / f"roundstart-agent.{os.getpid()}.tmp"
        with zipfile.ZipFile(tmp, "w") as z:
            z.writestr("META-INF/MANIFEST.MF", "Manifest-Version: 1.0\nPremain-Class: confront.RoundStartAgent\n")
            for f in sorted((classes / "confront").glob("RoundStartAgent*.class")):
                z.write(f, f"confront/{f.name}")
        tmp.replace(jar)
    return jar


def _die_with_parent() -> None:  # pragma: no cover - runs in the child between fork and exec
    """Ask Linux to kill the child when the Python process dies (prctl PR_SET_PDEATHSIG)."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)
    except (OSError, AttributeError):
        pass


def run_process(cmd: Sequence[str], timeout_s: float, cwd: Path, log: Path,
                env: Mapping[str, str] | None = None, cpu: int | None = None) -> int:
    """Run ``cmd`` in its own process group (``env``: variables added to this process's environment; ``cpu``:
    the only CPU it may run on); kill the whole group on timeout, error or Ctrl-C."""
    full_env = {**os.environ, **env} if env else None

    def child() -> None:  # pragma: no cover - runs in the child between fork and exec
        _die_with_parent()
        if cpu is not None:
            os.sched_setaffinity(0, {cpu})

    with open(log, "wb") as out:
        proc = subprocess.Popen(list(cmd), cwd=cwd, env=full_env, stdout=out, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, start_new_session=True,
                                preexec_fn=child if sys.platform == "linux" else None)
        try:
            return wait_exit(proc, timeout_s)
        except subprocess.TimeoutExpired:
            raise TimeoutError(f"engine run exceeded {timeout_s} s; see {log}") from None
        finally:
            if proc.poll() is None:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                proc.wait()


def wait_exit(proc: subprocess.Popen, timeout_s: float) -> int:
    """``proc.wait(timeout_s)`` that returns as soon as the process exits: on Linux through a pidfd (Popen's own wait
    with a time-out polls, sleeping up to 50 ms between looks, which an engine run of a second or two pays in full
    about half the time)."""
    if not hasattr(os, "pidfd_open"):
        return proc.wait(timeout=timeout_s)
    try:
        fd = os.pidfd_open(proc.pid)
    except OSError:  # an old kernel, or the process is gone already
        return proc.wait(timeout=timeout_s)
    try:
        poller = select.poll()  # not select(): a process with many open files may get a descriptor above 1023
        poller.register(fd, select.POLLIN)
        ready = poller.poll(timeout_s * 1000.0)
    finally:
        os.close(fd)
    if not ready:
        raise subprocess.TimeoutExpired(proc.args, timeout_s)
    return proc.wait()


def _row(d: dict[str, Any], name: str, team: str) -> ScoreRow:
    s = d["score"]
    return ScoreRow(
        name=name, total=s["total"], survival=s["survival"], surv_bonus=s["surv_bonus"],
        bullet_dmg=s["bullet_dmg"], bullet_bonus=s["bullet_bonus"], ram_dmg=s["ram_dmg"],
        ram_bonus=s["ram_bonus"], firsts=s["firsts"], seconds=s["seconds"], thirds=s["thirds"], team=team,
    )


def results_from_summary(summary: dict[str, Any], rounds: int) -> BattleResults:
    """Exact score parts (doubles from the engine's score snapshots) as :class:`BattleResults`."""
    conts = [_row(c, c["name"], c["name"]) for c in summary["contestants"]]
    by_index = {i: c.name for i, c in enumerate(conts)}
    robots = [_row(r, r["name"], by_index.get(r["contestant"], r["team"])) for r in summary["robots"]]
    conts.sort(key=lambda r: -r.total)
    return BattleResults(
        rounds=rounds, contestants=tuple(conts), robots=tuple(robots),
        skipped_turns=sum(summary["skipped_turns"].values()),
    )


def run_battle(
    spec: BattleSpec,
    options: EngineOptions | None = None,
    workdir: str | os.PathLike[str] | None = None,
    trace: str | os.PathLike[str] | None = None,
    robot_data: Mapping[str, Mapping[str, str]] | None = None,
    install: EngineInstall | None = None,
    extra_robots: Sequence[str | os.PathLike[str]] = (),
) -> EngineRun:
    """Run ``spec`` headless in the real engine and return its results.

    ``workdir``: the engine's working directory (created if needed; default a temporary one, removed
    afterwards). ``trace``: write a JSONL trace of every turn there. ``robot_data``: files for the project's
    robots' data folders, e.g. ``{"ScriptBot": {"script.txt": ...}}``. ``extra_robots``: robot jars or
    robots folders to add (e.g. an exported robot).
    """
    opts = options or EngineOptions()
    if opts.visible:
        require_display("a visible battle")
    install = install or find_engine()
    classes = compile_java(install)
    with tempfile.TemporaryDirectory(prefix="confront-robocode-") as tmp:
        wd = Path(workdir) if workdir is not None else Path(tmp) / "wd"
        prepare_workdir(wd, install, classes, opts.cpu_constant_ms, spec.teams, [Path(p) for p in extra_robots])
        for robot, files in (robot_data or {}).items():
            write_robot_data(wd, robot, files)
        run_dir = Path(tempfile.mkdtemp(prefix="run-", dir=tmp))
        battle_file = run_dir / "battle.battle"
        battle_file.write_text(spec.battle_file())
        results_file, summary_file = run_dir / "results.txt", run_dir / "summary.json"
        args = [str(wd), str(battle_file), str(results_file), str(summary_file)]
        if trace is not None:
            args.append(str(Path(trace).resolve()))
        log = run_dir / "engine.log"
        with claimed_cpu(opts.one_cpu) as cpu:
            cmd = java_command(install, classes, wd, opts, one_cpu=cpu is not None) + args
            timeout = max(opts.timeout_s, VISIBLE_TIMEOUT_S) if opts.visible else opts.timeout_s
            code = run_process(cmd, timeout, run_dir, log, env=dict(opts.env), cpu=cpu)
        if not summary_file.is_file() and opts.visible:
            raise RuntimeError(f"the engine exited (code {code}) before the battle ended: was its window closed?")
        if not summary_file.is_file():
            tail = log.read_text(errors="replace")[-2000:]
            raise RuntimeError(f"engine run failed (exit {code}) without a summary:\n{tail}")
        summary = json.loads(summary_file.read_text())
        if code != 0 or not summary["completed"]:
            raise RuntimeError(f"engine run failed (exit {code}): {'; '.join(summary['errors']) or 'no error'}")
        text = results_file.read_text()
    rounds = parse_results_text(text).rounds if summary["stopped_at_turn"] < 0 else 1
    exact = results_from_summary(summary, rounds)
    return EngineRun(
        results=exact, results_text=text, turns=summary["turns"], robot_turns=summary["robot_turns"],
        elapsed_s=summary["elapsed_s"], setup_s=summary["setup_s"],
        round_turns=tuple(summary["round_turns"]), skipped_turns=dict(summary["skipped_turns"]),
        errors=tuple(summary["errors"]), trace=Path(trace) if trace is not None else None,
        stopped_at_turn=summary["stopped_at_turn"], summary=summary, cpu=cpu,
    )


def run_scenario(
    scenario: str,
    ours: str | Sequence[str],
    opponents: str | Sequence[str],
    rounds: int = 10,
    seed: int | None = 0,
    cpu_constant_ms: float = 10.0,
    out_dir: str | os.PathLike[str] | None = None,
    visible: bool = False,
) -> EngineRun:
    """What ``confront battle --engine robocode`` calls: run a named scenario, optionally save the tables.

    With ``out_dir``: results.txt (the engine's own file), results.csv / results.md (exact score parts,
    contestants), robots.csv (per robot) and summary.json (turns, skipped turns, timings). ``visible``: in
    Robocode's battle window (:attr:`EngineOptions.visible`).
    """
    from confront.engine.battle import scenario_battle

    spec = scenario_battle(scenario, ours, opponents, rounds=rounds)
    run = run_battle(spec, EngineOptions(seed=seed, cpu_constant_ms=cpu_constant_ms, visible=visible))
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        (out / "results.txt").write_text(run.results_text)
        (out / "results.csv").write_text(run.results.to_csv())
        (out / "robots.csv").write_text(run.results.to_csv(level="robots"))
        (out / "results.md").write_text(run.results.to_markdown())
        keep = ("turns", "robot_turns", "elapsed_s", "setup_s", "round_turns", "skipped_turns", "errors")
        (out / "summary.json").write_text(json.dumps({k: run.summary[k] for k in keep}, indent=1) + "\n")
    return run
