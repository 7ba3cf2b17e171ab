"""Hypothesis fuzzing of everything that reads a user's or a robot's input: the config parser, the replay reader,
the checkpoint reader and the bridge's line protocol. The only failures allowed are the documented one-line
errors (ConfigError, ReplayError, CheckpointError, ValueError for a bridge line).

``CONFRONT_FUZZ_EXAMPLES`` sets the examples per test (default 200, so the suite stays fast; the hardening
issue's measurement used 10000).
"""

from __future__ import annotations

import gzip
import json
import math
import os
import shutil
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from confront import checkpoint as ck
from confront.arena.replay import Replay, ReplayError, load_replay
from confront.config import ConfigError, from_dict, to_dict, to_toml
from confront.engine.bridge import LineReader, parse_end, parse_hello, parse_history, parse_observation
from confront.train.spec import ExperimentConfig, experiment_data, load_experiment

EXAMPLES = int(os.environ.get("CONFRONT_FUZZ_EXAMPLES", "200"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.filter_too_much])

scalars = (st.none() | st.booleans() | st.integers() | st.integers(-(2**70), 2**70) | st.floats()
           | st.text(max_size=20))
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=4)
                      | st.dictionaries(st.text(max_size=8), inner, max_size=4), max_leaves=12)
DEFAULT = to_dict(ExperimentConfig())
PATHS = [(s, k) for s, table in DEFAULT.items() if isinstance(table, dict) for k in table] + [
    (k, None) for k, v in DEFAULT.items() if not isinstance(v, dict)]


# -- config ------------------------------------------------------------------------------------------------------

@FUZZ
@given(st.lists(st.tuples(st.sampled_from(PATHS) | st.tuples(st.text(max_size=8), st.none()), values),
                max_size=4))
def test_config_from_any_data(changes: list[tuple[tuple[str, str | None], Any]]) -> None:
    data = json.loads(json.dumps(DEFAULT))
    for (section, key), value in changes:
        if key is None:
            data[section] = value
        elif isinstance(data.get(section), dict):
            data[section][key] = value
    try:
        cfg = from_dict(ExperimentConfig, data)
    except ConfigError as exc:
        assert "\n" not in str(exc)
        return
    text = to_toml(to_dict(cfg))  # whatever loads, writes a config.toml that loads back the same
    assert from_dict(ExperimentConfig, tomllib.loads(text)) == cfg


long_numbers = st.builds(lambda key, digits, sign: f"{key}={sign}{'7' * digits}",
                         st.sampled_from(["learner.alpha", "train.seed", "x", "arena.battles"]),
                         st.integers(1, 6000), st.sampled_from(["", "-", "+", "0x", "1e"]))


@FUZZ
@given(st.text(max_size=60) | long_numbers)
def test_config_override_text(text: str) -> None:
    try:
        load_experiment("demo", [text])
    except ConfigError as exc:
        assert "\n" not in str(exc)


@FUZZ
@given(st.binary(max_size=300) | st.text(max_size=300).map(str.encode)
       | long_numbers.map(lambda t: ("[learner]\n" + t.split(".")[-1].replace("=", " = ") + "\n").encode()))
def test_config_file_bytes(raw: bytes) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "x.toml"
        path.write_bytes(raw)
        try:
            load_experiment(str(path))
        except ConfigError as exc:
            assert "\n" not in str(exc)


@FUZZ
@given(st.text(max_size=40))
def test_config_name_or_path(name: str) -> None:
    try:
        experiment_data(name)
    except ConfigError as exc:
        assert "\n" not in str(exc)


@FUZZ
@given(st.dictionaries(st.text(min_size=1, max_size=8),
                       st.recursive(st.booleans() | st.integers(-(2**63), 2**63 - 1) | st.text(max_size=20)
                                    | st.floats(allow_nan=False, allow_infinity=False),
                                    lambda inner: st.lists(inner, max_size=3), max_leaves=6), max_size=5))
def test_to_toml_round_trip(data: dict[str, Any]) -> None:
    try:
        text = to_toml({"t": data})
    except ConfigError:  # a lone surrogate: no TOML file can hold it
        assert any(0xD800 <= ord(c) <= 0xDFFF for c in json.dumps(data, ensure_ascii=False) + "".join(data))
        return
    assert tomllib.loads(text) == {"t": data}


# -- replays -----------------------------------------------------------------------------------------------------

def _good_replay() -> dict[str, Any]:
    rep = Replay(800.0, 600.0, ["a", "b"], [0, 1], scenario="1v1")
    for t in range(3):
        rep.add(turn=t, round=0, x=np.array([100.0, 200.0]), y=np.array([50.0, 60.0]), heading=np.zeros(2),
                gun_heading=np.zeros(2), radar_heading=np.zeros(2), energy=np.array([100.0, 99.0]),
                alive=np.ones(2), bullets=np.array([[1.0, 2.0, 3.0]]) if t else None, scores=np.zeros(2))
    return rep.to_dict()


GOOD_REPLAY = _good_replay()


@FUZZ
@given(st.lists(st.tuples(st.sampled_from(sorted(GOOD_REPLAY)) | st.text(max_size=6), values), max_size=3))
def test_replay_from_any_data(changes: list[tuple[str, Any]]) -> None:
    d = json.loads(json.dumps(GOOD_REPLAY))
    for key, value in changes:
        d[key] = value
    try:
        rep = Replay.from_dict(d)
    except ReplayError as exc:
        assert "\n" not in str(exc)
        return
    assert 400 <= rep.width <= 5000 and len(rep) == d["n_frames"]


