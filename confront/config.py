"""Typed configuration: dataclasses validated at the edge, loaded from TOML, overridden by ``a.b=v``.

A config class is a dataclass whose fields may carry bounds with :func:`field`::

    @dataclass
    class Train:
        rounds: int = field(500, ge=1)
        mode: str = field("fast", choices=("fast", "exact"))

:func:`from_dict` builds one from plain data and raises :class:`ConfigError` with a one-line message
naming the key, the value and what is allowed; :func:`to_dict` turns it back into TOML-ready data.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
import types
import typing
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")
MAX_STRING = 4096  # characters of a string value
MAX_FILE = 1 << 20  # bytes of a config or scenario file (the largest packaged one has about 2 KB)


class ConfigError(ValueError):
    """A user's config is wrong; the message is one line, fit to print without a traceback."""


def field(
    default: Any = dataclasses.MISSING,
    *,
    ge: float | None = None,
    gt: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    choices: Sequence[Any] | None = None,
    default_factory: Any = dataclasses.MISSING,
    doc: str = "",
) -> Any:
    """A dataclass field with bounds (``ge``/``gt``/``le``/``lt``) or allowed ``choices``, checked on load."""
    meta = {"ge": ge, "gt": gt, "le": le, "lt": lt, "choices": tuple(choices) if choices else None, "doc": doc}
    if default_factory is not dataclasses.MISSING:
        return dataclasses.field(default_factory=default_factory, metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def _show(value: Any) -> str:
    """``repr(value)`` for a message: at most 80 characters."""
    try:
        text = repr(value)
    except ValueError:  # an integer beyond Python's digit limit
        return f"<an integer of {value.bit_length()} bits>"
    return text if len(text) <= 80 else text[:77] + "..."


def _allowed(meta: Mapping[str, Any]) -> str:
    if meta.get("choices"):
        return "one of " + ", ".join(repr(c) for c in meta["choices"])
    parts = []
    for key, sym in (("ge", ">="), ("gt", ">"), ("le", "<="), ("lt", "<")):
        if meta.get(key) is not None:
            parts.append(f"{sym} {meta[key]}")
    return " and ".join(parts)


def _check_bounds(key: str, value: Any, meta: Mapping[str, Any]) -> None:
    if isinstance(value, tuple | list):  # bounds of a list field apply to each item
        for i, item in enumerate(value):
            _check_bounds(f"{key}[{i}]", item, meta)
        return
    choices = meta.get("choices")
    if choices and value not in choices:
        raise ConfigError(f"{key} = {_show(value)} is not allowed: use {_allowed(meta)}")
    if isinstance(value, int | float) and not isinstance(value, bool):
        bad = (
            (meta.get("ge") is not None and not value >= meta["ge"])
            or (meta.get("gt") is not None and not value > meta["gt"])
            or (meta.get("le") is not None and not value <= meta["le"])
            or (meta.get("lt") is not None and not value < meta["lt"])
            or (isinstance(value, float) and math.isnan(value))
        )
        if bad:
            raise ConfigError(f"{key} = {_show(value)} is out of range: must be {_allowed(meta)}")
        if isinstance(value, int) and not -(2**63) <= value < 2**63:
            raise ConfigError(f"{key} = {_show(value)} is out of range: must fit in 64 bits")


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", str(tp)).replace("typing.", "")


def _coerce(key: str, value: Any, tp: Any) -> Any:
    """Check ``value`` against the annotation ``tp`` and convert what is safe (int -> float, list -> tuple)."""
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if tp is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        for arg in (a for a in args if a is not type(None)):
            try:
                return _coerce(key, value, arg)
            except ConfigError as exc:
                errors.append(str(exc))
        allowed = " or ".join(_type_name(a) for a in args)
        raise ConfigError(f"{key} = {_show(value)} has the wrong type: expected {allowed}")
    if origin is typing.Literal:
        if isinstance(value, bool) and str(value).lower() in args:  # --set k=true parses as a bool
            return str(value).lower()
        if value not in args:
            raise ConfigError(f"{key} = {_show(value)} is not allowed: use one of {', '.join(map(repr, args))}")
        return value
    if origin in (tuple, list, Sequence) or tp in (tuple, list):
        if isinstance(value, str) or not isinstance(value, Sequence):
            raise ConfigError(f"{key} = {_show(value)} has the wrong type: expected a list")
        if args and origin is tuple and len(args) == 2 and args[1] is Ellipsis:
            items = [_coerce(f"{key}[{i}]", v, args[0]) for i, v in enumerate(value)]
        elif args and origin is tuple:
            if len(args) != len(value):
                raise ConfigError(f"{key} = {_show(value)} must have {len(args)} items")
            items = [_coerce(f"{key}[{i}]", v, a) for i, (v, a) in enumerate(zip(value, args, strict=True))]
        elif args:
            items = [_coerce(f"{key}[{i}]", v, args[0]) for i, v in enumerate(value)]
        else:
            items = list(value)
        return tuple(items) if origin is tuple or tp is tuple else items
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        if not isinstance(value, Mapping):
            raise ConfigError(f"{key} = {_show(value)} has the wrong type: expected a table of {_type_name(tp)} keys")
        return from_dict(tp, value, prefix=key)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"{key} = {_show(value)} has the wrong type: expected a number")
        if isinstance(value, int) and abs(value) > 2**1000 or not math.isfinite(value):
            raise ConfigError(f"{key} = {_show(value)} is out of range: must be a finite number")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{key} = {_show(value)} has the wrong type: expected an integer")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{key} = {_show(value)} has the wrong type: expected true or false")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{key} = {_show(value)} has the wrong type: expected a string")
        if len(value) > MAX_STRING or any(ord(c) < 32 and c != "\t" or c == "\x7f" for c in value):
            raise ConfigError(f"{key} = {_show(value)} is not allowed: use at most {MAX_STRING} printable "
                              "characters on one line")
        return value
    if isinstance(tp, type) and not isinstance(value, tp):
        raise ConfigError(f"{key} = {_show(value)} has the wrong type: expected {_type_name(tp)}")
    return value


