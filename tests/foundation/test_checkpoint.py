"""Checkpoints are data, atomic, verified; bad ones are refused and never overwrite good ones."""

import json
from pathlib import Path

import numpy as np
import pytest

from confront import checkpoint as ck


def _save(root: Path, name: str, value: float) -> Path:
    rng = np.random.default_rng(7)
    rng.random(3)
    return ck.save(root, name, {"w": np.full(4, value), "n": np.array(3)}, {"round": 3, "rng": ck.rng_state(rng)})


def test_round_trip_and_rng(tmp_path: Path) -> None:
    path = _save(tmp_path, "round-000003", 1.5)
    arrays, meta = ck.load(path)
    np.testing.assert_array_equal(arrays["w"], np.full(4, 1.5))
    assert meta["round"] == 3 and meta["format_version"] == ck.FORMAT_VERSION
    reference = np.random.default_rng(7)
    reference.random(3)
    assert ck.rng_from_state(meta["rng"]).random() == reference.random()
    assert ck.latest(tmp_path) == path


def test_tables_go_to_the_arrays_and_come_back_exactly(tmp_path: Path) -> None:
    rows = [{"round": i + 1, "opponent": f"1v1:Bot{i % 3}", "share": i / 7, "won": i % 2 == 0,
             "loss": float("nan") if i == 2 else -0.1 * i} for i in range(5)]
    mixed = [{"a": 1}, {"a": None}]  # not one type per column: stays in the JSON
    path = ck.save(tmp_path, "round-000005", {"w": np.ones(2)}, {"rounds_done": 5, "rows": rows, "mixed": mixed})
    text = (path / "meta.json").read_text()
    assert "Bot1" not in text and json.loads(text)["tables"] == {"rows": ["round", "opponent", "share", "won", "loss"]}
    arrays, meta = ck.load(path)
    assert set(arrays) == {"w"} and meta["mixed"] == mixed and "tables" not in meta
    back = meta["rows"]
    assert [list(r) for r in back] == [list(r) for r in rows]  # key order kept
    for got, want in zip(back, rows, strict=True):
        for k, v in want.items():
            assert type(got[k]) is type(v)
            assert got[k] == v or (v != v and got[k] != got[k])  # NaN stays NaN
    with pytest.raises(ValueError, match="reserved"):
        ck.save(tmp_path, "round-000006", {"table.x": np.ones(1)}, {})


def test_table_rows_must_fit_rounds_done(tmp_path: Path) -> None:
    path = ck.save(tmp_path, "round-000003", {"w": np.ones(2)}, {"rounds_done": 3, "rows": [{"r": 1}, {"r": 2}]})
    with pytest.raises(ck.CheckpointError, match="holds 2 rows"):
        ck.load(path)


def test_truncated_checkpoint_is_refused(tmp_path: Path) -> None:
    path = _save(tmp_path, "round-000003", 1.0)
    npz = path / "state.npz"
    npz.write_bytes(npz.read_bytes()[:40])
    with pytest.raises(ck.CheckpointError, match="corrupt or truncated"):
        ck.load(path)


