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


def test_existing_run_folder_is_not_overwritten(tmp_path: Path) -> None:
    Run.create(tmp_path / "r", {})
    with pytest.raises(FileExistsError, match="already exists"):
        Run.create(tmp_path / "r", {})
