"""Run folders: layout, tables in CSV (and Parquet), atomic JSON."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from confront.runs import Run


def test_layout_and_tables(tmp_path: Path) -> None:
    run = Run.create(tmp_path / "r", {"train": {"rounds": 5}})
    assert sorted(p.name for p in run.path.iterdir()) == [
        "checkpoints", "config.toml", "metrics", "plots", "replays",
    ]
    assert "rounds = 5" in (run.path / "config.toml").read_text()
    rows = [{"round": 1, "score": 10.5, "arm": "a"}, {"round": 2, "score": float("nan"), "arm": "b"}]
    paths = run.write_table("rounds", rows)
    assert [p.name for p in paths][0] == "rounds.csv"
    back = run.read_table("rounds")
    assert back == [{"round": 1, "score": 10.5, "arm": "a"}, {"round": 2, "score": None, "arm": "b"}]
    run.write_summary({"ratio": 0.5})
    assert json.loads((run.path / "summary.json").read_text()) == {"ratio": 0.5}


def test_append_table_appends_and_rewrites_when_it_must(tmp_path: Path) -> None:
    run = Run.create(tmp_path / "r")
    rows = [{"round": i, "share": i / 4} for i in range(1, 4)]
    assert run.append_table("rounds", rows[:2], 0) == 2
    csv = run.path / "metrics" / "rounds.csv"
    before = csv.stat().st_ino
    assert run.append_table("rounds", rows, 2) == 3
    assert csv.stat().st_ino == before  # appended in place, not rewritten
    assert run.read_table("rounds") == rows
    assert csv.read_text() == "round,share\n1,0.25\n2,0.5\n3,0.75\n"
    # a resumed run (written 0) rewrites whole: rows past its checkpoint are gone
    run.append_table("rounds", rows[:1], 0)
    assert run.read_table("rounds") == rows[:1]
    # new columns: rewritten whole with the union of the columns
    run.append_table("rounds", [*rows[:1], {"round": 2, "share": 0.5, "won": True}], 1)
    assert csv.read_text() == "round,share,won\n1,0.25,\n2,0.5,True\n"


def test_existing_run_folder_is_not_overwritten(tmp_path: Path) -> None:
    Run.create(tmp_path / "r", {})
    with pytest.raises(FileExistsError, match="already exists"):
        Run.create(tmp_path / "r", {})


def test_one_run_at_a_time_writes_a_run_folder(tmp_path: Path) -> None:
    """Issue 34 item 2: a second run into a folder being written is refused; the first is unharmed."""
    from confront.runs import RunBusyError

    first = Run.create(tmp_path / "r", {"a": 1}, lock=True)
    with pytest.raises(RunBusyError, match=f"being written by another run \\(process {os.getpid()}\\)"):
        Run.create(tmp_path / "r", {"a": 2}, exist_ok=True, lock=True)
    with pytest.raises(RunBusyError):
        Run.open(tmp_path / "r")
    assert (first.path / "config.toml").read_text() == "a = 1\n" and first.path.is_dir()
    first.release()
    assert not (first.path / ".lock").exists()
    again = Run.open(tmp_path / "r")
    again.release()
    # a new folder that another run locked first is not removed by the loser
    pre = Run.create(tmp_path / "p", lock=True)
    with pytest.raises(RunBusyError):
        Run.create(tmp_path / "p", {"a": 2}, exist_ok=True, lock=True).discard_if_new()
    assert pre.path.is_dir()
    pre.release()


def test_a_dead_runs_lock_does_not_block(tmp_path: Path) -> None:
    """Issue 34 item 2: the lock of a killed process (its .lock file left behind) is taken over."""
    folder = tmp_path / "r"
    Run.create(folder).release()
    code = ("import sys, time; from pathlib import Path; from confront.runs import Run; "
            "Run.open(Path(sys.argv[1])); print('locked', flush=True); time.sleep(60)")
    proc = subprocess.Popen([sys.executable, "-c", code, str(folder)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == "locked"
        with pytest.raises(FileExistsError, match=f"process {proc.pid}"):
            Run.open(folder)
    finally:
        proc.kill()
        proc.wait()
    assert (folder / ".lock").exists()  # left by the killed run
    Run.open(folder).release()


def test_symlinked_run_subfolder_is_refused(tmp_path: Path) -> None:
    """Issue 34 item 3: a run never writes through a linked plots/ or checkpoints/ folder."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    folder = tmp_path / "r"
    Run.create(folder).release()
    (folder / "plots").rmdir()
    (folder / "plots").symlink_to(elsewhere)
    with pytest.raises(FileExistsError, match="symbolic link"):
        Run.open(folder)
    assert list(elsewhere.iterdir()) == [] and not (folder / ".lock").exists()
