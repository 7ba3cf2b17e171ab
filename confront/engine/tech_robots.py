"""The classic-technique robots (``confront.tech.*``) as a robot jar for Robocode.

Each robot is a small subclass of ``confront/engine/java/confront/tech/TechBot.java`` that picks one gun and
one movement; the simulator plays the same robots (:mod:`confront.arena.tech`). The project's Java build
compiles them with the other sources; :func:`write_tech_jar` packs the classes, their sources and one
``.properties`` file per robot so that Robocode lists them as ``confront.tech.<Name> 1.0``.

Usage: ``python -m confront.engine.tech_robots OUT`` (``OUT``: a robots folder or a ``.jar`` path).
"""

from __future__ import annotations

import sys
import tempfile
import zipfile
from collections.abc import Sequence
from pathlib import Path

from confront.engine.install import EngineInstall, find_engine
from confront.engine.java_build import JAVA_SOURCES, compile_java

VERSION = "1.0"
JAR_NAME = "confront-tech.jar"
# name: (gun, movement), in rising strength in 1v1 (docs/results/tech/README.md); RiskGF is for melee and teams
TECH_ROBOTS: dict[str, tuple[str, str]] = {
    "RamHeadOn": ("head-on", "ramming"),
    "StopGoCircular": ("circular", "stop-and-go"),
    "OrbitLinear": ("linear", "random orbit, wall smoothing"),
    "OrbitCircular": ("circular", "random orbit, wall smoothing"),
    "OrbitVG": ("virtual guns", "random orbit, wall smoothing"),
    "OrbitGF": ("GuessFactor", "random orbit, wall smoothing"),
    "SurfCircular": ("circular", "wave surfing"),
    "SurfGF": ("GuessFactor", "wave surfing"),
    "SurfVG": ("virtual guns", "wave surfing"),
    "SurfAS": ("GuessFactor and anti-surfer GuessFactor", "wave surfing"),
    "RiskGF": ("GuessFactor", "minimum risk"),
}
PACKAGE = "confront.tech"


def engine_name(name: str) -> str:
    """The name Robocode lists a technique robot by: 'SurfGF' -> 'confront.tech.SurfGF 1.0'."""
    if name not in TECH_ROBOTS:
        raise ValueError(f"unknown technique robot {name!r}; known: {', '.join(TECH_ROBOTS)}")
    return f"{PACKAGE}.{name} {VERSION}"


def properties(name: str) -> str:
    """The robot's ``.properties`` file (what Robocode reads to list a robot in a jar)."""
    gun, move = TECH_ROBOTS[name]
    return (f"robot.classname={PACKAGE}.{name}\nrobot.name={name}\nrobot.version={VERSION}\n"
            f"robot.description=confront technique robot: {move}; {gun} gun\nrobot.author.name=confront\n"
            f"robot.java.source.included=true\nrobocode.version=1.9.3.9\n")


def write_tech_jar(out: str | Path, install: EngineInstall | None = None, classes: Path | None = None) -> Path:
    """Write the robots to ``out``: a ``.jar`` file, or else a robots folder (the jar goes inside it)."""
    classes = classes if classes is not None else compile_java(install or find_engine())
    out = Path(out)
    jar = out if out.suffix == ".jar" else out / JAR_NAME
    jar.parent.mkdir(parents=True, exist_ok=True)
    compiled = sorted((classes / "confront" / "tech").glob("*.class"))
    if not compiled:
        raise RuntimeError(f"no compiled technique robots under {classes}")
    with tempfile.NamedTemporaryFile(dir=jar.parent, suffix=".tmp", delete=False) as tmp:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("META-INF/MANIFEST.MF", "Manifest-Version: 1.0\n")
            for f in compiled:
                z.write(f, f"confront/tech/{f.name}")
            for f in sorted((JAVA_SOURCES / "confront" / "tech").glob("*.java")):
                z.write(f, f"confront/tech/{f.name}")
            for name in TECH_ROBOTS:
                z.writestr(f"confront/tech/{name}.properties", properties(name))
    Path(tmp.name).replace(jar)
    return jar


def cached_tech_jar(classes: Path) -> Path:
    """The jar next to the compiled classes (written once per build)."""
    jar = classes / JAR_NAME
    if not jar.is_file():
        write_tech_jar(jar, classes=classes)
    return jar


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: write the jar."""
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 1 or args[0].startswith("-"):
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    print(write_tech_jar(args[0]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = ["TECH_ROBOTS", "engine_name", "write_tech_jar", "cached_tech_jar", "properties", "JAR_NAME"]
