"""Output files that never write through a symbolic link: figures go to memory first, then to their path by
:func:`confront.checkpoint.write_atomic` (a temporary file renamed over the path, so a link there is replaced,
not followed)."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

from confront.checkpoint import write_atomic

FIGURE_FORMATS = ("png", "pdf", "svg", "jpg", "jpeg", "eps", "ps", "tif", "tiff", "webp")


def figure_path(path: str | Path, option: str = "--out") -> Path:
    """``path`` checked as a figure's file: not a folder, and a suffix naming a format matplotlib writes."""
    p = Path(path)
    if p.is_dir():
        raise IsADirectoryError(f"{option} {p} is a folder: give a file name such as {p / 'figure.png'}")
    fmt = p.suffix.lower().lstrip(".")
    if fmt not in FIGURE_FORMATS:
        raise ValueError(f"{option} {p} must end in one of {', '.join('.' + f for f in FIGURE_FORMATS)}")
    return p


def save_figure(fig: Any, path: str | Path, **kwargs: Any) -> Path:
    """``fig.savefig`` into ``path`` (its format from the suffix) atomically, replacing a link rather than
    following it."""
    p = figure_path(path)
    buf = io.BytesIO()
    fig.savefig(buf, format=p.suffix.lower().lstrip("."), **kwargs)
    write_atomic(p, buf.getvalue())
    return p
