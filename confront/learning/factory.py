"""Building learners by kind, copying them, and saving/loading them as data (``.npz``, no pickle)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from confront.checkpoint import write_npz
from confront.learning.base import Learner, params_from_dict
from confront.learning.dmnn import DMNN, DMNNParams
from confront.learning.fuzzy import FuzzyParams
from confront.learning.tabular import TabularParams, TabularQ
from confront.learning.transfer import Frozen, TransferParams, TransferPolicy
from confront.learning.uniform import UniformParams, UniformPolicy

__all__ = ["KINDS", "clone_learner", "load_learner", "make_learner", "save_learner", "transfer_from"]

_TD = {"exploration": "egreedy", "backup": "smdp", "bootstrap": "max", "alpha": 0.1, "exploit": 0.9}

# kind -> (parameter class, preset overriding the class defaults, constructor)
KINDS: dict[str, tuple[type, dict[str, Any], Callable[..., Learner]]] = {
    "ssaq": (TabularParams, {}, TabularQ),
    "qlearning_egreedy": (TabularParams, _TD, TabularQ),
    "qlearning_dgreedy": (TabularParams, {**_TD, "exploration": "degreedy"}, TabularQ),
    "dmnn": (DMNNParams, {"output_init": "zero"}, DMNN),  # Q = 0 at the start (docs/learning.md)
    "random": (UniformParams, {}, UniformPolicy),
}


def make_learner(kind: str, *, rng: np.random.Generator | None = None, fuzzy: dict[str, Any] | None = None,
                 **params: Any) -> Learner:
    """A new learner of ``kind`` (ssaq, qlearning_egreedy, qlearning_dgreedy, dmnn, random) with ``params`` overriding
    the kind's preset; ``fuzzy`` overrides the fuzzy rate's settings; ``rng`` initialises a network's weights."""
    if kind not in KINDS:
        raise ValueError(f"bad value kind={kind!r}: must be one of {', '.join(KINDS)}")
    cls, preset, ctor = KINDS[kind]
    p = params_from_dict(cls, {**preset, **params})
    fz = params_from_dict(FuzzyParams, fuzzy) if fuzzy else None  # type: ignore[arg-type]
    if ctor is DMNN:
        return DMNN(p, rng=rng, fuzzy=fz, kind=kind)  # type: ignore[arg-type]
    if ctor is UniformPolicy:
        return UniformPolicy(p, kind=kind)  # type: ignore[arg-type]
    return ctor(p, fuzzy=fz, kind=kind)


def _spec(learner: Learner) -> tuple[str, dict[str, Any], dict[str, Any] | None]:
    fz = getattr(learner, "_fuzzy", None)
    fuzzy = None
    if fz is not None:
        fuzzy = {k: list(v) if isinstance(v, tuple) else v for k, v in vars(fz.params).items()}
    return learner.kind, learner.params.to_dict(), fuzzy


def clone_learner(learner: Learner) -> Learner:
    """An independent copy with the same kind, parameters and state."""
    if isinstance(learner, Frozen):
        return Frozen(clone_learner(learner.inner))
    if isinstance(learner, TransferPolicy):
        raise ValueError("clone the TransferPolicy's current learner, not the wrapper")
    kind, params, fuzzy = _spec(learner)
    out = make_learner(kind, fuzzy=fuzzy, **params)
    out.load_state_dict({k: np.array(v, copy=True) for k, v in learner.state_dict().items()})
    return out


def transfer_from(source: Learner, params: TransferParams | None = None, warm_start: bool = True
                  ) -> TransferPolicy:
    """Start the next task of a curriculum: a copy of ``source`` keeps learning (or a fresh learner of the same
    kind when ``warm_start`` is False) while a frozen copy of ``source`` supplies prior actions (Eq. 34)."""
    src = source.current if isinstance(source, TransferPolicy) else source
    if isinstance(src, Frozen):
        src = src.inner
    if warm_start:
        current = clone_learner(src)
    else:
        kind, p, fuzzy = _spec(src)
        current = make_learner(kind, fuzzy=fuzzy, **p)
    return TransferPolicy(current, Frozen(clone_learner(src)), params)


def save_learner(path: str | Path, learner: Learner) -> Path:
    """Write kind, parameters (JSON text) and state arrays to one ``.npz`` (no pickled objects), atomically."""
    frozen = isinstance(learner, Frozen)
    inner = learner.inner if isinstance(learner, Frozen) else learner
    if isinstance(inner, TransferPolicy):
        inner = inner.current
    kind, params, fuzzy = _spec(inner)
    meta = json.dumps({"kind": kind, "params": params, "fuzzy": fuzzy, "frozen": frozen})
    state = inner.state_dict()
    if "__meta__" in state:
        raise ValueError("state key '__meta__' is reserved")
    out = Path(path)
    write_npz(out, {"__meta__": np.array(meta), **state})
    return out


def load_learner(path: str | Path, frozen: bool | None = None) -> Learner:
    """Read a learner saved by :func:`save_learner`; ``frozen`` overrides whether it keeps learning. A file whose
    metadata does not fit its arrays (say hidden layers far larger than the weights it holds), or whose arrays
    hold NaN or infinite values, is a ValueError: nothing is allocated for it, nothing plays it."""
    with np.load(path, allow_pickle=False) as data:
        meta = json.loads(str(data["__meta__"]))
        state = {k: data[k] for k in data.files if k != "__meta__"}
    if not isinstance(meta, dict) or not isinstance(meta.get("params"), dict) or not isinstance(meta.get("kind"), str):
        raise ValueError("its metadata is not a learner's (kind, params)")
    hidden = meta["params"].get("hidden")
    if isinstance(hidden, list) and all(isinstance(h, int) for h in hidden):
        weights = sum(a * b for a, b in zip(hidden, hidden[1:], strict=False)) + sum(hidden)
        if weights > sum(a.size for a in state.values()):  # the arrays could not hold such layers
            raise ValueError(f"hidden layers {str(hidden)[:60]} do not fit the {len(state)} arrays it holds")
    bad = [k for k, a in state.items() if a.dtype.kind in "fc" and not np.all(np.isfinite(a))]
    if bad:
        raise ValueError(f"its arrays {', '.join(bad[:5])} hold NaN or infinite values")
    learner = make_learner(meta["kind"], fuzzy=meta["fuzzy"], **meta["params"])
    learner.load_state_dict(state)
    if frozen if frozen is not None else meta["frozen"]:
        return Frozen(learner)
    return learner
