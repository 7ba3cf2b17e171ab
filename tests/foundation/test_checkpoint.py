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
