"""Training runs: run-folder layout, repeatability, kill-and-resume equality, refusal of corrupt checkpoints."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

SMALL = ["--set", "train.rounds=48", "--set", "train.session_rounds=8", "--set", "train.checkpoint_every=8",
         "--set", "arena.battles=4", "--set", "opponent.pretrain_rounds=8", "--set", "train.replay=false"]


def _env(tmp_path: Path) -> dict[str, str]:
    return {**os.environ, "CONFRONT_CACHE": str(tmp_path / "cache")}


def _train(tmp_path: Path, out: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "confront.cli.main", "train", "-c", "demo", "--quiet",
                           "--out", str(out), *SMALL, *extra], capture_output=True, text=True, env=_env(tmp_path),
                          timeout=600)


def _rows(run: Path, name: str = "rounds") -> list[dict[str, str]]:
    with (run / "metrics" / f"{name}.csv").open() as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    tmp = tmp_path_factory.mktemp("ref")
    proc = _train(tmp, tmp / "ref")
    assert proc.returncode == 0, proc.stderr
    return tmp, tmp / "ref"


def test_run_folder_layout(reference: tuple[Path, Path]) -> None:
    _, run = reference
    names = {p.name for p in run.iterdir()}
    assert {"config.toml", "metrics", "plots", "checkpoints", "model", "summary.json"} <= names
    assert {p.name for p in (run / "metrics").iterdir()} >= {"rounds.csv", "sessions.csv"}
    assert {p.name for p in (run / "plots").iterdir()} >= {"score_ratio.png", "scores.png", "defensive.png"}
    rows, sessions = _rows(run), _rows(run, "sessions")
    assert [int(r["round"]) for r in rows] == list(range(1, 49))
    assert len(sessions) == 6
    for r in rows:  # score ratio is ours / (ours + theirs) and the parts add up to the totals
        o, t = float(r["score_ours"]), float(r["score_theirs"])
        assert float(r["score_ratio"]) == pytest.approx(o / (o + t))
        parts = ("survival", "last_survivor", "bullet_damage", "bullet_kill_bonus", "ram_damage", "ram_kill_bonus")
        assert sum(float(r[f"{p}_ours"]) for p in parts) == pytest.approx(o)
    first = sessions[0]
    chunk = rows[:8]
    assert float(first["score_ours"]) == pytest.approx(sum(float(r["score_ours"]) for r in chunk))
    summary = json.loads((run / "summary.json").read_text())
    assert summary["rounds"] == 48 and 0.0 <= summary["final_score_ratio"] <= 1.0
    assert (run / "model" / "learner.npz").exists() and (run / "model" / "model.json").exists()


def test_same_seed_same_metrics_other_seed_differs(reference: tuple[Path, Path], tmp_path: Path) -> None:
    tmp, ref = reference
    again = _train(tmp, tmp_path / "again")
    assert again.returncode == 0, again.stderr
    assert _rows(tmp_path / "again") == _rows(ref)
    other = _train(tmp, tmp_path / "other", "--seed", "1")
    assert other.returncode == 0, other.stderr
    assert _rows(tmp_path / "other") != _rows(ref)


def test_sigkill_then_resume_equals_uninterrupted(reference: tuple[Path, Path], tmp_path: Path) -> None:
    tmp, ref = reference
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "confront.cli.main", "train", "-c", "demo", "--quiet",
                             "--out", str(out), *SMALL], env=_env(tmp), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    deadline = time.time() + 300
    while time.time() < deadline and not (out / "checkpoints" / "LATEST").exists():
        time.sleep(0.01)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    assert not (out / "summary.json").exists(), "the run finished before it could be killed"
    resumed = subprocess.run([sys.executable, "-m", "confront.cli.main", "train", "--resume", str(out), "--quiet"],
                             capture_output=True, text=True, env=_env(tmp), timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    assert _rows(out) == _rows(ref)
    assert _rows(out, "sessions") == _rows(ref, "sessions")


def test_corrupt_checkpoint_is_refused_and_kept(reference: tuple[Path, Path], tmp_path: Path) -> None:
    tmp, _ = reference
    out = tmp_path / "corrupt"
    proc = _train(tmp, out)
    assert proc.returncode == 0
    (out / "summary.json").unlink()
    latest = out / "checkpoints" / (out / "checkpoints" / "LATEST").read_text().strip()
    npz = latest / "state.npz"
    npz.write_bytes(npz.read_bytes()[: npz.stat().st_size // 2])
    before = sorted((p.name, p.stat().st_size) for p in (out / "checkpoints").rglob("*"))
    resumed = subprocess.run([sys.executable, "-m", "confront.cli.main", "train", "--resume", str(out), "--quiet"],
                             capture_output=True, text=True, env=_env(tmp), timeout=600)
    assert resumed.returncode == 2
    assert "corrupt or truncated" in resumed.stderr and "Traceback" not in resumed.stderr
    assert sorted((p.name, p.stat().st_size) for p in (out / "checkpoints").rglob("*")) == before


def test_random_reference_and_true_sensing_are_config_choices(tmp_path: Path,
                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    from confront.train.factory import train_run
    from confront.train.paper_model import smdp_config
    from confront.train.spec import load_experiment

    monkeypatch.setenv("CONFRONT_CACHE", str(tmp_path / "cache"))
    small = ["train.rounds=8", "train.session_rounds=4", "arena.battles=2", "opponent.pretrain_rounds=2",
             "train.replay=false"]
    cfg = load_experiment("demo", small + ["learner.kind=random", "arena.sensing=true"])
    assert cfg.arena.sensing == "true" and smdp_config(cfg).observation.sensing == "true"
    summary = train_run(cfg, tmp_path / "run", progress=False)
    assert summary["rounds"] == 8 and summary["learner"] == {"temperature": float("inf"), "updates": 0.0}
    # a different sensing trains (and caches) a different TD team
    again = train_run(load_experiment("demo", small + ["learner.kind=random"]), tmp_path / "run2", progress=False)
    assert again["td_model"] != summary["td_model"]


def test_one_loop_logs_every_learner_to_tensorboard(reference: tuple[Path, Path]) -> None:
    """The paper's learners go through the same loop as PPO tanks: TensorBoard scalars of the score share."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    _, run = reference
    acc = EventAccumulator(str(run / "tb"))
    acc.Reload()
    shares = acc.Scalars("share/all")
    assert "train/temperature" in acc.Tags()["scalars"] and len(shares) >= 6
    rows = _rows(run)
    o = sum(float(r["score_ours"]) for r in rows[-8:])
    t = sum(float(r["score_theirs"]) for r in rows[-8:])
    assert shares[-1].value == pytest.approx(o / (o + t), rel=1e-6)  # the last 8 rounds (session_rounds), pooled
    summary = json.loads((run / "summary.json").read_text())
    assert summary["engine"] == "sim" and summary["setup_s"] >= 0


def test_ppo_league_the_engine_cannot_play_is_refused_before_a_run_folder_is_left(tmp_path: Path) -> None:
    from confront.config import ConfigError
    from confront.train.factory import train_run
    from confront.train.spec import load_experiment

    with pytest.raises(ConfigError, match="'1v1:strafe' cannot be played in the engine"):  # the first of tanks.toml's
        train_run(load_experiment("tanks"), tmp_path / "run", progress=False, engine="robocode")
    assert not (tmp_path / "run").exists()
    with pytest.raises(ConfigError, match="engine must be one of"):
        train_run(load_experiment("demo"), tmp_path / "run", progress=False, engine="gazebo")
    assert not (tmp_path / "run").exists()
