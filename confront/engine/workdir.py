"""A private Robocode working directory: config with a fixed CPU constant, robots, teams, script data."""

from __future__ import annotations

import shutil
from collections.abc import Iterable, Mapping
from pathlib import Path

from confront.engine.battle import TEAM_PACKAGE, Team
from confront.engine.install import EngineInstall
from confront.engine.java_build import MODEL_CLASSES, ROBOT_CLASSES, ROBOT_HELPERS

SAMPLE_PACKAGES: tuple[str, ...] = ("sample", "sampleteam")
# BridgeBot runs the exported robot's gun/radar controller (PolicyModel) between decisions
BRIDGE_HELPERS: tuple[str, ...] = ("PolicyModel", *MODEL_CLASSES)


def prepare_workdir(
    path: Path,
    install: EngineInstall,
    classes: Path,
    cpu_constant_ms: float = 10.0,
    teams: Iterable[Team] = (),
    extra_robots: Iterable[Path] = (),
) -> Path:
    """Create (or refresh) a working directory at ``path`` and return it.

    The CPU constant (robot time per turn) is written to config/robocode.properties so the engine does not
    run its 5 s benchmark; sample robots, the project's robots (the technique robots as a jar) and
    ``extra_robots`` (robot jars, or folders holding package folders, e.g. an exported robot) are copied into
    robots/.
    """
    if not cpu_constant_ms > 0:
        raise ValueError(f"cpu_constant_ms must be > 0, got {cpu_constant_ms}")
    path = Path(path)
    (path / "config").mkdir(parents=True, exist_ok=True)
    robots = path / "robots"
    robots.mkdir(exist_ok=True)
    # robocode.cpu.constant is in ns [CpuManager]
    (path / "config" / "robocode.properties").write_text(
        f"robocode.cpu.constant={int(cpu_constant_ms * 1e6)}\n"
    )
    for pkg in SAMPLE_PACKAGES:
        if not (robots / pkg).is_dir():
            shutil.copytree(install.samples / pkg, robots / pkg)
    ours = robots / "confront"
    ours.mkdir(exist_ok=True)
    for helper in ROBOT_HELPERS + BRIDGE_HELPERS:
        shutil.copy2(classes / "confront" / f"{helper}.class", ours / f"{helper}.class")
    for cls in ROBOT_CLASSES:
        for f in (classes / "confront").glob(f"{cls}*.class"):
            if f.stem == cls or f.stem.startswith(cls + "$"):
                shutil.copy2(f, ours / f.name)
        (ours / f"{cls}.properties").write_text(
            f"robot.classname=confront.{cls}\nrobot.name={cls}\nrobocode.version=1.9.3.9\n"
        )
    if (classes / "confront" / "tech").is_dir():  # the technique robots (confront.tech.*), as one jar
        from confront.engine.tech_robots import JAR_NAME, cached_tech_jar

        shutil.copy2(cached_tech_jar(classes), robots / JAR_NAME)
    for extra in extra_robots:
        extra = Path(extra)
        if extra.suffix == ".jar":
            shutil.copy2(extra, robots / extra.name)
        elif extra.is_dir():
            shutil.copytree(extra, robots, dirs_exist_ok=True)
        else:
            raise ValueError(f"extra robot must be a .jar or a folder, got {extra}")
    if teams:
        (robots / TEAM_PACKAGE).mkdir(exist_ok=True)
        for team in teams:
            (robots / TEAM_PACKAGE / f"{team.name}.team").write_text(team.team_file())
    return path


def write_robot_data(workdir: Path, robot: str, files: Mapping[str, str]) -> Path:
    """Write files into the data folder of one of the project's robots (e.g. ScriptBot scripts)."""
    if robot not in ROBOT_CLASSES:
        raise ValueError(f"robot must be one of {ROBOT_CLASSES}, got {robot!r}")
    data = Path(workdir) / "robots" / "confront" / f"{robot}.data"
    if data.exists():
        shutil.rmtree(data)
    data.mkdir(parents=True)
    for name, text in files.items():
        if "/" in name or name.startswith("."):
            raise ValueError(f"bad data file name {name!r}")
        (data / name).write_text(text)
    return data
