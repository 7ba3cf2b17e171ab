"""Config validation: every user mistake is a one-line ConfigError naming key, value and what is allowed."""

from dataclasses import dataclass
from typing import Literal

import pytest

from confront.config import ConfigError, field, from_dict, merge, parse_override, to_dict, to_toml


@dataclass
class Inner:
    alpha: float = field(0.1, gt=0.0, le=1.0)
    hidden: tuple[int, ...] = (16,)


@dataclass
class Outer:
    name: str = "x"
    rounds: int = field(500, ge=1)
    mode: Literal["fast", "exact"] = "fast"
    kind: str = field("dmnn", choices=("dmnn", "ssaq"))
    inner: Inner = field(default_factory=Inner)


def test_valid_nested_and_coercion() -> None:
    cfg = from_dict(Outer, {"rounds": 20, "inner": {"alpha": 1, "hidden": [8, 4]}})
    assert cfg.rounds == 20
    assert cfg.inner.alpha == 1.0 and isinstance(cfg.inner.alpha, float)
    assert cfg.inner.hidden == (8, 4)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"rounds": 0}, "rounds = 0 is out of range: must be >= 1"),
        ({"rounds": "ten"}, "rounds = 'ten' has the wrong type: expected an integer"),
        ({"rounds": 2.5}, "rounds = 2.5 has the wrong type: expected an integer"),
        ({"mode": "slow"}, "mode = 'slow' is not allowed: use one of 'fast', 'exact'"),
        ({"kind": "dqn"}, "kind = 'dqn' is not allowed: use one of 'dmnn', 'ssaq'"),
        ({"inner": {"alpha": 1.5}}, "inner.alpha = 1.5 is out of range: must be > 0.0 and <= 1.0"),
        ({"inner": {"alpah": 0.2}}, "unknown key 'inner.alpah': allowed keys here are alpha, hidden"),
        ({"inner": {"hidden": "16"}}, "inner.hidden = '16' has the wrong type: expected a list"),
        ({"inner": {"hidden": [16, "a"]}}, "inner.hidden[1] = 'a' has the wrong type: expected an integer"),
        ({"inner": 3}, "inner = 3 has the wrong type: expected a table of Inner keys"),
        ({"rounds": True}, "rounds = True has the wrong type: expected an integer"),
    ],
)
def test_errors_are_one_line_and_precise(data: dict, message: str) -> None:
    with pytest.raises(ConfigError) as err:
        from_dict(Outer, data)
    assert str(err.value) == message
    assert "\n" not in str(err.value)


def test_override_parsing() -> None:
    assert parse_override("learner.alpha=0.2") == {"learner": {"alpha": 0.2}}
    assert parse_override("a.b=[1, 2]") == {"a": {"b": [1, 2]}}
    assert parse_override("a=fuzzy") == {"a": "fuzzy"}
    assert parse_override("a=true") == {"a": True}
    with pytest.raises(ConfigError, match="must look like"):
        parse_override("alpha")
    with pytest.raises(ConfigError, match="empty key"):
        parse_override("a..b=1")


def test_round_trip_through_toml() -> None:
    import tomllib

    cfg = from_dict(Outer, merge(to_dict(Outer()), {"inner": {"alpha": 0.5}}))
    again = from_dict(Outer, tomllib.loads(to_toml(to_dict(cfg))))
    assert again == cfg
    assert again.inner.alpha == 0.5
