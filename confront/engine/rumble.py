"""A rumble in the real engine: one robot (the candidate) against every robot in a folder of robot jars.

The folder is read as Robocode's ``robots/`` folder or a RoboRumble client keeps it: each jar's robots are found
from its ``.properties`` files (``robot.classname``, ``robot.version``), its teams from its ``.team`` files. Battles
follow the RoboRumble's settings (``/usr/share/games/robocode/roborumble/*.txt``; robocode-facts.md section 15):
1v1 35 rounds on 800x600, melee the candidate among up to 9 others on 1000x1000 (35 rounds), teams on 1200x1200
(10 rounds).

Each battle is a :class:`BattleJob`: its own JVM and working directory, a hard time limit after which the JVM is
killed, and a JSON result (:func:`play_job`) that keeps the engine's own words about a robot that cannot be loaded,
throws, hangs or overruns its time (:func:`robot_problems`). :func:`run_jobs` plays the jobs not yet done over
local processes or Ray tasks and stores each result atomically, so a rerun never plays a finished battle again.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import tempfile
import time
import zipfile
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from confront.engine.battle import BattleSpec, Contestant, Team

MODES: dict[str, tuple[int, int, int]] = {  # RoboRumble's rounds, width, height per mode
    "1v1": (35, 800, 600),
    "melee": (35, 1000, 1000),
    "teams": (10, 1200, 1200),
}
MELEE_OTHERS = 9  # the melee rumble's battles are 10 robots
TEAM_SIZE = 4  # a team of the candidate: the project's team size (its exported TankTeam / PolicyTeam)
# a robot's problem, most serious first: what stops a battle, then what a robot did in it
PROBLEMS = ("not loaded", "failed", "timed out", "throws", "hangs", "overran its time")


def default_timeout_s(rounds: int, robots: int) -> float:
    """Hard time limit of one battle's JVM: generous for healthy robots (a 35-round 1v1 plays in seconds), and
    enough for a robot that hangs every turn (the engine then waits the CPU constant each turn for it and several
    seconds at each round's end: about 7 s a round at 10 ms)."""
    return 120.0 + 12.0 * rounds * max(1, robots // 2)


@dataclass(frozen=True)
class Robot:
    """A robot (or a team of a team jar) by the name the engine selects it with: ``pkg.Bot 1.0`` for a jar's robot,
    ``sample.Tracker`` for one of the engine's own. ``members``: a team's robots (empty: a robot). ``problem``: why
    it cannot be played (a jar that is not a jar, a jar without robots), else empty."""

    name: str
    jar: str = ""  # file name of its jar in the folder, "" for the engine's own robots
    members: tuple[str, ...] = ()
    problem: str = ""

    @property
    def is_team(self) -> bool:
        return bool(self.members)


def _properties(text: str) -> dict[str, str]:
    """Java .properties lines (key=value or key: value, # and ! comments), without continuation lines."""
    out: dict[str, str] = {}
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line[0] in "#!":
            continue
        m = re.match(r"([^=:\s]+)\s*[=:]?\s*(.*)$", line)
        if m:
            out[m.group(1).replace("\\:", ":")] = m.group(2).strip()
    return out


def jar_robots(jar: Path) -> list[Robot]:
    """The robots and teams of one jar (a jar the engine cannot read gives one :class:`Robot` with its problem)."""
    try:
        with zipfile.ZipFile(jar) as z:
            entries = {n: z.read(n).decode("utf-8", "replace") for n in z.namelist()
                       if n.endswith((".properties", ".team")) and not n.startswith(("META-INF/", ".data/"))}
    except (zipfile.BadZipFile, OSError, ValueError) as err:
        return [Robot(jar.stem, jar.name, problem=f"not loaded: {jar.name} is not a readable jar ({err}); "
                                                  "the engine lists no robot from it")]
    robots: list[Robot] = []
    for path in sorted(entries):
        props = _properties(entries[path])
        if path.endswith(".team"):
            members = tuple(m.strip() for m in props.get("team.members", "").split(",") if m.strip())
            name = path[: -len(".team")].replace("/", ".")
            version = props.get("team.version", "")
            robots.append(Robot(f"{name} {version}" if version else name, jar.name, members or ("?",),
                                "" if members else "not loaded: its .team file lists no members"))
        elif "robot.classname" in props:
            version = props.get("robot.version", "")
            cls = props["robot.classname"]
            robots.append(Robot(f"{cls} {version}" if version else cls, jar.name))
    if not robots:
        return [Robot(jar.stem, jar.name, problem=f"not loaded: {jar.name} holds no robot (no .properties file "
                                                  "with robot.classname)")]
    return robots


def folder_robots(folder: str | os.PathLike[str]) -> list[Robot]:
    """Every robot and team of the jars directly in ``folder``, in file-name order."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"no such folder: {folder}")
    return [r for jar in sorted(folder.glob("*.jar")) for r in jar_robots(jar)]


# -- one battle ---------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BattleJob:
    """One battle of the rumble: the candidate (a robot; a team of ``team_size`` of it in teams mode) against
    ``opponents`` (one robot or team; up to 9 robots in melee), at one seed."""

    key: str
    mode: str
    candidate: Robot
    opponents: tuple[Robot, ...]
    seed: int
    rounds: int
    width: int
    height: int
    cpu_constant_ms: float
    team_size: int
    timeout_s: float
    one_cpu: bool = False  # the JVM on one claimed CPU, C1 only (confront.engine.affinity)

    def spec(self) -> BattleSpec:
        """The engine's battle: the candidate's side first."""
        conts: list[Contestant]
        if self.mode == "teams":
            conts = [Team("Ours", (self.candidate.name,) * self.team_size)]
            conts += [Team(f"Them{i}", o.members or (o.name,) * self.team_size)
                      for i, o in enumerate(self.opponents)]
        else:
            conts = [self.candidate.name, *(o.name for o in self.opponents)]
        return BattleSpec(tuple(conts), rounds=self.rounds, width=self.width, height=self.height, name=self.mode)

    def robots(self) -> int:
        return self.spec().robot_count


def job_key(mode: str, opponents: Sequence[Robot], seed: int) -> str:
    """A file-name-safe key: the opponent's name for 1v1 and teams, a hash of the group for melee."""
    if mode == "melee":
        digest = hashlib.sha1("\n".join(o.name for o in opponents).encode()).hexdigest()[:12]
        return f"melee-{digest}-s{seed}"
    safe = re.sub(r"[^\w.\-]+", "_", opponents[0].name)
    return f"{mode}-{safe}-s{seed}"


def robot_problems(summary: dict[str, Any], names: Iterable[str]) -> dict[str, str]:
    """What the engine said about each robot of ``names`` (selection names) in a battle's summary: its first
    line about a robot it cannot find, an exception the robot threw, a robot it had to force to stop, or skipped
    turns (the robot overran its time); robots it said nothing of are left out."""
    lines = [" ".join(str(s).strip(". \n").split()) for s in
             [*summary.get("errors", []), *summary.get("messages", []), *summary.get("robot_reports", [])]]
    out: dict[str, str] = {}
    names = list(names)
    for name in names:
        longer = [o for o in names if o != name and o.startswith(name)]  # sample.Tracker vs sample.Tracker 1.0

        def about(text: str, name: str = name, longer: list[str] = longer) -> bool:
            return name in text and not any(o in text for o in longer)

        mine = [ln for ln in lines if about(ln)]
        skipped = sum(n for robot, n in summary.get("skipped_turns", {}).items() if about(robot))
        found = (
            next((f"not loaded: {ln}" for ln in mine if "Can't find" in ln), None)
            or next((f"throws: {ln}" for ln in mine if "Exception" in ln or "Error:" in ln), None)
            or next((f"hangs: {ln}" for ln in mine if "not stopping" in ln or "cannot be stopped" in ln), None)
        )
        if found is None and skipped:
            first = next((ln for ln in mine if "skipped" in ln), "")
            found = f"overran its time: {skipped} skipped turn(s)" + (f" ({first})" if first else "")
        if found is not None:
            out[name] = found
    return out


def _contestant_rows(summary: dict[str, Any]) -> list[dict[str, Any]]:
    """Per contestant, in the battle's order (the candidate's side first): name and score parts."""
    return [{"name": c["name"], **c["score"]} for c in summary.get("contestants", [])]


def play_job(job: BattleJob, jars: dict[str, bytes], install: Any = None) -> dict[str, Any]:
    """Play one battle in its own working directory and JVM and return its result (never raises for a robot's
    fault or a failed engine run: ``status`` says what happened).

    ``jars``: file name -> bytes of the jars the battle needs (sent along, so that a Ray worker on another machine
    needs no shared folder)."""
    from confront.engine.affinity import claimed_cpu
    from confront.engine.install import find_engine
    from confront.engine.java_build import compile_java
    from confront.engine.runner import EngineOptions, java_command, run_process
    from confront.engine.workdir import prepare_workdir

    install = install or find_engine()
    classes = compile_java(install)
    spec = job.spec()
    started = time.time()
    result: dict[str, Any] = {"key": job.key, "mode": job.mode, "seed": job.seed, "rounds": job.rounds,
                              "candidate": job.candidate.name, "opponents": [o.name for o in job.opponents]}
    with tempfile.TemporaryDirectory(prefix="confront-rumble-") as tmp:
        root = Path(tmp)
        (root / "jars").mkdir()
        for name, data in jars.items():
            (root / "jars" / name).write_bytes(data)
        wd = prepare_workdir(root / "wd", install, classes, job.cpu_constant_ms, spec.teams,
                             sorted((root / "jars").iterdir()))
        (root / "battle.battle").write_text(spec.battle_file())
        summary_file, log = root / "summary.json", root / "engine.log"
        opts = EngineOptions(seed=job.seed, cpu_constant_ms=job.cpu_constant_ms)
        args = [str(wd), str(root / "battle.battle"), str(root / "results.txt"), str(summary_file)]
        try:
            with claimed_cpu(job.one_cpu) as cpu:
                cmd = java_command(install, classes, wd, opts, one_cpu=cpu is not None) + args
                code = run_process(cmd, job.timeout_s, root, log, cpu=cpu)
        except TimeoutError:
            tail = " | ".join(ln for ln in log.read_text(errors="replace").splitlines()[-3:] if ln.strip())
            return {**result, "status": "timed out", "elapsed_s": time.time() - started,
                    "reason": f"timed out: the engine had not finished after {job.timeout_s:.0f} s and was "
                              f"killed (its last output: {tail or 'none'})", "problems": {}, "contestants": []}
        summary = json.loads(summary_file.read_text()) if summary_file.is_file() else {}
        log_tail = " | ".join(ln for ln in log.read_text(errors="replace").splitlines()[-3:] if ln.strip())
    names = [job.candidate.name, *(m for o in job.opponents for m in (o.members or (o.name,)))]
    problems = robot_problems(summary, names)
    result.update(elapsed_s=time.time() - started, problems=problems, contestants=_contestant_rows(summary),
                  skipped_turns=summary.get("skipped_turns", {}), exit_code=code)
    if code == 0 and summary.get("completed"):
        return {**result, "status": "ok", "reason": ""}
    words = "; ".join(summary.get("errors", [])) or log_tail or "no output"
    status = "not loaded" if any(p.startswith("not loaded") for p in problems.values()) else "failed"
    return {**result, "status": status, "reason": f"{status}: the engine run ended with exit code {code}: {words}"}


def write_json_atomic(path: Path, data: Any) -> None:
    """Write ``data`` as JSON to ``path`` through a temporary file and a rename (no half-written result)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, indent=1) + "\n")
    tmp.replace(path)


def _play_from_files(job: BattleJob, jar_paths: dict[str, str]) -> dict[str, Any]:
    """:func:`play_job` in a local worker process, reading the jars from disk."""
    return play_job(job, {n: Path(p).read_bytes() for n, p in jar_paths.items()})


def _play_sent(job: BattleJob, names: Sequence[str], *datas: bytes) -> dict[str, Any]:
    """:func:`play_job` in a Ray task: the jars' bytes arrive as top-level arguments (Ray resolves those)."""
    return play_job(job, dict(zip(names, datas, strict=True)))


@dataclass
class RunStats:
    """How many battles a call to :func:`run_jobs` found done and how many it played."""

    done_before: int = 0
    played: int = 0
    elapsed_s: float = 0.0
    keys_played: list[str] = field(default_factory=list)
    unplayed: list[dict[str, Any]] = field(default_factory=list)  # battles Python could not run: not stored


def _not_played(job: BattleJob, err: BaseException) -> dict[str, Any]:
    """The result of a battle that could not be run at all (no engine, a worker lost, ...): a row that says so,
    not stored, so the next run tries it again."""
    return {"key": job.key, "mode": job.mode, "seed": job.seed, "rounds": job.rounds, "candidate": job.candidate.name,
            "opponents": [o.name for o in job.opponents], "status": "failed", "problems": {}, "contestants": [],
            "stored": False, "reason": f"failed: the battle could not be run ({type(err).__name__}: "
                                       f"{' '.join(str(err).split())[:300]}); the next run tries it again"}


def run_jobs(jobs: Sequence[BattleJob], jar_files: dict[str, Path], battles_dir: Path, workers: int = 1,
             address: str | None = None, progress: bool = True) -> RunStats:
    """Play every job whose ``<battles_dir>/<key>.json`` is missing: ``workers`` local processes, or one Ray task
    each when ``address`` is given ("auto", or ray://host:port). ``jar_files``: each jar's file name (as
    :attr:`Robot.jar` gives it) and path. Each result is stored as soon as it is back."""
    from tqdm import tqdm

    stats = RunStats()
    todo = [j for j in jobs if not (battles_dir / f"{j.key}.json").is_file()]
    stats.done_before = len(jobs) - len(todo)
    if not todo:
        return stats
    start = time.time()

    def jar_paths(job: BattleJob) -> dict[str, str]:
        return {r.jar: str(jar_files[r.jar]) for r in (job.candidate, *job.opponents) if r.jar}

    with tqdm(total=len(todo), desc="rumble", unit="battle", disable=not progress) as bar:
        def done(result: dict[str, Any]) -> None:
            if result.get("stored", True):
                write_json_atomic(battles_dir / f"{result['key']}.json", result)
                stats.played += 1
                stats.keys_played.append(result["key"])
            else:
                stats.unplayed.append(result)
            bar.set_postfix_str(f"{result['key']}: {result['status']}")
            bar.update(1)

        if address is not None:
            _run_ray(todo, jar_paths, address, done)
        else:
            _run_local(todo, jar_paths, workers, done)
    stats.elapsed_s = time.time() - start
    return stats


def _run_local(todo: Sequence[BattleJob], jar_paths: Callable[[BattleJob], dict[str, str]], workers: int,
               done: Callable[[dict[str, Any]], None]) -> None:
    """Jobs over ``workers`` spawned processes (each waits for its battle's JVM); one worker plays them in turn
    here."""
    if workers <= 1:
        for job in todo:
            try:
                done(_play_from_files(job, jar_paths(job)))
            except Exception as err:  # noqa: BLE001 - the rest of the rumble goes on; the row says what failed
                done(_not_played(job, err))
        return
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        jobs = {pool.submit(_play_from_files, job, jar_paths(job)): job for job in todo}
        pending = set(jobs)
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                try:
                    result = fut.result()
                except Exception as err:  # noqa: BLE001 - a worker lost or a battle that could not start
                    result = _not_played(jobs[fut], err)
                done(result)


def _run_ray(todo: Sequence[BattleJob], jar_paths: Callable[[BattleJob], dict[str, str]], address: str,
             done: Callable[[dict[str, Any]], None]) -> None:
    """Jobs as Ray tasks (one CPU each) on the cluster at ``address``; the jars travel through Ray's object
    store, so the workers need the engine and confront, not the folder."""
    import ray

    if not ray.is_initialized():
        os.environ.setdefault("RAY_raylet_start_wait_time_s", "300")
        ray.init(address=address, include_dashboard=False, log_to_driver=False)
    remote = ray.remote(num_cpus=1)(_play_sent)
    refs: dict[str, Any] = {}
    pending = {}
    for job in todo:
        paths = jar_paths(job)
        for name, path in paths.items():
            if name not in refs:
                refs[name] = ray.put(Path(path).read_bytes())
        pending[remote.remote(job, list(paths), *(refs[n] for n in paths))] = job
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        job = pending.pop(ready[0])
        try:
            result = ray.get(ready[0])
        except Exception as err:  # noqa: BLE001 - a task lost (a node gone, no engine there)
            result = _not_played(job, err)
        done(result)


def sample_jars(folder: str | os.PathLike[str], names: Sequence[str], version: str = "1.0",
                install: Any = None) -> list[Path]:
    """Jars of Robocode's own sample robots (``["Tracker", ...]``, package ``sample``), made from the installed
    engine's classes, as ``sample.<Name>_<version>.jar`` in ``folder`` (a folder of opponents for a rumble, tests and
    benchmarks). Their ``.properties`` get ``robot.version`` so the engine tells them from its loose sample robots."""
    from confront.engine.install import find_engine

    install = install or find_engine()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name in names:
        src = install.samples / "sample"
        if not (src / f"{name}.class").is_file():
            raise ValueError(f"no sample robot {name!r} in {src}")
        jar = folder / f"sample.{name}_{version}.jar"
        with zipfile.ZipFile(jar, "w") as z:
            for f in sorted(src.glob(f"{name}*.class")):
                if f.stem == name or f.stem.startswith(name + "$"):
                    z.write(f, f"sample/{f.name}")
            props = (src / f"{name}.properties").read_text(errors="replace")
            z.writestr(f"sample/{name}.properties", props.rstrip("\n") + f"\nrobot.version={version}\n")
        out.append(jar)
    return out
