"""A corpus of user mistakes run through the command line: each exits 2 with one line on stderr that names the
input, prints no traceback, and leaves every file that was there before byte-identical (and makes no run folder).
"""

from __future__ import annotations

import gzip
import hashlib
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from confront.cli.main import cli

TINY = ("--set", "train.rounds=4", "--set", "train.session_rounds=2", "--set", "train.checkpoint_every=2",
        "--set", "opponent.kind=SpinBot", "--set", "arena.battles=2")


@pytest.fixture(scope="module")
def ws(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A workspace: a small trained run, a resumable copy, broken copies, and bad files of every kind."""
    from confront.train.factory import train_run
    from confront.train.spec import load_experiment

    root = tmp_path_factory.mktemp("ws")
    cfg = load_experiment("demo", [t for t in TINY if t != "--set"])
    train_run(cfg, root / "run", progress=False)
    shutil.copytree(root / "run", root / "resumable")
    (root / "resumable" / "summary.json").unlink()
    edited = root / "edited"
    shutil.copytree(root / "resumable", edited)
    meta = edited / "checkpoints" / "round-000002" / "meta.json"
    meta.write_text(meta.read_text().replace('"rounds_done": 2', '"rounds_done": 1300'))
    pointer = root / "pointer"
    shutil.copytree(root / "resumable", pointer)
    (pointer / "checkpoints" / "LATEST").write_text("../../run\n")
    shutil.copytree(root / "run", root / "listmodel")
    (root / "listmodel" / "model" / "model.json").write_text("[]")
    shutil.copytree(root / "run", root / "truncated")
    npz = root / "truncated" / "model" / "learner.npz"
    npz.write_bytes(npz.read_bytes()[:100])
    _edit_learner(root, "nanmodel", lambda meta, state: (meta, {k: np.full_like(v, np.nan) if v.dtype.kind == "f"
                                                                  else v for k, v in state.items()}))
    _edit_learner(root, "hugemodel", lambda meta, state: ({**meta, "params": {**meta["params"],
                                                                                "hidden": [100000, 100000]}}, state))
    for name, edit in TANK_EDITS.items():
        _tank_model(root / name, edit)
    (root / "afile").write_text("not a folder\n")
    (root / "adir").mkdir()
    (root / "latin1.toml").write_bytes('name = "d\xe9mo"\n'.encode("latin-1"))
    (root / "wide.toml").write_text('name = "wide"\nteams = [2, 2]\nwidth = 20000\nheight = 600\n')
    (root / "crowd.toml").write_text('name = "crowd"\nteams = [3000, 3000]\n')
    (root / "frac.toml").write_text('name = "frac"\nteams = [1.7, 2.9]\n')
    (root / "big.toml").write_text("# " + "x" * (2 << 20) + '\nname = "big"\n')
    (root / "notgzip.replay.json.gz").write_bytes(b"plain text, not gzip")
    good = json.loads(gzip.decompress((root / "run" / "replays" / "last_round.replay.json.gz").read_bytes()))
    (root / "nokeys.replay.json").write_text(json.dumps({"format": "confront-replay/1", "width": 800}))
    (root / "wide.replay.json").write_text(json.dumps({**good, "width": 20000}))
    (root / "frames.replay.json").write_text(json.dumps({**good, "n_frames": 10**9}))
    (root / "robots.replay.json").write_text(json.dumps({**good, "names": ["r"] * 5000, "teams": [0] * 5000}))
    (root / "bomb.replay.json.gz").write_bytes(gzip.compress(b" " * (65 << 20)))
    (root / "grid.toml").write_text('experiment = "demo"\nseeds = 1\n')
    return root


def _edit_learner(root: Path, name: str, edit: Any) -> None:
    """A copy of the trained run whose model/learner.npz went through ``edit(meta, state)``."""
    shutil.copytree(root / "run", root / name)
    path = root / name / "model" / "learner.npz"
    with np.load(path, allow_pickle=False) as z:
        meta, state = json.loads(str(z["__meta__"])), {k: z[k] for k in z.files if k != "__meta__"}
    meta, state = edit(meta, state)
    with path.open("wb") as fh:
        np.savez(fh, __meta__=np.array(json.dumps(meta)), **state)


TANK_EDITS: dict[str, Any] = {  # PPO model folders written by hand: tank.json and actor.npz edited
    "tank-step": lambda tank, actor: ({**tank, "step_turns": 1e30}, actor),
    "tank-json": lambda tank, actor: ("[1, 2", actor),
    "tank-nan": lambda tank, actor: (tank, {k: np.full_like(v, np.nan) for k, v in actor.items()}),
    "tank-wrong": lambda tank, actor: (tank, {**actor, "w0": actor["w0"][:, :7]}),
    "tank-truncated": lambda tank, actor: (tank, None),
}


def _tank_model(folder: Path, edit: Any) -> None:
    from confront.arena.tank import TankSpace

    space = TankSpace()
    rng = np.random.default_rng(0)
    actor = {"w0": rng.normal(size=(sum(space.dims), space.n_features)), "b0": np.zeros(sum(space.dims))}
    tank, actor = edit({"step_turns": 5}, actor)
    model = folder / "model"
    model.mkdir(parents=True)
    (model / "model.json").write_text(json.dumps({"format": "confront-model/1", "kind": "ppo"}))
    (model / "tank.json").write_text(tank if isinstance(tank, str) else json.dumps(tank))
    with (model / "actor.npz").open("wb") as fh:
        np.savez(fh, **(actor if actor is not None else {"w0": np.zeros(3)}))
    if actor is None:
        (model / "actor.npz").write_bytes((model / "actor.npz").read_bytes()[:60])


def test_a_hand_written_tank_model_loads() -> None:
    """The control of the tank-* cases: the same files unedited make a policy."""
    from confront.engine.tank_export import load_tank_policy

    with tempfile.TemporaryDirectory() as tmp:
        _tank_model(Path(tmp) / "ok", lambda tank, actor: (tank, actor))
        assert load_tank_policy(Path(tmp) / "ok").step_turns == 5


# (arguments with {ws} for the workspace, text the error line must contain, path that must not appear)
CASES: list[tuple[str, list[str], str, str | None]] = [
    ("unknown scenario", ["train", "--set", "arena.scenario=nope", "--out", "{ws}/new"], "arena.scenario", "new"),
    ("scenario file outside Robocode", ["train", "--set", "arena.scenario={ws}/wide.toml", "--out", "{ws}/new"],
     "arena.scenario", "new"),
    ("infinite temperature", ["train", "--set", "learner.t_max=inf", "--out", "{ws}/new"], "learner.t_max", "new"),
    ("nan rate", ["train", "--set", "learner.alpha=nan", "--out", "{ws}/new"], "learner.alpha", "new"),
    ("empty hidden layer", ["train", "--set", "learner.hidden=[0]", "--out", "{ws}/new"], "learner.hidden[0]",
     "new"),
    ("seed 2^70 in the config", ["train", "--set", f"train.seed={2**70}", "--out", "{ws}/new"], "train.seed", "new"),
    ("seed 2^70 option", ["train", "--seed", str(2**70), "--out", "{ws}/new"], "--seed", "new"),
    ("negative seed", ["battle", "--seed", "-1"], "--seed", None),
    ("run name with a newline", ["train", "--set", 'name="a\\nb"', "--out", "{ws}/new"], "name", "new"),
    ("run name with a path", ["train", "--set", "name=../../evil"], "name", None),
    ("unknown opponent", ["train", "--set", "opponent.kind=Nobody", "--out", "{ws}/new"], "opponent.kind", "new"),
    ("config is a folder", ["train", "-c", "{ws}/adir", "--out", "{ws}/new"], "is a folder", "new"),
    ("config is not UTF-8", ["train", "-c", "{ws}/latin1.toml", "--out", "{ws}/new"], "UTF-8", "new"),
    ("unknown experiment", ["train", "-c", "nosuch", "--out", "{ws}/new"], "unknown experiment 'nosuch'", "new"),
    ("missing transfer source", ["train", *TINY, "--set", "transfer.source={ws}/nosuch", "--out", "{ws}/new"],
     "no trained model", "new"),
    ("missing TD model", ["train", *TINY[:-4], "--set", "opponent.model={ws}/nosuch", "--out", "{ws}/new"],
     "no trained model", "new"),
    ("out is a file", ["train", "--out", "{ws}/afile"], "afile", None),
    ("out is an existing run", ["train", "--out", "{ws}/run"], "already exists", None),
    ("resume with --set", ["train", "--resume", "{ws}/resumable", "--set", "train.rounds=9"], "--set", None),
    ("resume with -c", ["train", "--resume", "{ws}/resumable", "-c", "awm"], "-c", None),
    ("resume with --out", ["train", "--resume", "{ws}/resumable", "--out", "{ws}/new"], "--out", "new"),
    ("resume with --seed 0", ["train", "--resume", "{ws}/resumable", "--seed", "0"], "--seed", None),
    ("resume with --init", ["train", "--resume", "{ws}/resumable", "--init", "{ws}/run"], "--init", None),
    ("init of a paper learner", ["train", "--init", "{ws}/run", "--out", "{ws}/new"], "train.init", "new"),
    ("init from a paper run", ["train", "-c", "tanks-engine", "--engine", "robocode", "--init", "{ws}/run", "--out",
                               "{ws}/new"], "no trained PPO model", "new"),
    ("PPO engine training against a strafer", ["train", "-c", "tanks", "--engine", "robocode", "--out", "{ws}/new"],
     "'1v1:strafe'", "new"),
    ("resume an edited checkpoint", ["train", "--resume", "{ws}/edited", "--quiet"], "edited or corrupt", None),
    ("resume a bad LATEST", ["train", "--resume", "{ws}/pointer", "--quiet"], "LATEST", None),
    ("resume a folder that is no run", ["train", "--resume", "{ws}/adir"], "not a run folder", None),
    ("engine training with true sensing", ["train", "--engine", "robocode", "--set", "arena.sensing=true", "--out",
                                           "{ws}/new"], "arena.sensing", "new"),
    ("battle of 0 rounds", ["battle", "--rounds", "0"], "--rounds", None),
    ("battle of 0 battles", ["battle", "--battles", "0"], "--battles", None),
    ("unknown robot", ["battle", "--robots", "SpinBot,Nobody"], "Nobody", None),
    ("unknown battle scenario", ["battle", "--scenario", "nope"], "scenario 'nope'", None),
    ("battle scenario file that is none", ["battle", "--scenario", "{ws}/run/config.toml"], "config.toml", None),
    ("evaluate an unknown opponent", ["evaluate", "{ws}/run", "--opponents", "Nobody"], "Nobody", None),
    ("evaluate 0 rounds", ["evaluate", "{ws}/run", "--rounds", "0"], "--rounds", None),
    ("evaluate a model.json of []", ["evaluate", "{ws}/listmodel", "--rounds", "2"], "not a confront model", None),
    ("evaluate a truncated learner.npz", ["evaluate", "{ws}/truncated", "--rounds", "2"], "cannot be read", None),
    ("evaluate a missing run", ["evaluate", "{ws}/nosuch"], "nosuch", None),
    ("export onto a file", ["export", "{ws}/run", "--out", "{ws}/afile"], "afile", None),
    ("export --name", ["export", "{ws}/run", "--out", "{ws}/robots", "--name", "X"], "--name", "robots"),
    ("export --play of a paper run", ["export", "{ws}/run", "--out", "{ws}/robots", "--play", "sampled"], "--play",
     "robots"),
    ("evaluate --play of a paper run", ["evaluate", "{ws}/run", "--play", "greedy"], "--play", None),
    ("replay of a non-gzip .gz", ["replay", "{ws}/notgzip.replay.json.gz"], "notgzip", None),
    ("replay with missing keys", ["replay", "{ws}/nokeys.replay.json"], "lacks the keys", None),
    ("replay 20000 wide", ["replay", "{ws}/wide.replay.json"], "outside Robocode", None),
    ("replay of 10^9 frames", ["replay", "{ws}/frames.replay.json"], "n_frames", None),
    ("replay of 5000 robots", ["replay", "{ws}/robots.replay.json"], "robots", None),
    ("replay gzip bomb", ["replay", "{ws}/bomb.replay.json.gz"], "64 MB", None),
    ("sweep without Ray", ["sweep", "{ws}/grid.toml", "--out", "{ws}/sweep"], "'ray'", "sweep"),
    ("demo of 0 rounds", ["demo", "--rounds", "0"], "--rounds", None),
    ("config show with a bad override", ["config", "show", "demo", "--set", "learner.hidden=[-3]"],
     "learner.hidden[0]", None),
    # issue 34 items 6, 7, 21: hand-edited models are refused before they play or export
    ("evaluate an all-NaN DMNN", ["evaluate", "{ws}/nanmodel", "--rounds", "2"], "NaN", None),
    ("export an all-NaN DMNN", ["export", "{ws}/nanmodel", "--out", "{ws}/nan.jar"], "NaN", "nan.jar"),
    ("evaluate a DMNN claiming 10^5 x 10^5 weights", ["evaluate", "{ws}/hugemodel", "--rounds", "2"],
     "do not fit", None),
    ("export a tank held 1e30 turns", ["export", "{ws}/tank-step", "--out", "{ws}/t.jar"], "step_turns", "t.jar"),
    ("export a tank.json that is no JSON", ["export", "{ws}/tank-json", "--out", "{ws}/t.jar"], "tank-json",
     "t.jar"),
    ("export an all-NaN actor", ["export", "{ws}/tank-nan", "--out", "{ws}/t.jar"], "non-finite", "t.jar"),
    ("export an actor of the wrong size", ["export", "{ws}/tank-wrong", "--out", "{ws}/t.jar"], "do not chain",
     "t.jar"),
    ("export a truncated actor.npz", ["export", "{ws}/tank-truncated", "--out", "{ws}/t.jar"], "tank-truncated",
     "t.jar"),
    # issue 34 frictions: export --out x.zip made a folder named x.zip
    ("export to a .zip", ["export", "{ws}/run", "--out", "{ws}/x.zip"], "must be a robots folder", "x.zip"),
    ("replay of a run without replays", ["replay", "{ws}/adir"], "train.replay = true", None),
    ("replay --out onto a file", ["replay", "{ws}/nokeys.replay.json", "--out", "{ws}/afile"], "--out", None),
    # issue 34 item 11: scenarios too big for memory, and team sizes that are not whole numbers
    ("scenario of 6000 robots", ["train", "--set", "arena.scenario={ws}/crowd.toml", "--out", "{ws}/new"],
     "at most 256", "new"),
    ("battle of 6000 robots", ["battle", "--scenario", "{ws}/crowd.toml"], "at most 256", None),
    ("scenario of 1.7 robots", ["train", "--set", "arena.scenario={ws}/frac.toml", "--out", "{ws}/new"],
     "whole sizes", "new"),
    # issue 34 item 12: files are read with a size limit
    ("config show /dev/zero", ["config", "show", "/dev/zero"], "larger than 1 MB", None),
    ("config of 2 MB", ["train", "-c", "{ws}/big.toml", "--out", "{ws}/new"], "larger than 1 MB", "new"),
    ("scenario of 2 MB", ["battle", "--scenario", "{ws}/big.toml"], "larger than 1 MB", None),
    # issue 34 item 4: file systems that refuse (read-only, a name too long) are one line too
    ("read-only --out", ["train", *TINY, "--out", "/sys/confront-run", "--quiet"], "/sys/confront-run", None),
    ("--out name of 300 characters", ["train", *TINY, "--out", "{ws}/" + "r" * 300, "--quiet"], "too long", None),
    ("--replay name of 300 characters", ["battle", "--rounds", "1", "--replay", "{ws}/" + "r" * 300 + ".json"],
     "too long", None),
    ("export to a read-only .jar", ["export", "{ws}/run", "--out", "/sys/confront.jar"], "/sys", None),
    ("plot fuzzy of an unknown format", ["plot", "fuzzy", "--out", "{ws}/x.xyz"], ".png", "x.xyz"),
    # issue 34 item 16: a folder is not a figure's name (it wrote adir.png and said "wrote adir")
    ("plot fuzzy into a folder", ["plot", "fuzzy", "--out", "{ws}/adir"], "is a folder", "adir.png"),
    # issue 34 item 10: Robocode's numRounds is a Java int
    ("battle of 2^32+1 rounds", ["battle", "--engine", "robocode", "--rounds", "4294967297"], "--rounds", None),
    ("evaluate 2^31 rounds", ["evaluate", "{ws}/run", "--rounds", str(2**31)], "--rounds", None),
]


def _snapshot(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "dir"
            for p in sorted(root.rglob("*"))}


@pytest.mark.parametrize(("name", "args", "expect", "absent"), CASES, ids=[c[0] for c in CASES])
def test_user_mistake_is_one_line_exit_2(ws: Path, name: str, args: list[str], expect: str, absent: str | None,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CONFRONT_CACHE", str(ws / "cache"))
    monkeypatch.chdir(ws)
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` fails as without the extra
    before = _snapshot(ws)
    result = CliRunner().invoke(cli, [a.replace("{ws}", str(ws)) for a in args])
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2, (result.output, result.exception)
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert expect in lines[0]
    assert "Traceback" not in result.output
    after = _snapshot(ws)
    assert {k: v for k, v in after.items() if not k.startswith("cache")} == {
        k: v for k, v in before.items() if not k.startswith("cache")}
    if absent is not None:
        assert not (ws / absent).exists()


@pytest.mark.parametrize("args", [["train", "--set", "arena.scenario=nope"], ["replay", "{ws}/notgzip.replay.json.gz"],
                                  ["export", "{ws}/run", "--out", "{ws}/afile"], ["battle", "--rounds", "0"]])
def test_no_traceback_in_a_real_process(ws: Path, args: list[str]) -> None:
    proc = subprocess.run([sys.executable, "-m", "confront.cli.main", *[a.replace("{ws}", str(ws)) for a in args]],
                          capture_output=True, text=True, cwd=ws, timeout=300)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and proc.stderr.startswith("error: ")


def test_missing_engine_is_one_line_and_no_run_folder(ws: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CONFRONT_ROBOCODE_JAR", str(ws / "nosuch.jar"))
    result = CliRunner().invoke(cli, ["train", "--engine", "robocode", "--out", str(ws / "new"), "--quiet"])
    assert result.exit_code == 2 and result.stderr.startswith("error: Robocode engine not found")
    assert len(result.stderr.strip().splitlines()) == 1 and not (ws / "new").exists()


def test_corrupt_td_cache_is_rebuilt_aloud(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from confront.train.league import td_team
    from confront.train.spec import load_experiment

    monkeypatch.setenv("CONFRONT_CACHE", str(tmp_path))
    cfg = load_experiment("demo", ["opponent.pretrain_rounds=2"])
    first, where = td_team(cfg, 4)
    npz = where / "learner.npz"
    good = npz.read_bytes()
    npz.write_bytes(good[: len(good) // 2])  # a truncated zip: BadZipFile
    said: list[str] = []
    monkeypatch.setattr("click.echo", lambda text, err=False: said.append(text))
    again, where2 = td_team(cfg, 4)
    assert where2 == where and len(said) == 1 and "cached TD team cannot be used" in said[0]
    assert again.state_dict().keys() == first.state_dict().keys()
    td_team(cfg, 4)  # the rebuilt entry loads without a word
    assert len(said) == 1


def test_missing_latest_resumes_from_the_newest_checkpoint_aloud(ws: Path, tmp_path: Path,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CONFRONT_CACHE", str(ws / "cache"))
    run = tmp_path / "run"
    shutil.copytree(ws / "resumable", run)
    (run / "checkpoints" / "LATEST").unlink()
    result = CliRunner().invoke(cli, ["train", "--resume", str(run), "--quiet"])
    assert result.exit_code == 0, result.output
    assert "LATEST is missing; using round-000002" in result.stderr
    assert (run / "metrics" / "rounds.csv").read_text() == (ws / "run" / "metrics" / "rounds.csv").read_text()


def test_demo_rounds_below_its_session_are_allowed(monkeypatch: pytest.MonkeyPatch) -> None:
    from confront.train import factory, loop

    got = []
    monkeypatch.setattr(factory, "train_run", lambda cfg, out, progress: got.append(cfg) or {})
    monkeypatch.setattr(loop, "print_summary", lambda summary: None)
    result = CliRunner().invoke(cli, ["demo", "--rounds", "8", "--out", "unused"])
    assert result.exit_code == 0, result.output
    assert (got[0].train.rounds, got[0].train.session_rounds) == (8, 8)
    assert "sessions of 8 rounds" in result.stderr


ENV_CASES = [  # issue 34 items 4 and 5: (variable, value, arguments, text the error line must contain)
    ("CONFRONT_THREADS", "abc", ["battle", "--rounds", "1"], "CONFRONT_THREADS"),
    ("CONFRONT_THREADS", "0", ["battle", "--rounds", "1"], "CONFRONT_THREADS"),
    ("CONFRONT_THREADS", "-1", ["battle", "--rounds", "1"], "CONFRONT_THREADS"),
    ("CONFRONT_CACHE", "/sys/confront-cache", ["train", "--set", "train.rounds=2", "--set", "train.session_rounds=2",
                                               "--set", "opponent.pretrain_rounds=2", "--out", "{ws}/new", "--quiet"],
     "/sys/confront-cache"),
]


@pytest.mark.parametrize(("var", "value", "args", "expect"), ENV_CASES, ids=[f"{c[0]}={c[1]}" for c in ENV_CASES])
def test_bad_environment_is_one_line_exit_2(ws: Path, var: str, value: str, args: list[str], expect: str,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CONFRONT_CACHE", str(ws / "cache"))
    monkeypatch.setenv(var, value)
    before = _snapshot(ws)
    result = CliRunner().invoke(cli, [a.replace("{ws}", str(ws)) for a in args])
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2, (result.output, result.exception)
    assert len(lines) == 1 and lines[0].startswith("error: ") and expect in lines[0], result.stderr
    assert {k: v for k, v in _snapshot(ws).items() if not k.startswith("cache")} == {
        k: v for k, v in before.items() if not k.startswith("cache")}
    assert not (ws / "new").exists()


def _full_disk(*args: object, **kwargs: object) -> None:
    import errno
    import os

    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def test_full_disk_at_start_is_one_line_and_leaves_no_folder(ws: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 34 item 4: the disk is full when the run folder's config is written."""
    monkeypatch.setenv("CONFRONT_CACHE", str(ws / "cache"))
    monkeypatch.setattr("confront.runs.write_atomic", _full_disk)
    result = CliRunner().invoke(cli, ["train", *TINY, "--out", str(ws / "full"), "--quiet"])
    assert result.exit_code == 2 and result.stderr == "error: No space left on device\n", result.output
    assert not (ws / "full").exists()


def test_full_disk_at_a_checkpoint_is_one_line_and_keeps_the_run(ws: Path, tmp_path: Path,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 34 item 4: the disk fills up at a checkpoint: one line; the folder (config, metrics) stays."""
    monkeypatch.setenv("CONFRONT_CACHE", str(ws / "cache"))
    monkeypatch.setattr("confront.checkpoint._savez", _full_disk)
    result = CliRunner().invoke(cli, ["train", *TINY, "--out", str(tmp_path / "run"), "--quiet"])
    assert result.exit_code == 2 and result.stderr == "error: No space left on device\n", result.output
    assert (tmp_path / "run" / "config.toml").is_file()
    assert [p.name for p in (tmp_path / "run" / "checkpoints").iterdir()] == []


@pytest.mark.parametrize(("args", "expect"), [(["99999"], "PORT must be"), (["abc"], "PORT must be"),
                                              (["0", "nosuchmodule:f"], "cannot be loaded"),
                                              (["0", "json"], "module:function"), (["0", "json:nothing"], "nothing"),
                                              (["0", "json:__doc__"], "not a function")])
def test_bridge_command_refuses_a_bad_port_or_policy_in_one_line(args: list[str], expect: str,
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 34 item 18: docs/engine.md's bridge command (the token from the environment), bad arguments."""
    monkeypatch.setenv("CONFRONT_BRIDGE_TOKEN", "t" * 32)
    proc = subprocess.run([sys.executable, "-m", "confront.engine.bridge", *args], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and expect in proc.stderr, proc.stderr
    docs = (Path(__file__).parents[2] / "docs" / "engine.md").read_text()
    assert "bridge PORT TOKEN" not in docs and "CONFRONT_BRIDGE_TOKEN=<token> python -m confront.engine.bridge PORT" \
        in docs
