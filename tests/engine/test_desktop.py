"""`confront robocode`: Robocode's own program on Debian's working directory, started with the Java 17 flags that
Debian's launcher lacks, so that its robot repository loads the exported jar's robot and team."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from confront.cli.main import cli
from confront.engine.desktop import open_robocode, robocode_command, robocode_workdir
from confront.engine.export import ExportedPolicy, export_robot
from confront.engine.install import EngineInstall

pytestmark = pytest.mark.xdist_group("display")  # one virtual display at a time


def test_workdir_is_made_as_debians_launcher_makes_it(install: EngineInstall, tmp_path: Path) -> None:
    wd = robocode_workdir(install, tmp_path / "rc")
    assert (wd / "robots" / "sample" / "SpinBot.class").is_file() and (wd / "config").is_dir()
    assert (wd / "robots" / "sampleteam" / "MyFirstTeam.team").is_file()
    assert wd.stat().st_mode & 0o777 == 0o700
    (wd / "robots" / "mine.jar").write_bytes(b"kept")
    assert robocode_workdir(install, wd) == wd and (wd / "robots" / "mine.jar").read_bytes() == b"kept"


def _repository_after(proc, wd: Path, seconds: float = 90.0) -> bytes:  # noqa: ANN001 - a Popen
    """robots/robot.database once the program has written it (its repository loaded), then stop the program."""
    db = wd / "robots" / "robot.database"
    try:
        for _ in range(int(seconds / 0.5)):
            if db.is_file() and db.stat().st_size > 0 and proc.poll() is None:
                time.sleep(1.0)  # let it finish writing
                return db.read_bytes()
            if proc.poll() is not None:
                break
            time.sleep(0.5)
        return db.read_bytes() if db.is_file() else b""
    finally:
        proc.terminate()
        proc.wait(30)


def test_robocode_lists_the_exported_team_with_our_flags_and_not_with_debians(
        install: EngineInstall, display: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    jar = export_robot(ExportedPolicy("qtable", q=np.zeros((320, 4))), tmp_path / "Paper.jar")
    monkeypatch.setenv("DISPLAY", display)
    ours = tmp_path / "ours"
    db = _repository_after(open_robocode(install, [jar], ours, wait=False), ours)
    assert b"confront.PolicyTeam" in db and b"confront.PolicyBot" in db and b"sample.SpinBot" in db
    assert b"InaccessibleObjectException" not in (ours / "confront-robocode.log").read_bytes()
    # Debian's launcher: the same program without --add-opens lists no robot at all
    debian = robocode_workdir(install, tmp_path / "debian")
    (debian / "robots" / jar.name).write_bytes(jar.read_bytes())
    cmd = [c for c in robocode_command(install, debian) if not c.startswith("--add-opens")]
    with open(debian / "log.txt", "wb") as log:
        proc = subprocess.Popen(cmd, cwd=debian, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        for _ in range(180):  # until its repository has failed (the log says why), at most 90 s
            if b"InaccessibleObjectException" in (debian / "log.txt").read_bytes() or proc.poll() is not None:
                break
            time.sleep(0.5)
        time.sleep(2.0)
    finally:
        proc.terminate()
        proc.wait(30)
    assert b"InaccessibleObjectException" in (debian / "log.txt").read_bytes()
    db = debian / "robots" / "robot.database"
    assert not db.is_file() or b"confront.PolicyTeam" not in db.read_bytes()


def test_robocode_command_refuses_without_a_display_or_a_jar(monkeypatch: pytest.MonkeyPatch,
                                                            tmp_path: Path) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    res = CliRunner().invoke(cli, ["robocode", "--workdir", str(tmp_path / "wd")])
    assert res.exit_code == 2 and "Robocode's window needs a display, and DISPLAY is not set" in res.output
    assert not (tmp_path / "wd").exists()  # nothing made before the check
    monkeypatch.setenv("DISPLAY", ":12345")
    monkeypatch.setattr("confront.engine.install.require_display", lambda what: None)  # as if it had an X server
    monkeypatch.setattr("confront.engine.desktop.require_display", lambda what: None)
    (tmp_path / "policy.txt").write_text("not a jar")
    res = CliRunner().invoke(cli, ["robocode", str(tmp_path / "policy.txt"), "--workdir", str(tmp_path / "wd")])
    assert res.exit_code == 2 and "is not a robot jar: write one with confront export RUN --out NAME.jar" in res.output


def test_a_display_without_an_x_server_is_refused(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """Issue 34 item 8: DISPLAY=:N with no X server on it was started (Robocode crashed, exit 0)."""
    number = next(n for n in range(987, 1100) if not Path(f"/tmp/.X11-unix/X{n}").exists())
    monkeypatch.setenv("DISPLAY", f":{number}")
    res = CliRunner().invoke(cli, ["robocode", "--workdir", str(tmp_path / "wd")])
    assert res.exit_code == 2 and f"no X server runs on DISPLAY=:{number}" in res.stderr, res.output
    assert len(res.stderr.strip().splitlines()) == 1 and not (tmp_path / "wd").exists()


def test_robocode_that_crashes_with_exit_0_is_a_failure(install: EngineInstall, monkeypatch: pytest.MonkeyPatch,
                                                        tmp_path: Path) -> None:
    """Issue 34 item 8: Robocode's window failing (an AWTError in its log) while it exits 0 is reported."""
    import confront.engine.desktop as desktop

    wd = robocode_workdir(install, tmp_path / "wd")

    def crashing(install: EngineInstall, jars: list[Path], workdir: Path | None, wait: bool) -> subprocess.Popen:
        (wd / "confront-robocode.log").write_text('Exception in thread "main" java.awt.AWTError: Can\'t connect\n')
        return subprocess.Popen(["true"])

    monkeypatch.setattr("confront.engine.install.require_display", lambda what: None)
    monkeypatch.setattr(desktop, "open_robocode", crashing)
    res = CliRunner().invoke(cli, ["robocode", "--workdir", str(wd)])
    assert res.exit_code == 1 and "java.awt.AWTError" in res.output and "Robocode failed" in res.output, res.output


def test_workdir_relative_or_without_robots_folder(install: EngineInstall, monkeypatch: pytest.MonkeyPatch,
                                                  tmp_path: Path) -> None:
    """Issue 34 item 9: a relative --workdir is made absolute (Robocode looked in rel/rel); a folder of other
    things without robots/ is refused in one line; an empty one is made a working directory."""
    monkeypatch.chdir(tmp_path)
    wd = robocode_workdir(install, Path("rel"))
    assert wd == tmp_path / "rel" and (wd / "robots" / "sample").is_dir()
    assert f"-DWORKINGDIRECTORY={tmp_path / 'rel'}" in robocode_command(install, wd)
    (tmp_path / "empty").mkdir()
    assert (robocode_workdir(install, Path("empty")) / "robots").is_dir()
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "mine.txt").write_text("m")
    monkeypatch.setattr("confront.engine.install.require_display", lambda what: None)
    monkeypatch.setattr("confront.engine.desktop.require_display", lambda what: None)
    res = CliRunner().invoke(cli, ["robocode", "--workdir", "other"])
    assert res.exit_code == 2 and "is not a Robocode working directory" in res.stderr, res.output
    assert sorted(p.name for p in (tmp_path / "other").iterdir()) == ["mine.txt"]
