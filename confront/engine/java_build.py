"""Compiling the project's Java sources (runner, script robot, bridge robots) against the engine's jar.

Compiled classes are cached by a hash of the sources and the engine jar, under
$CONFRONT_CACHE (or the older name $CONFRONT_CACHE_DIR) or $XDG_CACHE_HOME/confront (default ~/.cache/confront).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from confront.engine.install import EngineInstall

JAVA_SOURCES = Path(__file__).parent / "java"
# Robot classes (package confront) and their robot.name entries for the .properties files.
ROBOT_CLASSES: tuple[str, ...] = ("ScriptBot", "BridgeBot")
# helper classes the robots load at run time, copied next to them
ROBOT_HELPERS: tuple[str, ...] = ("RoundStart", "RobotParts")
# the model reader, MLP and gun/radar controller PolicyModel and TankModel share (no Robocode dependency)
MODEL_CLASSES: tuple[str, ...] = ("ModelFile", "Mlp", "Aim")


def cache_root() -> Path:
    """confront's cache folder (compiled classes, TD-team artefacts): $CONFRONT_CACHE, else the older name
    $CONFRONT_CACHE_DIR, else $XDG_CACHE_HOME/confront or ~/.cache/confront."""
    env = os.environ.get("CONFRONT_CACHE") or os.environ.get("CONFRONT_CACHE_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "confront"


def _sources(src: Path) -> list[Path]:
    return sorted(src.rglob("*.java"))


def source_hash(install: EngineInstall, src: Path = JAVA_SOURCES) -> str:
    """Hash of every Java source file (path and bytes) plus the engine jar's size and path."""
    h = hashlib.sha256()
    for p in _sources(src):
        h.update(str(p.relative_to(src)).encode())
        h.update(p.read_bytes())
    h.update(f"{install.jar}:{install.jar.stat().st_size}".encode())
    return h.hexdigest()[:16]


def compile_java(install: EngineInstall, cache_dir: Path | None = None, src: Path = JAVA_SOURCES) -> Path:
    """Compile the sources once per hash with javac; return the folder of .class files."""
    root = Path(cache_dir) if cache_dir is not None else cache_root()
    out = root / "java" / source_hash(install, src)
    if (out / "OK").is_file():
        return out
    sources = _sources(src)
    if not sources:
        raise ValueError(f"no Java sources under {src}")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="build-", dir=out.parent))
    try:
        cmd = [install.javac, "-nowarn", "-encoding", "UTF-8", "-cp", install.classpath, "-d", str(tmp)]
        proc = subprocess.run(cmd + [str(p) for p in sources], capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            raise RuntimeError(f"javac failed:\n{proc.stderr.strip()}")
        (tmp / "OK").write_text("ok\n")
        try:
            tmp.rename(out)
        except OSError:  # another process finished the same build first
            if not (out / "OK").is_file():
                raise
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return out