def from_dict(cls: type[T], data: Mapping[str, Any], prefix: str = "") -> T:
    """Build the dataclass ``cls`` from plain data, validating every key, type and range."""
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    kwargs: dict[str, Any] = {}
    for key, value in data.items():
        full = f"{prefix}.{key}" if prefix else key
        if key not in fields:
            raise ConfigError(f"unknown key {full!r}: allowed keys here are {', '.join(sorted(fields))}")
        value = _coerce(full, value, hints[key])
        _check_bounds(full, value, fields[key].metadata)
        kwargs[key] = value
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:  # a class's own __post_init__ check
        msg = str(exc).splitlines()[0]
        where = f" in {prefix}" if prefix and f"{prefix}." not in msg else ""
        raise ConfigError(f"{msg}{where}") from None


def to_dict(obj: Any) -> dict[str, Any]:
    """A config dataclass as plain TOML-ready data (tuples become lists, ``None`` values are dropped)."""

    def plain(v: Any) -> Any:
        if dataclasses.is_dataclass(v) and not isinstance(v, type):
            return {f.name: plain(getattr(v, f.name)) for f in dataclasses.fields(v) if getattr(v, f.name) is not None}
        if isinstance(v, tuple | list):
            return [plain(x) for x in v]
        if isinstance(v, Mapping):
            return {k: plain(x) for k, x in v.items()}
        return v

    return plain(obj)


def merge(base: Mapping[str, Any], update: Mapping[str, Any]) -> dict[str, Any]:
    """Deep-merge two plain config tables (``update`` wins)."""
    out = dict(base)
    for k, v in update.items():
        out[k] = merge(out[k], v) if isinstance(v, Mapping) and isinstance(out.get(k), Mapping) else v
    return out