@FUZZ
@given(st.binary(max_size=400) | values.map(lambda v: json.dumps(v).encode()), st.booleans())
def test_replay_file_bytes(raw: bytes, gz: bool) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / ("x.replay.json.gz" if gz else "x.replay.json")
        path.write_bytes(gzip.compress(raw) if gz and raw[:1] != b"\x00" else raw)
        try:
            load_replay(path)
        except ReplayError as exc:
            assert "\n" not in str(exc)


# -- checkpoints -------------------------------------------------------------------------------------------------

ROWS = [{"round": i + 1, "score_ours": 10.0 * i, "won": bool(i % 2)} for i in range(3)]


@FUZZ
@given(st.sampled_from(["npz_cut", "npz_flip", "meta_value", "meta_bytes", "meta_drop", "latest"]),
       st.integers(0, 10**6), st.integers(0, 255), values, st.binary(max_size=200))
def test_checkpoint_reader(kind: str, where: int, byte: int, value: Any, raw: bytes) -> None:
    root = Path(tempfile.mkdtemp())
    try:
        arrays = {"w": np.arange(6.0).reshape(2, 3), "n": np.array(3)}
        path = ck.save(root, "round-000003", arrays, {"rounds_done": 3, "rows": ROWS, "rng": {"x": 1}})
        npz, meta_path = path / "state.npz", path / "meta.json"
        meta = json.loads(meta_path.read_text())
        if kind == "npz_cut":
            npz.write_bytes(npz.read_bytes()[: where % npz.stat().st_size])
        elif kind == "npz_flip":
            b = bytearray(npz.read_bytes())
            b[where % len(b)] ^= byte or 1
            npz.write_bytes(bytes(b))
        elif kind == "meta_value":
            meta[sorted(meta)[where % len(meta)]] = value
            meta_path.write_text(json.dumps(meta))
        elif kind == "meta_bytes":
            meta_path.write_bytes(raw)
        elif kind == "meta_drop":
            del meta[sorted(meta)[where % len(meta)]]
            meta_path.write_text(json.dumps(meta))
        else:
            (root / "LATEST").write_bytes(raw)
        try:
            found = ck.latest(root, notice=None)
            got, got_meta = ck.load(found)
        except ck.CheckpointError as exc:
            assert "\n" not in str(exc)
            return
        # what loads is exactly what was saved
        assert found.parent == root
        assert got.keys() == arrays.keys() and all(np.array_equal(got[k], arrays[k]) for k in arrays)
        assert got_meta["rounds_done"] == 3 and got_meta["rows"] == ROWS
    finally:
        shutil.rmtree(root)


# -- bridge lines ------------------------------------------------------------------------------------------------

HELLO = {"v": 2, "type": "hello", "token": "t0k", "name": "confront.BridgeBot* (1)", "team": "x (2)", "round": 0,
         "rounds": 3, "width": 800.0, "height": 600.0}
OBS = ("O 0 7 100.0 200.0 0.0 0.5 1.0 8.0 99.5 2.3 2 12.0\tsample.Walls;6;0;0.5;300.0;1.0;-8.0;80.0;400.0;200.0"
       '\t[{"type":"hit_wall"}]\t5;99.5;sample.Walls;80.0;77.0')
END = "E 0 9 death 0.0 2 300 1 9 450\t9;0.0;sample.Walls;50.0;50.0"
ALPHABET = st.sampled_from(list(" \t|;.-0123456789eEOAnNaifx[]{}\",:\n\\") + ["\u00e9", "\x00", "\ud800"])


def _mutate(text: str, edits: list[tuple[int, str]]) -> str:
    for pos, ins in edits:
        pos %= len(text) + 1
        text = text[:pos] + ins + text[pos + 1:]
    return text


mutations = st.lists(st.tuples(st.integers(0, 400), st.text(ALPHABET, max_size=4)), max_size=4)


@FUZZ
@given(st.sampled_from([json.dumps(HELLO), OBS, END]), mutations, st.text(max_size=80))
def test_bridge_lines(line: str, edits: list[tuple[int, str]], junk: str) -> None:
    hello = parse_hello(json.dumps(HELLO), "t0k")
    for text in (_mutate(line, edits), junk):
        for parse in (lambda t: parse_hello(t, "t0k"), lambda t: parse_observation(t, hello),
                      lambda t: parse_end(t, hello), parse_history):
            try:
                out = parse(text)
            except ValueError as exc:
                assert str(exc) is not None
                continue
            if hasattr(out, "x"):  # an observation: only finite values reach the policy
                assert all(math.isfinite(v) for v in (out.x, out.y, out.energy, out.velocity))
            if isinstance(out, dict):
                assert out["token"] == "t0k"


class FakeSocket:
    def __init__(self, chunks: list[bytes]) -> None:
        self.chunks = list(chunks)

    def recv(self, n: int) -> bytes:
        return self.chunks.pop(0)[:n] if self.chunks else b""


@FUZZ
@given(st.lists(st.binary(max_size=300), max_size=8), st.integers(1, 200))
def test_bridge_line_reader(chunks: list[bytes], limit: int) -> None:
    chunks = [c for c in chunks if c]
    reader = LineReader(FakeSocket(chunks), limit)  # type: ignore[arg-type]
    data = b"".join(chunks)
    expected = data.split(b"\n")[:-1]  # complete lines; an unterminated tail is dropped at the close
    got: list[str] = []
    try:
        while (line := reader.readline()) is not None:
            got.append(line)
    except ValueError:  # too long, or not UTF-8
        assert any(len(x) > limit for x in data.split(b"\n")) or any(_bad_utf8(x) for x in expected)
        assert len(reader.buf) <= limit + 300
        return
    assert got == [x.decode() for x in expected]


def _bad_utf8(b: bytes) -> bool:
    try:
        b.decode()
    except UnicodeDecodeError:
        return True
    return False
