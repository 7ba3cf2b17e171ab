"""Robocode's own program (its window, its New Battle dialog), started so that it works under Java 17.

Debian's launcher ``/usr/games/robocode`` starts the engine without the ``--add-opens`` flags Java 17 needs
(robocode-facts.md, section 0): its robot repository then fails to load (``InaccessibleObjectException`` in
``URLJarCollector``) and the program lists no robot. :func:`open_robocode` starts the same program on the same
working directory (``~/.local/share/robocode/1.9.3.9``, made the first time as the launcher makes it) with the
flags, after copying the given robot jars (``confront export``) into its robots folder.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

from confront.engine.install import ENGINE_VERSION, HEADLESS, JVM_FLAGS, EngineInstall, require_display

# what Debian's launcher copies into a new working directory (the rest it links)
COPIED = ("battles", "compilers", "config", "roborumble", "robots", "templates", "theme")


def default_workdir() -> Path:
    """The working directory Debian's launcher uses."""
    return Path.home() / ".local" / "share" / "robocode" / ENGINE_VERSION


def robocode_workdir(install: EngineInstall, path: Path | None = None) -> Path:
    """``path`` (default :func:`default_workdir`), made as Debian's launcher makes it when it does not exist:
    the installation's folders copied (sample robots included), mode 700."""
    wd = Path(path).absolute() if path is not None else default_workdir()  # Robocode resolves from its own cwd
    if wd.is_dir() and (wd / "robots").is_dir():
        return wd
    if wd.is_dir() and any(wd.iterdir()):
        raise ValueError(f"--workdir {wd} is not a Robocode working directory (it has no robots folder): give a "
                         "new or empty folder, or one Robocode made")
    if wd.is_dir():
        wd.rmdir()  # an empty folder: made as a new one
    share = install.samples.parent
    tmp = wd.with_name(f".{wd.name}.{os.getpid()}.tmp")
    tmp.mkdir(mode=0o700, parents=True)
    for name in COPIED:
        if (share / name).is_dir():
            shutil.copytree(share / name, tmp / name)
    (tmp / "robots").mkdir(exist_ok=True)
    tmp.rename(wd)
    return wd


def robocode_command(install: EngineInstall, workdir: Path) -> list[str]:
    """The JVM command line of Robocode's program on ``workdir``: the engine's Java 17 flags, with a display."""
    flags = [f for f in JVM_FLAGS if f != HEADLESS]
    return [install.java, "-Xmx512M", f"-DWORKINGDIRECTORY={workdir}", *flags, "-cp", install.classpath,
            "robocode.Robocode"]


def open_robocode(install: EngineInstall, robots: Sequence[Path] = (), workdir: Path | None = None,
                  wait: bool = True) -> subprocess.Popen[bytes]:
    """Start Robocode's program with ``robots`` (robot jars) copied into its robots folder; with ``wait``, return
    when its window is closed. Needs a display (``DISPLAY``)."""
    require_display("Robocode's window")
    for jar in robots:
        if Path(jar).suffix != ".jar" or not Path(jar).is_file():
            raise ValueError(f"{jar} is not a robot jar: write one with confront export RUN --out NAME.jar")
    wd = robocode_workdir(install, workdir)
    for jar in robots:
        shutil.copy2(jar, wd / "robots" / Path(jar).name)
    with open(wd / "confront-robocode.log", "wb") as log:  # the program's output (the child keeps the file open)
        proc = subprocess.Popen(robocode_command(install, wd), cwd=wd, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL)
    if wait:
        proc.wait()
    return proc