def test_corrupt_meta_and_wrong_version_are_refused(tmp_path: Path) -> None:
    path = _save(tmp_path, "round-000003", 1.0)
    meta = json.loads((path / "meta.json").read_text())
    meta["format_version"] = 99
    (path / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(ck.CheckpointError, match="format version 99"):
        ck.load(path)
    (path / "meta.json").write_text("{not json")
    with pytest.raises(ck.CheckpointError, match="corrupt meta.json"):
        ck.load(path)
    (path / "meta.json").unlink()
    with pytest.raises(ck.CheckpointError, match="incomplete"):
        ck.load(path)


def test_pickled_arrays_are_not_loaded(tmp_path: Path) -> None:
    path = _save(tmp_path, "round-000003", 1.0)
    npz = path / "state.npz"
    np.savez(npz, obj=np.array([{"a": 1}], dtype=object))
    meta = json.loads((path / "meta.json").read_text())
    meta["sha256"] = ck._sha256(npz)
    meta["meta_sha256"] = ck._meta_digest(meta)
    (path / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(ck.CheckpointError, match="cannot be read"):
        ck.load(path)


def test_keeps_newest_and_cleans_partial_saves(tmp_path: Path) -> None:
    for i in range(4):
        _save(tmp_path, f"round-{i:06d}", float(i))
    (tmp_path / ".round-000009.partial").mkdir()
    _save(tmp_path, "round-000005", 5.0)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["LATEST", "round-000003", "round-000005"]
    assert ck.load(ck.latest(tmp_path))[0]["w"][0] == 5.0


def _train_save(root: Path, done: int) -> Path:
    rows = [{"round": i + 1, "score_ours": 1.0, "battle": 0} for i in range(done)]
    return ck.save(root, f"round-{done:06d}", {"w": np.arange(3.0)}, {"rounds_done": done, "rows": rows})


def test_edited_meta_is_refused_and_nothing_is_deleted(tmp_path: Path) -> None:
    for done in (100, 200, 300):
        _train_save(tmp_path, done)
    path = ck.latest(tmp_path)
    meta_path = path / "meta.json"
    meta = json.loads(meta_path.read_text())
    meta["rounds_done"] = 1300
    meta_path.write_text(json.dumps(meta))
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    with pytest.raises(ck.CheckpointError, match="edited or corrupt meta.json"):
        ck.load(path)
    meta["meta_sha256"] = ck._meta_digest(meta)  # a consistent-looking digest still disagrees with the rows
    meta_path.write_text(json.dumps(meta))
    before[meta_path] = meta_path.read_bytes()
    with pytest.raises(ck.CheckpointError, match="rounds_done = 1300"):
        ck.load(path)
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_version_1_checkpoints_are_read_with_the_cross_checks(tmp_path: Path) -> None:
    path = _train_save(tmp_path, 5)
    meta = json.loads((path / "meta.json").read_text())
    meta["format_version"] = 1
    del meta["meta_sha256"]
    (path / "meta.json").write_text(json.dumps(meta))
    assert ck.load(path)[1]["rounds_done"] == 5
    meta["rounds_done"] = 6
    (path / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(ck.CheckpointError, match="name says 5"):
        ck.load(path)


def test_saving_an_older_round_keeps_newer_checkpoints(tmp_path: Path) -> None:
    for done in (100, 200, 300):
        _train_save(tmp_path, done)
    _train_save(tmp_path, 150)  # e.g. after a resume from an older checkpoint
    assert sorted(p.name for p in tmp_path.iterdir()) == ["LATEST", "round-000150", "round-000200",
                                                         "round-000300"]
    assert ck.latest(tmp_path).name == "round-000150"


def test_missing_latest_falls_back_to_the_newest_valid_checkpoint(tmp_path: Path) -> None:
    for done in (100, 200):
        _train_save(tmp_path, done)
    (tmp_path / "LATEST").unlink()
    (tmp_path / "round-000200" / "state.npz").write_bytes(b"broken")
    said: list[str] = []
    assert ck.latest(tmp_path, notice=said.append) == tmp_path / "round-000100"
    assert len(said) == 1 and "round-000100" in said[0] and "LATEST is missing" in said[0]
    (tmp_path / "round-000100" / "meta.json").unlink()
    assert ck.latest(tmp_path, notice=said.append) is None and len(said) == 1


def test_checkpoint_rows_keep_their_column_order(tmp_path: Path) -> None:
    rows = [{"zeta": 1, "alpha": 2, "mid": 3}]
    path = ck.save(tmp_path, "round-000001", {"w": np.zeros(1)}, {"rounds_done": 1, "rows": rows})
    assert list(ck.load(path)[1]["rows"][0]) == ["zeta", "alpha", "mid"]


def test_save_deletes_only_checkpoints_it_wrote(tmp_path: Path) -> None:
    """Issue 34 item 1: a user's folders in checkpoints/ (sorting before the new name, or hidden) stay."""
    root = tmp_path / "checkpoints"
    _save(root, "round-000002", 1.0)
    (root / "best").mkdir()
    (root / "best" / "notes.txt").write_text("n\n")
    (root / ".git").mkdir()
    (root / ".git" / "HEAD").write_text("ref\n")
    (root / "aaa-mine").mkdir()  # empty, sorts first
    (root / "round-000001").mkdir()  # a checkpoint's name, but not one confront wrote
    (root / "round-000001" / "meta.json").write_text('{"format": "mine"}')
    (root / "round-000001" / "state.npz").write_bytes(b"x")
    stale = root / ".round-000003.abcd_123"  # a killed save's temporary folder
    stale.mkdir()
    (stale / "state.npz").write_bytes(b"half")
    _save(root, "round-000004", 2.0)
    _save(root, "round-000006", 3.0)
    assert (root / "best" / "notes.txt").read_text() == "n\n" and (root / ".git" / "HEAD").read_text() == "ref\n"
    assert (root / "aaa-mine").is_dir() and (root / "round-000001" / "meta.json").is_file()
    assert not stale.exists() and not (root / "round-000002").exists()
    assert (root / "round-000004").is_dir() and (root / "round-000006").is_dir()


def test_save_refuses_a_symlinked_checkpoints_folder_and_a_foreign_name(tmp_path: Path) -> None:
    """Issue 34 item 1: a checkpoints folder linked to a shared folder is not written into or pruned."""
    shared = tmp_path / "shared"
    (shared / "other").mkdir(parents=True)
    _save(shared, "round-000001", 1.0)  # another run's checkpoint there
    link = tmp_path / "checkpoints"
    link.symlink_to(shared)
    with pytest.raises(ck.CheckpointError, match="symbolic link"):
        _save(link, "round-000009", 2.0)
    assert sorted(p.name for p in shared.iterdir()) == ["LATEST", "other", "round-000001"]
    mine = tmp_path / "mine"
    (mine / "round-000003").mkdir(parents=True)
    (mine / "round-000003" / "keep.txt").write_text("k")
    with pytest.raises(ck.CheckpointError, match="not a checkpoint confront wrote"):
        _save(mine, "round-000003", 2.0)
    assert (mine / "round-000003" / "keep.txt").read_text() == "k"


def test_an_edited_generator_state_is_refused_and_reseeds_nothing() -> None:
    """Issue 34 item 13: a checkpoint's rng naming 'seed' called np.random.seed (NumPy's global generator)."""
    np.random.seed(5)
    expected = np.random.random()
    np.random.seed(5)
    good = ck.rng_state(np.random.default_rng(1))
    for bad in ({**good, "bit_generator": "seed"}, {**good, "bit_generator": "RandomState"},
                {**good, "state": {"state": "x", "inc": 1}}, {"bit_generator": "PCG64"}):
        with pytest.raises(ck.CheckpointError, match="generator"):
            ck.rng_from_state(bad)
    assert np.random.random() == expected
    assert ck.rng_from_state(good).random() == np.random.default_rng(1).random()