def parse_override(text: str) -> dict[str, Any]:
    """``"learner.alpha=0.2"`` -> ``{"learner": {"alpha": 0.2}}``; the value is read as TOML, else as a string."""
    if "=" not in text:
        raise ConfigError(f"--set {text!r} must look like key.path=value")
    key, raw = (s.strip() for s in text.split("=", 1))
    if not key or any(not part for part in key.split(".")):
        raise ConfigError(f"--set {text!r} has an empty key")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except (tomllib.TOMLDecodeError, RecursionError):
        value = raw
    except ValueError:  # e.g. an integer of more than 4300 digits
        raise ConfigError(f"--set {key} = {_show(raw)} cannot be read: numbers have at most 4300 digits") from None
    out: dict[str, Any] = {}
    node = out
    parts = key.split(".")
    for part in parts[:-1]:
        node = node.setdefault(part, {})
    node[parts[-1]] = value
    return out


def _short(p: Path) -> str:
    text = repr(str(p))
    return text if len(text) <= 120 else text[:58] + "..." + text[-58:]


def load_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file of at most ``MAX_FILE`` bytes; a missing, malformed or larger file is a ConfigError."""
    p = Path(path)
    try:
        with p.open("rb") as fh:
            raw = fh.read(MAX_FILE + 1)  # a bounded read: /dev/zero or a huge file is refused, not loaded
        if len(raw) > MAX_FILE:
            raise ConfigError(f"config file {_short(p)} is larger than {MAX_FILE >> 20} MB: give a TOML config")
        return tomllib.loads(raw.decode("utf-8"))
    except ConfigError:
        raise
    except FileNotFoundError:
        raise ConfigError(f"config file {_short(p)} does not exist") from None
    except IsADirectoryError:
        raise ConfigError(f"config file {_short(p)} is a folder: give a TOML file") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config file {_short(p)} is not valid TOML: {str(exc).splitlines()[0]}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"config file {_short(p)} is not valid TOML: it is not UTF-8 text") from None
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise ConfigError(f"config file {_short(p)} cannot be read: {str(exc).splitlines()[0][:120]}") from None
    except RecursionError:
        raise ConfigError(f"config file {_short(p)} is nested too deeply") from None
    except OSError as exc:
        raise ConfigError(f"config file {_short(p)} cannot be read: {exc.strerror}") from None


_ESCAPES = {'"': '\\"', "\\": "\\\\", "\n": "\\n", "\t": "\\t", "\r": "\\r", "\b": "\\b", "\f": "\\f"}


def toml_string(v: str) -> str:
    """``v`` as a TOML basic string: quotes, backslashes and control characters escaped (a newline in a name
    cannot break the file); a lone surrogate, which no TOML file can hold, is a ConfigError."""
    out = []
    for c in v:
        if c in _ESCAPES:
            out.append(_ESCAPES[c])
        elif ord(c) < 32 or ord(c) == 127:
            out.append(f"\\u{ord(c):04x}")
        elif 0xD800 <= ord(c) <= 0xDFFF:
            raise ConfigError(f"{v[:60]!r} holds a lone surrogate (not Unicode text)")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def toml_key(k: str) -> str:
    """A TOML key: bare when it can be, quoted otherwise."""
    return k if k and all(c.isascii() and (c.isalnum() or c in "_-") for c in k) else toml_string(k)


def to_toml(data: Mapping[str, Any]) -> str:
    """Write plain config data as TOML (tables after scalar keys)."""
    lines: list[str] = []

    def scalar(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return toml_string(v)
        if isinstance(v, float):
            return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf" if v < 0 else "nan")
        if isinstance(v, list | tuple):
            return "[" + ", ".join(scalar(x) for x in v) + "]"
        if isinstance(v, Mapping):
            return "{ " + ", ".join(f"{toml_key(k)} = {scalar(x)}" for k, x in v.items()) + " }"
        return str(v)

    def table(name: str, node: Mapping[str, Any]) -> None:
        plain = {k: v for k, v in node.items() if not isinstance(v, Mapping)}
        subs = {k: v for k, v in node.items() if isinstance(v, Mapping)}
        if name and (plain or not subs):
            lines.append(f"\n[{name}]")
        lines.extend(f"{toml_key(k)} = {scalar(v)}" for k, v in plain.items())
        for k, v in subs.items():
            table(f"{name}.{toml_key(k)}" if name else toml_key(k), v)

    table("", data)
    return "\n".join(lines).lstrip("\n") + "\n"
