"""numba's on-disk cache for the arena kernels, and the kernels compiled ahead of time that ship with confront.

:func:`install` gives the cached numba functions (``@njit(cache=True)``) of the kernel modules
(:data:`KERNEL_MODULES`) a :class:`KernelCache`, numba's cache with two changes:

- The source stamp of every kernel is one digest of all kernel module files, not its own file's: numba stores a
  caller with its callees compiled in (``smdp_turns`` holds the turn of ``kernels.py``, the bots of
  ``bots/`` and the technique robots of ``tech.py``), so an entry stamped with its own file alone would run old
  code after a callee's module changed.
- On a miss, the kernel is looked up in ``prebuilt/<PREBUILT>/``: numba's cache files of the kernels Python
  calls, compiled by ``scripts/build_kernels.py`` for the x86-64-v3 CPU level (AVX2, FMA, BMI2; the same
  operations in the same order as the host's code: no fast-math, no fused multiply-add, so the same results bit
  for bit), read by numba's own cache reader. They are used when the sources' digest, numba, Python and the
  platform match the folder's and the CPU has the level's features; first use then loads the kernels instead of
  compiling them (docs/arena.md, "First-use compile time"). ``CONFRONT_PREBUILT_KERNELS=0`` (or false, no,
  off) turns them off (numba then compiles for this CPU and caches as usual).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numba
from numba.core.caching import CompileResultCacheImpl, FunctionCache, IndexDataCacheFile
from numba.core.dispatcher import Dispatcher

__all__ = ["KERNEL_MODULES", "TARGET_CPU", "PREBUILT", "KernelCache", "install", "sources_digest", "prebuilt_dir",
           "entry"]

HERE = Path(__file__).resolve().parent
# the modules whose code is compiled into the kernels (functions, and the constants they read); every module of
# bots/ (the controller and one per robot)
KERNEL_MODULES = ("rules", "state", "kernels", *(f"bots.{p.stem}" for p in sorted((HERE / "bots").glob("*.py"))),
                  "observe", "tank", "strictmath", "tech", "smdp_kernel")
TARGET_CPU = "x86-64-v3"
# LLVM's names of the x86-64-v2 and -v3 features (the x86-64 psABI levels)
TARGET_FEATURES = ("cx16", "popcnt", "sahf", "sse3", "sse4.1", "sse4.2", "ssse3", "avx", "avx2", "bmi", "bmi2",
                   "f16c", "fma", "lzcnt", "movbe", "xsave")
PREBUILT = (f"numba-{numba.__version__}-py{sys.version_info[0]}{sys.version_info[1]}-{sys.platform}-"
            f"{platform.machine()}-{TARGET_CPU}")
OFF_ENV = "CONFRONT_PREBUILT_KERNELS"


@functools.cache
def sources_digest() -> str:
    """sha256 of the kernel module files (the source stamp of every kernel's cache entries)."""
    h = hashlib.sha256()
    for name in KERNEL_MODULES:
        h.update(name.encode())
        h.update((HERE / f"{name.replace('.', '/')}.py").read_bytes())
    return h.hexdigest()


@functools.cache
def prebuilt_dir() -> Path | None:
    """The folder of shipped kernels if it can serve this process, else None (then numba compiles)."""
    path = HERE / "prebuilt" / PREBUILT
    if os.environ.get(OFF_ENV, "1").strip().lower() in ("0", "false", "no", "off") or not path.is_dir():
        return None
    from numba.core import config
    from numba.core.codegen import get_host_cpu_features

    if config.CPU_NAME is not None or config.CPU_FEATURES is not None:  # type: ignore[attr-defined]
        return None  # the user chose the code's target CPU
    host = {f[1:] for f in get_host_cpu_features().split(",") if f.startswith("+")}
    if not host.issuperset(TARGET_FEATURES):
        return None
    try:
        meta = json.loads((path / "manifest.json").read_text())
    except (OSError, ValueError):
        return None
    return path if meta.get("sources") == sources_digest() else None


class _Stamped:
    """A numba cache locator whose source stamp is :func:`sources_digest`."""

    def __init__(self, locator: Any) -> None:
        self._locator = locator

    def __getattr__(self, name: str) -> Any:
        return getattr(self._locator, name)

    def get_source_stamp(self) -> str:
        return sources_digest()


class _KernelCacheImpl(CompileResultCacheImpl):
    def __init__(self, py_func: Any) -> None:
        super().__init__(py_func)
        self._locator = _Stamped(self._locator)


class KernelCache(FunctionCache):
    """numba's cache of compiled functions, stamped with all kernel sources, backed by the shipped kernels."""

    _impl_class = _KernelCacheImpl

    def _load_overload(self, sig: Any, target_context: Any) -> Any:
        data = super()._load_overload(sig, target_context)
        if data is None and self._enabled:
            data = self._load_prebuilt(sig, target_context)
        return data

    def _load_prebuilt(self, sig: Any, target_context: Any) -> Any:
        """The shipped entry for ``sig``, or None. Entries are keyed like numba's own, for the folder's CPU level:
        its code runs on every CPU that has the level's features."""
        path = prebuilt_dir()
        if path is None:
            return None
        sig_key, magic, code_key = self._index_key(sig, target_context.codegen())
        shipped = IndexDataCacheFile(str(path), self._impl.filename_base, sources_digest())
        try:  # numba's reader: checks numba's version and the source stamp; None when the kernel is not there
            data = shipped.load((sig_key, (magic[0], TARGET_CPU, ""), code_key))
            return None if data is None else self._impl.rebuild(target_context, data)
        except Exception:  # noqa: BLE001 - a damaged file: compile instead
            return None


def install(namespace: dict[str, Any]) -> None:
    """Give the cached numba functions defined so far in a kernel module (its ``globals()``) a :class:`KernelCache`
    (call it at the module's end, and before anything there compiles them)."""
    module = namespace["__name__"]
    for obj in list(namespace.values()):
        cache = getattr(obj, "_cache", None)  # numba's private cache slot of a Dispatcher
        if isinstance(obj, Dispatcher) and obj.py_func.__module__ == module and isinstance(cache, FunctionCache) \
                and not isinstance(cache, KernelCache):
            obj._cache = KernelCache(obj.py_func)  # type: ignore[attr-defined]


def entry(kernel: Dispatcher, *args: Any) -> Callable[..., Any]:
    """The compiled code of ``kernel`` for the types of ``args`` (loaded from the cache or compiled now), to call
    without numba's type dispatch, which works out the types of NamedTuple bundles in Python (microseconds a call).
    Every later call must pass arguments of the same types (the same arrays' dtypes, dimensions and layouts)."""
    return kernel.compile(tuple(numba.typeof(a) for a in args))
