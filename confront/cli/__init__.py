"""confront.cli"""

from __future__ import annotations

import os
import shlex
import shutil
import sys
from pathlib import Path


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
