"""Transport by measurement: the TCP bridge vs the engine driven in-process through JPype, same 1v1 battle.

In one run, ``ours`` vs Walls for N rounds (seed and CPU constant fixed) four ways:
  - engine process (the project's runner), a sample robot (Tracker) in our place      -> the engine's own speed
  - engine process, BridgeBot asking ``nearest_enemy_policy`` over the loopback TCP bridge
  - engine inside this Python process (JPype, control API), Tracker in our place
  - engine inside this Python process, a robot calling the same Python policy through a JPype proxy
plus the bare cost of one Java -> Python proxy call with the engine idle. The benchmark's robot and helpers are
compiled from the Java text below (they are not part of the package). Needs ``pip install jpype1``.

Usage: python benchmarks/transport_jpype.py [--rounds 10] [--cpu-ms 30] [--seed 1] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

from confront.engine.battle import BattleSpec
from confront.engine.bridge import Observation, Scan, nearest_enemy_policy
from confront.engine.bridged import BRIDGE_BOT, BRIDGE_CPU_CONSTANT_MS, run_bridged_battle
from confront.engine.install import JVM_FLAGS, EngineInstall, find_engine
from confront.engine.java_build import compile_java
from confront.engine.runner import EngineOptions, EngineRun, run_battle
from confront.engine.workdir import prepare_workdir

OPPONENT = "sample.Walls"
STAND_IN = "sample.Tracker"

# system class path (not a robot): the Python proxy's interface, a static slot for it, a turn counter
HUB_SOURCES = {
    "confrontjp/Decider.java": "package confrontjp;\npublic interface Decider { String decide(String line); }\n",
    "confrontjp/Hub.java": """package confrontjp;
import java.util.concurrent.atomic.AtomicLong;
public final class Hub {
    public static volatile Decider decider;
    public static final AtomicLong calls = new AtomicLong();
    public static final AtomicLong nanos = new AtomicLong();
    public static final AtomicLong slow = new AtomicLong();
    private Hub() { }
    public static String ask(String line) {
        long t0 = System.nanoTime();
        String answer = decider.decide(line);
        long dt = System.nanoTime() - t0;
        calls.incrementAndGet();
        nanos.addAndGet(dt);
        if (dt > 1000000L) { slow.incrementAndGet(); }
        return answer;
    }
    /** n proxy calls in a row from a Java thread; returns the total nanoseconds. */
    public static long spin(int n, String line) {
        long t0 = System.nanoTime();
        for (int i = 0; i < n; i++) { decider.decide(line); }
        return System.nanoTime() - t0;
    }
}
""",
    "confrontjp/Counter.java": """package confrontjp;
import robocode.control.events.*;
import robocode.control.snapshot.IRobotSnapshot;
public final class Counter extends BattleAdaptor {
    public volatile long turns, skipped, setupNanos;
    public volatile boolean completed;
    private boolean first;
    private long last = System.nanoTime();
    public final long start = System.nanoTime();
    public volatile long end;
    @Override public void onRoundStarted(RoundStartedEvent e) { first = true; }
    @Override public void onTurnEnded(TurnEndedEvent e) {
        long now = System.nanoTime();
        if (first) { setupNanos += now - last; first = false; }
        last = now;
        turns++;
        for (IRobotSnapshot r : e.getTurnSnapshot().getRobots()) {
            String out = r.getOutputStreamSnapshot();
            if (out != null && out.contains(" skipped turn ")) {
                for (String line : out.split("\\n")) { if (line.contains(" skipped turn ")) { skipped++; } }
            }
        }
    }
    @Override public void onBattleCompleted(BattleCompletedEvent e) { completed = true; end = System.nanoTime(); }
}
""",
}

# the robot: every turn it hands its state and latest scan to Hub.ask (the Python policy) and acts on the answer
ROBOT_SOURCES = {
    "jpbench/JpBot.java": """package jpbench;
