"""Data-only checkpoints: a folder with ``state.npz`` (arrays) and ``meta.json`` (format version, counters,
RNG states, the arrays' SHA-256), written atomically and verified on load. Never pickle.

Layout inside a run folder::

    checkpoints/
      round-000120/state.npz, meta.json
      LATEST            # name of the newest complete checkpoint, replaced atomically
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

FORMAT = "confront-checkpoint"
FORMAT_VERSION = 1


class CheckpointError(RuntimeError):
    """A checkpoint is missing, truncated, corrupt or of another format version."""


def rng_state(rng: np.random.Generator) -> dict[str, Any]:
    """A Generator's full state as JSON-ready data."""
    return rng.bit_generator.state


def rng_from_state(state: Mapping[str, Any]) -> np.random.Generator:
    """Rebuild a Generator from :func:`rng_state` output."""
    bit_gen = getattr(np.random, state["bit_generator"])()
    bit_gen.state = dict(state)
    return np.random.Generator(bit_gen)


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename, so readers see old or new, never half."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
        _fsync_dir(path.parent)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def save(directory: str | Path, name: str, arrays: Mapping[str, np.ndarray], meta: Mapping[str, Any],
         keep: int = 2) -> Path:
    """Save a checkpoint ``directory/name`` atomically, point ``LATEST`` at it and keep the newest ``keep``."""
    root = Path(directory)
    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=root, prefix=f".{name}."))
    try:
        npz = tmp / "state.npz"
        with npz.open("wb") as fh:
            np.savez(fh, **{k: np.asarray(v) for k, v in arrays.items()})
            fh.flush()
            os.fsync(fh.fileno())
        full_meta = {"format": FORMAT, "format_version": FORMAT_VERSION, "sha256": _sha256(npz), **meta}
        write_atomic(tmp / "meta.json", json.dumps(full_meta, indent=1, sort_keys=True).encode())
        final = root / name
        if final.exists():
            shutil.rmtree(final)
        os.replace(tmp, final)
        _fsync_dir(root)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    write_atomic(root / "LATEST", (name + "\n").encode())
    complete = sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))
    for old in complete[:-keep] if keep > 0 else []:
        if old.name != name:
            shutil.rmtree(old, ignore_errors=True)
    for stale in root.glob(".*"):  # leftovers of a save that was killed
        if stale.is_dir():
            shutil.rmtree(stale, ignore_errors=True)
    return final


def latest(directory: str | Path) -> Path | None:
    """The newest complete checkpoint in ``directory`` (by ``LATEST``), or None if there is none."""
    root = Path(directory)
    pointer = root / "LATEST"
    if not pointer.exists():
        return None
    name = pointer.read_text().strip()
    if not name or "/" in name or name.startswith("."):
        raise CheckpointError(f"checkpoint pointer {pointer} is corrupt ({name!r})")
    return root / name


def load(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Load and verify a checkpoint folder; raise CheckpointError naming what is wrong."""
    p = Path(path)
    meta_path, npz_path = p / "meta.json", p / "state.npz"
    if not meta_path.exists() or not npz_path.exists():
        raise CheckpointError(f"checkpoint {p} is incomplete: it needs meta.json and state.npz")
    try:
        meta = json.loads(meta_path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise CheckpointError(f"checkpoint {p} has a corrupt meta.json ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise CheckpointError(f"{p} is not a confront checkpoint")
    if meta.get("format_version") != FORMAT_VERSION:
        raise CheckpointError(
            f"checkpoint {p} has format version {meta.get('format_version')!r}; "
            f"this confront reads version {FORMAT_VERSION}"
        )
    if _sha256(npz_path) != meta.get("sha256"):
        raise CheckpointError(f"checkpoint {p} is corrupt or truncated: state.npz does not match its checksum")
    try:
        with np.load(npz_path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise CheckpointError(f"checkpoint {p} cannot be read: {exc}") from None
    return arrays, meta
