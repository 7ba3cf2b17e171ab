"""Run folders: layout, tables in CSV (and Parquet), atomic JSON."""

import json
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