import robocode.*;
public class JpBot extends AdvancedRobot {
    private String scan = "-";
    public void run() {
        setAdjustGunForRobotTurn(true);
        setAdjustRadarForGunTurn(true);
        try { Thread.sleep(3); } catch (InterruptedException e) { Thread.currentThread().interrupt(); }
        while (true) {
            String line = getRoundNum() + " " + getTime() + " " + getX() + " " + getY() + " " + getHeadingRadians()
                + " " + getGunHeadingRadians() + " " + getRadarHeadingRadians() + " " + getVelocity() + " "
                + getEnergy() + " " + getGunHeat() + " " + getOthers() + " " + getDistanceRemaining() + " "
                + getBattleFieldWidth() + " " + getBattleFieldHeight() + " " + scan;
            String[] a = confrontjp.Hub.ask(line).split(" ");
            double ahead = Double.parseDouble(a[0]), turn = Double.parseDouble(a[1]);
            double gun = Double.parseDouble(a[2]), radar = Double.parseDouble(a[3]);
            double fire = Double.parseDouble(a[4]);
            if (!Double.isNaN(ahead)) { setAhead(ahead); }
            if (!Double.isNaN(turn)) { setTurnRightRadians(turn); }
            if (!Double.isNaN(gun)) { setTurnGunRightRadians(gun); }
            if (!Double.isNaN(radar)) { setTurnRadarRightRadians(radar); }
            if (fire > 0) { setFire(fire); }
            execute();
        }
    }
    public void onScannedRobot(ScannedRobotEvent e) {
        double abs = getHeadingRadians() + e.getBearingRadians();
        scan = e.getName().replace(' ', '_') + " " + e.getTime() + " " + e.getBearingRadians() + " "
            + e.getDistance() + " " + e.getHeadingRadians() + " " + e.getVelocity() + " " + e.getEnergy() + " "
            + (getX() + e.getDistance() * Math.sin(abs)) + " " + (getY() + e.getDistance() * Math.cos(abs));
    }
}
""",
}


def parse_line(line: str) -> Observation:
    """The JpBot's state line as the bridge's Observation."""
    f = line.split(" ")
    nums = [float(v) for v in f[:14]]
    scans: tuple[Scan, ...] = ()
    if f[14] != "-":
        s = [float(v) for v in f[15:23]]
        scans = (Scan(f[14], int(s[0]), False, *s[1:]),)
    return Observation("jpbench.JpBot", (), int(nums[0]), int(nums[1]), *nums[2:9], int(nums[10]), nums[11],
                       nums[12], nums[13], scans)


def format_action(action: Any) -> str:
    """Five numbers for Java's Double.parseDouble ('NaN', not 'nan')."""
    return " ".join("NaN" if math.isnan(v) else repr(float(v)) for v in action)


def _compile(install: EngineInstall, sources: dict[str, str], out: Path, extra_cp: str = "") -> Path:
    src = out / "src"
    for name, text in sources.items():
        (src / name).parent.mkdir(parents=True, exist_ok=True)
        (src / name).write_text(text)
    classes = out / "classes"
    classes.mkdir(parents=True, exist_ok=True)
    cp = install.classpath + (os.pathsep + extra_cp if extra_cp else "")
    proc = subprocess.run([install.javac, "-nowarn", "-cp", cp, "-d", str(classes),
                           *[str(src / n) for n in sources]], capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"javac failed:\n{proc.stderr}")
    return classes


def _process_record(mode: str, run: EngineRun, rtt: float | None = None, slow: int | None = None,
                    decisions: int = 0) -> dict[str, Any]:
    busy = max(run.elapsed_s - run.setup_s, 1e-9)
    return {"mode": mode, "turns": run.turns, "turns_per_s": run.turns / run.elapsed_s,
            "turns_per_s_excl_setup": run.turns / busy, "setup_s": run.setup_s, "elapsed_s": run.elapsed_s,
            "skipped_turns": sum(run.skipped_turns.values()), "decisions": decisions, "rtt_mean_us": rtt,
            "rtt_over_1ms": slow}


