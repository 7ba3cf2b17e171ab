"""Run folders: where every training run writes what it did.

    <run>/config.toml          the fully resolved config (re-runnable with ``confront train -c``)
    <run>/metrics/rounds.csv   one row per round (and .parquet when pyarrow is installed)
    <run>/metrics/sessions.csv one row per session of rounds
    <run>/plots/*.png          figures
    <run>/checkpoints/         data-only checkpoints (see confront.checkpoint)
    <run>/replays/             optional battle replays
    <run>/summary.json         headline numbers, wall time, versions
    <run>/.lock                while a run writes the folder (see :class:`RunLock`)

One run at a time writes a run folder: :meth:`Run.create` (with ``lock``) and :meth:`Run.open` hold an exclusive
``flock`` on ``<run>/.lock`` until :meth:`Run.release`; a second run is refused with :class:`RunBusyError`. The
kernel drops the lock when its process dies, so a lock file left by a killed run never blocks.
"""

from __future__ import annotations

import csv
import errno
import fcntl
import io
import json
import math
import os
import shlex
import shutil
import sys
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
LOCK = ".lock"


class Interrupted(Exception):
    """Training stopped on request (Ctrl-C) after saving a checkpoint of the step it had finished."""

    def __init__(self, run: Path, rounds_done: int, checkpoint: Path) -> None:
        super().__init__(f"stopped after {rounds_done} rounds; saved {checkpoint}")
        self.run, self.rounds_done, self.checkpoint = run, rounds_done, checkpoint


class RunBusyError(FileExistsError):
    """Another run (a live process) holds the run folder's lock."""


class RunLock:
    """An exclusive ``flock`` on ``<folder>/.lock``, holding the writer's process id (for the message)."""

    def __init__(self, folder: Path) -> None:
        self.path = folder / LOCK
        self.fd: int | None = None
        while self.fd is None:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                holder = os.pread(fd, 32, 0).decode(errors="replace").strip()
                os.close(fd)
                if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise
                who = f"process {holder}" if holder.isdigit() else "another process"
                raise RunBusyError(f"run folder {folder} is being written by another run ({who}): wait until it "
                                   "ends or give another folder") from None
            try:  # the previous holder may have removed the file between our open and our lock: then again
                same = os.stat(self.path, follow_symlinks=False).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if not same:
                os.close(fd)
                continue
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
            self.fd = fd

    def release(self) -> None:
        """Remove the lock file and drop the lock (removed first, so nobody locks a file that is going away)."""
        if self.fd is None:
            return
        try:
            self.path.unlink(missing_ok=True)
        finally:
            os.close(self.fd)
            self.fd = None


def _check_subfolders(p: Path) -> None:
    """A run writes into its own sub-folders only: one that is a symbolic link (or a file) is refused."""
    for sub in SUBDIRS:
        if (p / sub).is_symlink() or ((p / sub).exists() and not (p / sub).is_dir()):
            raise FileExistsError(f"{p / sub} is a symbolic link or a file: a run writes only into real "
                                  "folders of its own (replace it by a folder)")


def _entries(p: Path) -> list[str]:
    """What a folder holds besides a run's lock file."""
    return [e.name for e in p.iterdir() if e.name != LOCK]


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
    """A run folder. ``new``: :meth:`create` made the folder (so a failed start may remove it again); ``lock``:
    the run's hold on the folder (:class:`RunLock`), dropped by :meth:`release`."""

    path: Path
    new: bool = field(default=False, compare=False)
    lock: RunLock | None = field(default=None, compare=False, repr=False)

    @classmethod
    def create(cls, path: str | Path, config: Mapping[str, Any] | None = None, exist_ok: bool = False,
               lock: bool = False) -> Run:
        """Make the folder (and its sub-folders); write the resolved config if given. With ``lock``, hold the
        folder's lock (:class:`RunBusyError` if another run holds it) until :meth:`release`."""
        p = Path(path)
        if p.exists() and not p.is_dir():
            raise FileExistsError(f"run folder {p} is an existing file; pick another --out")
        if p.exists() and _entries(p) and not exist_ok:
            raise FileExistsError(f"run folder {p} already exists; pick another --out or use --resume")
        text = to_toml(config).encode() if config is not None else None  # a value TOML cannot hold fails here
        try:
            p.mkdir(parents=True)
            new = True  # made here, by this run alone (mkdir is atomic): a failed start may remove it
        except FileExistsError:
            new = False
        try:
            held = RunLock(p) if lock else None
        except BaseException:
            if new:
                p.rmdir()
            raise
        run = cls(p, new=new, lock=held)
        try:
            if not new and _entries(p) and not exist_ok:  # another run got here first
                raise FileExistsError(f"run folder {p} already exists; pick another --out or use --resume")
            _check_subfolders(p)
            for sub in SUBDIRS:
                (p / sub).mkdir(parents=True, exist_ok=True)
            if text is not None:
                write_atomic(p / "config.toml", text)
        except BaseException:
            run.discard_if_new()
            raise
        return run

    @classmethod
    def open(cls, path: str | Path) -> Run:
        """An existing run folder, locked for this run (to continue it): :class:`RunBusyError` if another run
        holds it."""
        p = Path(path)
        run = cls(p, lock=RunLock(p))
        try:
            _check_subfolders(p)
        except BaseException:
            run.release()
            raise
        return run

    def release(self) -> None:
        """Drop the folder's lock (if this run holds it)."""
        if self.lock is not None:
            self.lock.release()

    def discard_if_new(self) -> None:
        """Remove the folder if :meth:`create` made it (after a failed start); an older folder is left alone.
        Drops the lock either way."""
        self.release()
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


def command() -> str:
    """How this confront was started, to repeat in hints: ``confront`` when that is what PATH finds, else the path
    that was typed (``.venv/bin/confront``), else ``python -m confront.cli.main`` with this interpreter."""
    argv0 = sys.argv[0] if sys.argv else ""
    if Path(argv0).name == "confront":
        found = shutil.which("confront")
        if found is not None and Path(found).resolve() == Path(argv0).resolve():
            return "confront"
        return shlex.quote(argv0)
    python = os.path.relpath(sys.executable) if not os.path.relpath(sys.executable).startswith("..") \
        else sys.executable
    return f"{shlex.quote(python)} -m confront.cli.main"
