"""Run folders: where every training run writes what it did.

    <run>/config.toml          the fully resolved config (re-runnable with ``confront train -c``)
    <run>/metrics/rounds.csv   one row per round (and .parquet when pyarrow is installed)
    <run>/metrics/sessions.csv one row per session of rounds
    <run>/plots/*.png          figures
    <run>/checkpoints/         data-only checkpoints (see confront.checkpoint)
    <run>/replays/             optional battle replays
    <run>/summary.json         headline numbers, wall time, versions
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import shutil
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from confront.checkpoint import write_atomic
from confront.config import to_toml

try:  # Parquet is written when pyarrow is present (extra `confront[parquet]`); CSV always.
    import pyarrow as pa
    import pyarrow.parquet as pq
except ImportError:  # pragma: no cover - exercised on installs without the extra
    pa = None
    pq = None

SUBDIRS = ("metrics", "plots", "checkpoints", "replays")


def new_run_name(prefix: str) -> str:
    """A sortable, unique-enough run name: ``<prefix>-YYYYmmdd-HHMMSS``."""
    return f"{prefix}-{time.strftime('%Y%m%d-%H%M%S')}"


def _json_default(v: Any) -> Any:
    if hasattr(v, "item"):
        return v.item()
    if hasattr(v, "tolist"):
        return v.tolist()
    raise TypeError(f"cannot write {type(v).__name__} as JSON")


def _clean(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def _columns(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """Every key of the rows, in order of first appearance."""
    return list(dict.fromkeys(k for row in rows for k in row))


def _csv(rows: Sequence[Mapping[str, Any]], columns: list[str], header: bool) -> bytes:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    if header:
        writer.writeheader()
    for row in rows:
        writer.writerow({k: _clean(row.get(k)) for k in columns})
    return buf.getvalue().encode()


@dataclass(frozen=True)
class Run:
    """A run folder. ``new``: :meth:`create` made the folder (so a failed start may remove it again)."""

    path: Path
    new: bool = field(default=False, compare=False)

    @classmethod
    def create(cls, path: str | Path, config: Mapping[str, Any] | None = None, exist_ok: bool = False) -> Run:
        """Make the folder (and its sub-folders); write the resolved config if given."""
        p = Path(path)
        if p.exists() and not p.is_dir():
            raise FileExistsError(f"run folder {p} is an existing file; pick another --out")
        if p.exists() and any(p.iterdir()) and not exist_ok:
            raise FileExistsError(f"run folder {p} already exists; pick another --out or use --resume")
        text = to_toml(config).encode() if config is not None else None  # a value TOML cannot hold fails here
        run = cls(p, new=not p.exists())
        try:
            for sub in SUBDIRS:
                (p / sub).mkdir(parents=True, exist_ok=True)
            if text is not None:
                write_atomic(p / "config.toml", text)
        except BaseException:
            run.discard_if_new()
            raise
        return run

    def discard_if_new(self) -> None:
        """Remove the folder if :meth:`create` made it (after a failed start); an older folder is left alone."""
        if self.new:
            shutil.rmtree(self.path, ignore_errors=True)

    @property
    def checkpoints(self) -> Path:
        return self.path / "checkpoints"

    @property
    def plots(self) -> Path:
        return self.path / "plots"

    @property
    def replays(self) -> Path:
        return self.path / "replays"

    def write_table(self, name: str, rows: Sequence[Mapping[str, Any]]) -> list[Path]:
        """Write ``metrics/<name>.csv`` (and ``.parquet``) atomically from a list of flat dict rows."""
        out = self.path / "metrics"
        out.mkdir(parents=True, exist_ok=True)
        columns = _columns(rows)
        written = [out / f"{name}.csv"]
        write_atomic(written[0], _csv(rows, columns, header=True))
        if pa is not None and rows:
            table = pa.table({c: [_clean(r.get(c)) for r in rows] for c in columns})
            sink = pa.BufferOutputStream()
            pq.write_table(table, sink)
            written.append(out / f"{name}.parquet")
            write_atomic(written[1], sink.getvalue().to_pybytes())
        return written

    def append_table(self, name: str, rows: Sequence[Mapping[str, Any]], written: int) -> int:
        """Bring ``metrics/<name>.csv``, which holds the first ``written`` of ``rows``, up to all of them by
        appending the rest (CSV only; :meth:`write_table` writes the whole table, and the Parquet file). With
        ``written`` 0, or new rows whose columns are not the file's, the CSV is rewritten whole (atomically).
        Returns ``len(rows)``. What a run's checkpoints call: the cost grows with the new rows, not the run."""
        path = self.path / "metrics" / f"{name}.csv"
        new = rows[written:]
        header: list[str] = []
        if written > 0 and path.is_file():
            with path.open(newline="") as fh:
                header = next(csv.reader(fh), [])
        if not header or any(list(r) != header for r in new):
            write_atomic(path, _csv(rows, _columns(rows), header=True))
        elif new:
            with path.open("ab") as fh:
                fh.write(_csv(new, header, header=False))
                fh.flush()
                os.fsync(fh.fileno())
        return len(rows)

    def read_table(self, name: str) -> list[dict[str, Any]]:
        """Read ``metrics/<name>.csv`` back as rows of floats (ints where integral) and strings."""

        def parse(v: str) -> Any:
            if v == "":
                return None
            try:
                f = float(v)
            except ValueError:
                return v
            return int(f) if f.is_integer() and "." not in v and "e" not in v.lower() else f

        with (self.path / "metrics" / f"{name}.csv").open() as fh:
            return [{k: parse(v) for k, v in row.items()} for row in csv.DictReader(fh)]

    def write_json(self, name: str, data: Mapping[str, Any]) -> Path:
        """Write ``<run>/<name>`` as JSON atomically."""
        path = self.path / name
        write_atomic(path, json.dumps(data, indent=2, default=_json_default, sort_keys=True).encode())
        return path

    def write_summary(self, data: Mapping[str, Any]) -> Path:
        return self.write_json("summary.json", data)