def _in_process(install: EngineInstall, tmp: Path, rounds: int, cpu_ms: float, seed: int,
                proxy_calls: int) -> list[dict[str, Any]]:
    """Start a JVM inside this process, run the two in-process battles, and time bare proxy calls."""
    import jpype
    from jpype import JImplements, JOverride

    hub = _compile(install, HUB_SOURCES, tmp / "hub")
    robots = _compile(install, ROBOT_SOURCES, tmp / "jprobots", str(hub))
    (robots / "jpbench" / "JpBot.properties").write_text(
        "robot.classname=jpbench.JpBot\nrobot.name=JpBot\nrobocode.version=1.9.3.9\n")
    wd = prepare_workdir(tmp / "wd-jp", install, compile_java(install), cpu_ms, (), [robots])
    os.chdir(tmp)  # the engine may write next to the process's working directory
    jpype.startJVM("-Xmx512M", f"-DWORKINGDIRECTORY={wd}", f"-DRANDOMSEED={seed}", "-DNOSECURITY=true",
                   *JVM_FLAGS, classpath=[install.classpath, str(hub)], convertStrings=True)

    @JImplements("confrontjp.Decider")
    class PythonDecider:
        @JOverride
        def decide(self, line: str) -> str:
            return format_action(nearest_enemy_policy(parse_line(line)))

    hub_cls = jpype.JClass("confrontjp.Hub")
    hub_cls.decider = PythonDecider()
    control = jpype.JPackage("robocode").control
    control.RobocodeEngine.setLogMessagesEnabled(False)
    engine = control.RobocodeEngine(jpype.JClass("java.io.File")(str(wd)))
    records = []
    try:
        for mode, ours in (("in-process (JPype), sample robots", STAND_IN),
                           ("in-process (JPype), Python policy via proxy", "jpbench.JpBot*")):
            counter = jpype.JClass("confrontjp.Counter")()
            engine.addBattleListener(counter)
            hub_cls.calls.set(0)
            hub_cls.nanos.set(0)
            hub_cls.slow.set(0)
            selected = engine.getLocalRepository(f"{ours},{OPPONENT}")
            if len(selected) != 2:
                raise RuntimeError(f"in-process engine found {len(selected)} of the robots {ours}, {OPPONENT}")
            spec = control.BattleSpecification(rounds, 450, 0.1, False, control.BattlefieldSpecification(800, 600),
                                               selected)
            engine.runBattle(spec, True)
            engine.removeBattleListener(counter)
            if not counter.completed:
                raise RuntimeError(f"in-process battle '{mode}' did not complete")
            elapsed = (counter.end - counter.start) / 1e9
            setup = counter.setupNanos / 1e9
            calls = int(hub_cls.calls.get())
            records.append({
                "mode": mode, "turns": int(counter.turns), "turns_per_s": counter.turns / elapsed,
                "turns_per_s_excl_setup": counter.turns / max(elapsed - setup, 1e-9), "setup_s": setup,
                "elapsed_s": elapsed, "skipped_turns": int(counter.skipped), "decisions": calls,
                "rtt_mean_us": hub_cls.nanos.get() / calls / 1e3 if calls else None,
                "rtt_over_1ms": int(hub_cls.slow.get()) if calls else None,
            })
        line = "0 100 400.0 300.0 0.5 0.4 0.3 8.0 100.0 0.0 1 0.0 800.0 600.0 sample.Walls 99 0.2 250.0 1.5 8.0 " \
               "100.0 450.0 520.0"
        hub_cls.spin(200, line)  # warm-up
        ns = hub_cls.spin(proxy_calls, line)
        records.append({"mode": "bare proxy call, engine idle", "decisions": proxy_calls,
                        "rtt_mean_us": ns / proxy_calls / 1e3})
        t0 = time.perf_counter()
        for _ in range(proxy_calls):
            format_action(nearest_enemy_policy(parse_line(line)))
        records.append({"mode": "same policy called from Python (no transport)", "decisions": proxy_calls,
                        "rtt_mean_us": (time.perf_counter() - t0) / proxy_calls * 1e6})
    finally:
        engine.close()
    return records


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--cpu-ms", type=float, default=BRIDGE_CPU_CONSTANT_MS,
                    help="engine CPU constant (ms per robot turn)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--proxy-calls", type=int, default=20000)
    ap.add_argument("--json", action="store_true", help="print the records as one JSON list at the end")
    args = ap.parse_args()
    install = find_engine()
    opts = EngineOptions(seed=args.seed, cpu_constant_ms=args.cpu_ms)
    records: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="confront-transport-") as tmp:
        ref = run_battle(BattleSpec((STAND_IN, OPPONENT), rounds=args.rounds), opts)
        records.append(_process_record("engine process, sample robots", ref))
        bridged = run_bridged_battle(BattleSpec((BRIDGE_BOT, OPPONENT), rounds=args.rounds), nearest_enemy_policy,
                                     opts)
        records.append(_process_record("engine process, TCP bridge", bridged.run, bridged.rtt_mean_us,
                                       bridged.rtt_over_1ms, bridged.decisions))
        records += _in_process(install, Path(tmp), args.rounds, args.cpu_ms, args.seed, args.proxy_calls)
    print(f"1v1 vs Walls: rounds={args.rounds} cpu_constant_ms={args.cpu_ms} seed={args.seed}")
    print("| mode | turns | turns/s | turns/s excl. set-up | set-up s | skipped | decisions | mean round trip µs "
          "| round trips > 1 ms |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")

    def cell(r: dict[str, Any], key: str, fmt: str) -> str:
        v = r.get(key)
        return "–" if v is None else format(v, fmt)

    for r in records:
        print(f"| {r['mode']} | {cell(r, 'turns', 'd')} | {cell(r, 'turns_per_s', '.0f')} | "
              f"{cell(r, 'turns_per_s_excl_setup', '.0f')} | {cell(r, 'setup_s', '.2f')} | "
              f"{cell(r, 'skipped_turns', 'd')} | {cell(r, 'decisions', 'd')} | {cell(r, 'rtt_mean_us', '.1f')} | "
              f"{cell(r, 'rtt_over_1ms', 'd')} |")
    if args.json:
        print(json.dumps(records))


if __name__ == "__main__":
    main()
