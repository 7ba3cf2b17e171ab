"""Finding the installed Robocode engine (Debian package ``robocode`` 1.9.3.9) and a Java toolchain."""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

INSTALL_HINT = "install it with: apt-get install -y robocode  (Debian/Ubuntu; brings Java 17 and javac)"
ENGINE_VERSION = "1.9.3.9"

_DEFAULT_JAR = Path("/usr/share/java/robocode.jar")
_DEFAULT_SAMPLES = Path("/usr/share/games/robocode/robots")

# JVM flags the engine needs under Java 17 (robocode-facts.md, section 0).
HEADLESS = "-Djava.awt.headless=true"  # no display (dropped for a visible battle)
JVM_FLAGS: tuple[str, ...] = (
    HEADLESS,
    "--add-opens=java.base/sun.net.www.protocol.jar=ALL-UNNAMED",
    "--add-opens=java.base/java.lang.reflect=ALL-UNNAMED",
    "--add-opens=java.desktop/javax.swing.text=ALL-UNNAMED",
    "--add-opens=java.desktop/sun.awt=ALL-UNNAMED",
)


X11_SOCKETS = Path("/tmp/.X11-unix")  # where a local X server ":N" listens (X<N>)


def require_display(what: str) -> None:
    """ValueError naming ``what`` when no display is set, or when ``DISPLAY`` names a local display (``:N``) whose
    X server is not running (no socket): Robocode's windows need one."""
    display = os.environ.get("DISPLAY")
    if not display:
        raise ValueError(f"{what} needs a display, and DISPLAY is not set (run it on a desktop, or under xvfb-run)")
    host, _, rest = display.rpartition(":")
    number = rest.split(".")[0]
    if host in ("", "unix") and number.isdigit() and not (X11_SOCKETS / f"X{number}").exists():
        raise ValueError(f"{what} needs a display, and no X server runs on DISPLAY={display[:40]} (no "
                         f"{X11_SOCKETS}/X{number}): start one, or run under xvfb-run")


class EngineNotFoundError(RuntimeError):
    """The Robocode engine or the Java tools are missing."""


@dataclass(frozen=True)
class EngineInstall:
    """Paths of an installed engine: its main jar, the sample robots and the java/javac binaries."""

    jar: Path
    samples: Path
    java: str
    javac: str

    @property
    def classpath(self) -> str:
        """Class path of the engine (the jar's manifest pulls in the other engine jars)."""
        return str(self.jar)


def find_engine(jar: str | os.PathLike[str] | None = None) -> EngineInstall:
    """Locate the engine: ``jar`` argument, then $CONFRONT_ROBOCODE_JAR, then the Debian location."""
    jar_path = Path(jar or os.environ.get("CONFRONT_ROBOCODE_JAR") or _DEFAULT_JAR)
    if not jar_path.is_file():
        raise EngineNotFoundError(f"Robocode engine not found ({jar_path} is missing); {INSTALL_HINT}")
    samples = Path(os.environ.get("CONFRONT_ROBOCODE_SAMPLES") or _DEFAULT_SAMPLES)
    if not (samples / "sample").is_dir():
        raise EngineNotFoundError(f"Robocode sample robots not found in {samples}; {INSTALL_HINT}")
    java = shutil.which("java")
    javac = shutil.which("javac")
    if java is None or javac is None:
        raise EngineNotFoundError(f"java/javac not found on PATH; {INSTALL_HINT}")
    return EngineInstall(jar=jar_path, samples=samples, java=java, javac=javac)


def engine_available() -> bool:
    """True when :func:`find_engine` succeeds."""
    try:
        find_engine()
    except EngineNotFoundError:
        return False
    return True
