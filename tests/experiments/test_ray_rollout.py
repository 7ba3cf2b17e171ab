"""PPO rollouts on Ray actors (``confront train --address``): one worker is the local path bit for bit, a killed
worker is started again without losing an update, a killed Ray run resumes exactly, and the user's mistakes
(a cluster that is not there, a resume in the other mode) are one-line refusals."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from confront import checkpoint as ck
from confront.config import ConfigError
from confront.runs import Run
from confront.train.factory import train_run
from confront.train.loop import new_run
from confront.train.spec import load_experiment

ray = pytest.importorskip("ray")

from confront.train.ppo_ray import RayTankTrainer, split_league, worker_seed  # noqa: E402

TIMING = ("wall_s", "decisions_per_s", "env_fraction", "update_wait_fraction")


@pytest.fixture(scope="module", autouse=True)
def local_ray() -> Any:
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


@pytest.fixture(autouse=True)
def td_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CONFRONT_CACHE", str(tmp_path / "cache"))  # the TD team, pre-trained for 4 rounds


def _overrides(**kw: str) -> list[str]:
    ov = ['learner.kind="ppo"', 'league.opponents=["1v1:SpinBot","4v4:td","1v1:self"]', "league.battles=2",
          "ppo.rollout_steps=16", "ppo.hidden=32", "train.session_rounds=8", "opponent.pretrain_rounds=4",
          "league.snapshot_every=1", "train.replay=false"]
    return ov + [f"{k}={v}" for k, v in kw.items()]


def _cfg(**kw: str) -> Any:
    return load_experiment("demo", _overrides(**kw))


def _same_run(a: Path, b: Path) -> None:
    """Rows, update logs (but their timings) and the model of two run folders are equal."""
    ra, rb = Run(a), Run(b)
    strip = [{k: v for k, v in r.items() if k not in TIMING} for r in ra.read_table("rounds")]
    assert strip == [{k: v for k, v in r.items() if k not in TIMING} for r in rb.read_table("rounds")]
    ua = [{k: v for k, v in r.items() if k not in TIMING} for r in ra.read_table("updates")]
    assert ua == [{k: v for k, v in r.items() if k not in TIMING} for r in rb.read_table("updates")]
    wa, wb = np.load(a / "model" / "actor.npz"), np.load(b / "model" / "actor.npz")
    assert wa.files == wb.files
    for k in wa.files:
        np.testing.assert_array_equal(wa[k], wb[k])


def test_the_league_splits_over_workers_by_battles() -> None:
    cfg = load_experiment("demo", ['learner.kind="ppo"', 'league.opponents=["1v1:SpinBot","4v4:td","1v1:Walls"]',
                                   "league.battles=3", 'league.focus=["1v1:Walls*2"]'])
    assert split_league(cfg, 1) == [{"1v1:SpinBot": 3, "4v4:td": 3, "1v1:Walls": 6}]
    # 3 battles over 2 workers: 2 + 1, the left-over ones to the workers in turn
    assert split_league(cfg, 2) == [{"1v1:SpinBot": 2, "4v4:td": 1, "1v1:Walls": 3},
                                    {"1v1:SpinBot": 1, "4v4:td": 2, "1v1:Walls": 3}]
    assert split_league(cfg, 12)[11] == {"1v1:Walls": 1}
    assert [sum(p.values()) for p in split_league(cfg, 12)] == [1] * 12
    with pytest.raises(ConfigError, match="12 battles, so 1 worker"):
        split_league(cfg, 13)
    assert worker_seed(7, 0) == 7 and len({worker_seed(7, w) for w in range(8)}) == 8
    assert all(0 <= worker_seed(2**32 - 1, w) < 2**32 for w in range(4))


SKILLS = {"tank.leads": '["none","linear","circular","gf"]', "tank.surf": "true", "tank.knowledge": "true",
          "tank.skill_prior": "3.0"}  # the tanks-tech tank: its prior is in the learner's first weights


@pytest.mark.parametrize(("overlap", "prioritise", "skills"), [("false", "false", False), ("true", "true", False),
                                                                ("false", "true", True)])
def test_one_worker_is_the_local_path_bit_for_bit(tmp_path: Path, overlap: str, prioritise: str, skills: bool) -> None:
    cfg = _cfg(**{"train.rounds": "14", "ppo.overlap": overlap, "league.prioritise": prioritise,
                  **(SKILLS if skills else {})})
    local = train_run(cfg, tmp_path / "local", progress=False)
    on_ray = train_run(cfg, tmp_path / "ray", progress=False, address="auto", workers=1)
    assert on_ray["rollout_workers"] == 1 and on_ray["rollout_worker_restarts"] == 0
    assert on_ray["decisions"] == local["decisions"] and on_ray["updates"] == local["updates"]
    _same_run(tmp_path / "local", tmp_path / "ray")


def test_a_killed_worker_is_started_again_and_no_update_is_lost(tmp_path: Path,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    calls = {"rollout": 0}
    original = RayTankTrainer._call

    def kill_during_the_third_rollout(self: RayTankTrainer, method: str, *args: Any) -> list[Any]:
        if method == "rollout":
            calls["rollout"] += 1
            if calls["rollout"] == 3:  # while (or just before) it collects
                threading.Timer(0.05, ray.kill, [self.workers[1]]).start()
        return original(self, method, *args)

    monkeypatch.setattr(RayTankTrainer, "_call", kill_during_the_third_rollout)
    cfg = _cfg(**{"train.rounds": "10"})
    summary = train_run(cfg, tmp_path / "run", progress=False, address="auto", workers=2)
    assert summary["rollout_workers"] == 2 and summary["rollout_worker_restarts"] == 1
    assert summary["rounds"] >= 10
    updates = Run(tmp_path / "run").read_table("updates")
    assert [int(u["update"]) for u in updates] == list(range(len(updates)))  # one update per rollout after the first
    assert all(np.isfinite(float(u["policy_loss"])) for u in updates[1:])
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["rollout_worker_restarts"] == 1


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "confront.cli.main", "train", *args], capture_output=True, text=True,
                          timeout=120)


def _refused(proc: subprocess.CompletedProcess[str], message: str) -> None:
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert len([line for line in proc.stderr.splitlines() if line.startswith("error:")]) == 1


def test_a_killed_ray_run_resumes_exactly_and_only_on_ray(tmp_path: Path) -> None:
    cfg = _cfg(**{"train.rounds": "10", "train.checkpoint_every": "4"})
    full = train_run(cfg, tmp_path / "full", progress=False, address="auto", workers=2)
    part = new_run(cfg, tmp_path / "part")
    part.release()  # the "killed" driver's lock
    trainer = RayTankTrainer(cfg, "auto", 2)
    try:
        while trainer.rounds_done < 4:
            trainer.update()
        arrays, meta = trainer.state()
    finally:
        trainer.close()
    ck.save(part.checkpoints, f"round-{trainer.rounds_done:06d}", arrays, meta)  # then the driver "dies"
    _refused(_cli("--resume", str(part.path), "--quiet"), "was trained on Ray with 2 rollout workers")
    _refused(_cli("--resume", str(part.path), "--address", "auto", "--workers", "3"), "resume it with --workers 2")
    resumed = train_run(None, part.path, resume=True, progress=False, address="auto")
    assert resumed["rounds"] == full["rounds"] and resumed["rollout_workers"] == 2
    _same_run(tmp_path / "full", tmp_path / "part")


def test_user_mistakes_are_one_line_refusals(tmp_path: Path) -> None:
    base = [a for o in _overrides(**{"train.rounds": "8", "train.session_rounds": "4", "train.checkpoint_every": "2"})
            for a in ("--set", o)]
    _refused(_cli("-c", "demo", *base, "--address", "127.0.0.1:9", "--out", str(tmp_path / "bad")),
             "no Ray cluster at --address 127.0.0.1:9")
    _refused(_cli("-c", "demo", *base, "--address", "ray://127.0.0.1:9", "--out", str(tmp_path / "bad")),
             "no Ray cluster at --address ray://127.0.0.1:9")
    _refused(_cli("-c", "demo", *base, "--workers", "2", "--out", str(tmp_path / "bad")), "give --address too")
    assert not (tmp_path / "bad").exists()
    # a local run, killed after a checkpoint, is not resumed on Ray (refused before Ray is asked)
    local = tmp_path / "local"
    assert _cli("-c", "demo", *base, "--out", str(local), "--quiet").returncode == 0
    (local / "summary.json").unlink()  # as if it had been killed after its last checkpoint
    _refused(_cli("--resume", str(local), "--address", "auto"), "was trained without --address")
