"""Issue 34, the training side: one run at a time per run folder, resumes that say what they do, checkpoints
edited with their checksums recomputed, TensorBoard after a resume, Ctrl-C, and the PPO run's replay."""

from __future__ import annotations

import hashlib
import json
import shutil
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from confront import checkpoint as ck
from confront.cli.main import cli
from confront.runs import Interrupted, Run
from confront.train.factory import train_run
from confront.train.spec import load_experiment

PAPER = ["train.rounds=6", "train.session_rounds=2", "train.checkpoint_every=2", "opponent.kind=SpinBot",
         "arena.battles=2"]
PPO = ['learner.kind="ppo"', 'league.opponents=["1v1:SpinBot", "4v4:SpinBot"]', "ppo.rollout_steps=16",
       "ppo.hidden=32", "league.battles=2", "train.rounds=8", "train.session_rounds=4", "train.checkpoint_every=4"]


def _snapshot(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "dir"
            for p in sorted(root.rglob("*"))}


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished paper run (6 rounds, checkpoints at 2 and 4) and a finished tiny PPO run."""
    root = tmp_path_factory.mktemp("runs")
    train_run(load_experiment("demo", PAPER), root / "paper", progress=False)
    train_run(load_experiment("demo", PPO), root / "ppo", progress=False)
    return root


def _killed(runs: Path, name: str, dest: Path) -> Path:
    """A copy of a finished run as a kill after its first checkpoint leaves it."""
    shutil.copytree(runs / name, dest)
    (dest / "summary.json").unlink()
    first = sorted(p for p in (dest / "checkpoints").iterdir() if p.name.startswith("round-"))[0]
    for p in (dest / "checkpoints").iterdir():
        if p.is_dir() and p != first:
            shutil.rmtree(p)
    (dest / "checkpoints" / "LATEST").write_text(first.name + "\n")
    return dest


def _edit(checkpoint: Path, arrays_edit: Any = None, meta_edit: Any = None) -> None:
    """Edit a checkpoint and recompute its checksums (what a hostile but careful user can do)."""
    arrays, meta = ck.load(checkpoint)
    if arrays_edit is not None:
        arrays = arrays_edit(arrays)
    if meta_edit is not None:
        meta = meta_edit(meta)
    for key in ("format", "format_version", "sha256", "meta_sha256"):
        meta.pop(key, None)
    tmp = checkpoint.parent / "edited"
    ck.save(tmp, checkpoint.name, arrays, meta)
    shutil.rmtree(checkpoint)
    shutil.move(tmp / checkpoint.name, checkpoint)
    shutil.rmtree(tmp)


def _one_line_exit_2(args: list[str], expect: str) -> None:
    res = CliRunner().invoke(cli, args)
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 2, (res.output, res.exception)
    assert len(lines) == 1 and lines[0].startswith("error: ") and expect in lines[0], res.stderr


def test_a_second_run_into_a_busy_folder_is_refused_and_the_first_unharmed(runs: Path, tmp_path: Path) -> None:
    """Item 2: another process holds the run folder (a run writing it): a new run and a resume get one line."""
    busy = _killed(runs, "paper", tmp_path / "busy")
    code = ("import sys, time; from pathlib import Path; from confront.runs import Run; "
            "Run.open(Path(sys.argv[1])); print('locked', flush=True); time.sleep(120)")
    proc = subprocess.Popen([sys.executable, "-c", code, str(busy)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == "locked"
        before = _snapshot(busy)
        _one_line_exit_2(["train", "--resume", str(busy), "--quiet"], f"being written by another run (process "
                                                                       f"{proc.pid})")
        cfg = load_experiment("demo", PAPER)
        with pytest.raises(FileExistsError, match="being written by another run"):
            train_run(cfg, busy, exist_ok=True, progress=False)
        assert _snapshot(busy) == before
    finally:
        proc.kill()
        proc.wait()
    summary = train_run(None, busy, resume=True, progress=False)  # the holder died: its lock is gone
    assert summary["rounds"] == 6 and not (busy / ".lock").exists()


def test_two_runs_started_together_into_one_empty_folder(tmp_path: Path) -> None:
    """Item 2: of two `confront train --out SAME` started at once, one trains and one is refused in one line."""
    (tmp_path / "same").mkdir()
    cmd = [sys.executable, "-m", "confront.cli.main", "train", "--out", str(tmp_path / "same"), "--quiet",
           *[a for kv in PAPER for a in ("--set", kv)]]
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outs = [(p.wait(timeout=600), p.stderr.read() if p.stderr else "") for p in procs]
    assert sorted(rc for rc, _ in outs) == [0, 2], outs
    refused = next(err for rc, err in outs if rc == 2)
    assert len(refused.strip().splitlines()) == 1 and "error: run folder" in refused
    assert json.loads((tmp_path / "same" / "summary.json").read_text())["rounds"] == 6


def test_resume_says_what_it_does(runs: Path, tmp_path: Path) -> None:
    """Frictions: resuming a finished run re-trained its last rounds quietly; a run without a checkpoint
    restarted from round 0 without a word."""
    _one_line_exit_2(["train", "--resume", str(runs / "paper"), "--quiet"], "is finished")
    fresh = _killed(runs, "paper", tmp_path / "fresh")
    shutil.rmtree(fresh / "checkpoints")
    (fresh / "checkpoints").mkdir()
    res = CliRunner().invoke(cli, ["train", "--resume", str(fresh), "--quiet"])
    assert res.exit_code == 0 and "has no checkpoint yet: training starts from round 0" in res.stderr
    killed = _killed(runs, "paper", tmp_path / "killed")
    res = CliRunner().invoke(cli, ["train", "--resume", str(killed), "--quiet"])
    assert res.exit_code == 0 and "from round-000002 (2 rounds done)" in res.stderr


def test_an_edited_config_is_refused_on_resume(runs: Path, tmp_path: Path) -> None:
    """Item 15: config.toml edited mid-run (a learning rate 200 times higher) is not used silently."""
    run = _killed(runs, "paper", tmp_path / "run")
    text = (run / "config.toml").read_text()
    (run / "config.toml").write_text(text.replace("rounds = 6", "rounds = 8"))
    before = _snapshot(run)
    _one_line_exit_2(["train", "--resume", str(run), "--quiet"], "config.toml was edited after round-000002")
    assert _snapshot(run) == before


@pytest.mark.parametrize(("name", "arrays_edit", "meta_edit", "expect"), [
    ("snapshots 10^8", None, lambda m: {**m, "snapshots": 10**8}, "snapshots = 100000000"),
    ("generator reseeding numpy", None, lambda m: {**m, "pool_rng": {**m["pool_rng"], "bit_generator": "seed"}},
     "bit generator 'seed'"),
    ("decisions negative", None, lambda m: {**m, "decisions": -5}, "decisions = -5"),
    ("observations of another shape", lambda a: {**a, "obs": a["obs"][:3]}, None, "array obs"),
])
def test_an_edited_ppo_checkpoint_with_checksums_is_refused(runs: Path, tmp_path: Path, name: str, arrays_edit: Any,
                                                            meta_edit: Any, expect: str) -> None:
    """Item 13: every field of a checkpoint is checked against the run's config, quickly and in one line."""
    run = _killed(runs, "ppo", tmp_path / "run")
    _edit(run / "checkpoints" / "round-000004", arrays_edit, meta_edit)
    np.random.seed(3)
    expected = np.random.random()
    np.random.seed(3)
    _one_line_exit_2(["train", "--resume", str(run), "--quiet"], expect)
    assert np.random.random() == expected  # NumPy's global generator untouched


def test_tensorboard_after_a_resume_has_each_step_once(runs: Path, tmp_path: Path) -> None:
    """Item 14: the scalars logged past the checkpoint before the kill are dropped, not shown twice."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    run = _killed(runs, "paper", tmp_path / "run")
    train_run(None, run, resume=True, progress=False)

    def steps(folder: Path) -> list[int]:
        acc = EventAccumulator(str(folder / "tb"))
        acc.Reload()
        return [e.step for e in acc.Scalars("share/all")]

    got = steps(run)
    assert got == sorted(set(got)) and got == steps(runs / "paper")


def test_ctrl_c_saves_and_the_run_resumes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                          request: pytest.FixtureRequest) -> None:
    """Friction: Ctrl-C kept nothing before the first checkpoint; now it saves after the step it is in."""
    from confront.train.paper_sim import SMDPTrainer

    advance = SMDPTrainer.advance

    pressed: list[int] = []

    def then_ctrl_c(self: Any, *args: Any) -> Any:
        out = advance(self, *args)
        if not pressed:  # once (a second Ctrl-C stops at once)
            pressed.append(1)
            signal.raise_signal(signal.SIGINT)
        return out

    monkeypatch.setattr(SMDPTrainer, "advance", then_ctrl_c)
    # Python's own handler, also when the suite runs as a background job (which starts with SIGINT ignored)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    request.addfinalizer(lambda: signal.signal(signal.SIGINT, before))
    cfg = load_experiment("demo", [*PAPER[:2], "train.checkpoint_every=1000", *PAPER[3:]])
    with pytest.raises(Interrupted) as stop:
        train_run(cfg, tmp_path / "run", progress=False)
    done = stop.value.rounds_done
    assert 0 < done < 6 and stop.value.checkpoint == tmp_path / "run" / "checkpoints" / f"round-{done:06d}"
    assert ck.load(stop.value.checkpoint)[1]["rounds_done"] == done and not (tmp_path / "run" / ".lock").exists()
    monkeypatch.setattr(SMDPTrainer, "advance", advance)
    assert train_run(None, tmp_path / "run", resume=True, progress=False)["rounds"] == 6
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_ppo_run_records_its_replay(runs: Path, tmp_path: Path) -> None:
    """Item 20: train.replay = true was ignored by PPO runs, so `confront replay RUN` on the demo's run failed."""
    replays = runs / "ppo" / "replays"
    assert (replays / "last_round.replay.json.gz").is_file() and (replays / "last_round.html").is_file()
    summary = json.loads((runs / "ppo" / "summary.json").read_text())
    assert summary["replay"] == str(replays / "last_round.replay.json.gz")
    res = CliRunner().invoke(cli, ["replay", str(runs / "ppo"), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0 and (tmp_path / "out" / "last_round.gif").is_file(), res.output


def test_the_lock_is_dropped_when_a_run_ends_or_fails(tmp_path: Path) -> None:
    cfg = load_experiment("demo", PAPER)
    train_run(cfg, tmp_path / "a", progress=False)
    assert not (tmp_path / "a" / ".lock").exists() and Run.open(tmp_path / "a").release() is None


def test_evaluate_of_a_ppo_run_names_its_measure_and_its_option(runs: Path) -> None:
    """Frictions: one name for the share in both tables, explained; a bad --opponents named as the option."""
    res = CliRunner().invoke(cli, ["evaluate", str(runs / "ppo"), "--rounds", "2", "--opponents", "1v1:SpinBot"])
    assert res.exit_code == 0 and "score share (simulator)" in res.output and "0.5 is even" in res.output
    _one_line_exit_2(["evaluate", str(runs / "ppo"), "--opponents", "1v1:Nobody"], "--opponents entry '1v1:Nobody'")


def test_demo_hints_name_the_command_as_started_and_the_replay(tmp_path: Path,
                                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """Frictions: the demo's "Next:" used a bare `confront` (not on PATH after the README's commands) and had no
    replay of the trained team."""
    replay = tmp_path / "run" / "replays" / "last_round.replay.json.gz"
    monkeypatch.setattr("confront.train.factory.train_run", lambda cfg, out, progress: {"replay": str(replay)})
    monkeypatch.setattr("confront.train.loop.print_summary", lambda summary: None)
    monkeypatch.setattr(sys, "argv", [".venv/bin/confront", "demo"])
    res = CliRunner().invoke(cli, ["demo", "--out", str(tmp_path / "run")])
    assert res.exit_code == 0, res.output
    assert f"open {replay.parent / 'last_round.html'}" in res.output
    assert f".venv/bin/confront evaluate {tmp_path / 'run'} --rounds 100" in res.output
    assert "  confront " not in res.output


def test_a_linked_figure_is_replaced_on_resume_not_followed(runs: Path, tmp_path: Path) -> None:
    """Item 3: a symlinked ``plots/score_ratio.png`` had its target overwritten by ``--resume``."""
    run = _killed(runs, "paper", tmp_path / "run")
    target = tmp_path / "precious.png"
    target.write_bytes(b"keep")
    (run / "plots" / "score_ratio.png").unlink()
    (run / "plots" / "score_ratio.png").symlink_to(target)
    res = CliRunner().invoke(cli, ["train", "--resume", str(run), "--quiet"])
    assert res.exit_code == 0, res.output
    assert target.read_bytes() == b"keep"
    figure = run / "plots" / "score_ratio.png"
    assert not figure.is_symlink() and figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _nan(state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {k: np.full_like(v, np.nan) if v.dtype.kind == "f" else v for k, v in state.items()}


@pytest.mark.parametrize(("name", "edit", "expect"), [
    ("all-NaN", _nan, "cannot be read: its arrays net.actor.0.weight, net.actor.0.bias, net.actor.2.weight, "
                      "net.actor.2.bias, net.actor.4.weight hold NaN or infinite values"),
    ("a wrong-size weight", lambda s: {**s, "net.actor.0.weight": s["net.actor.0.weight"][:, :7]},
     "cannot be read: network does not fit: Error(s) in loading state_dict for ActorCritic:"),
    ("a wrong-size generator state", lambda s: {**s, "gen": s["gen"][:100]}, "cannot be read: "),
])
def test_an_edited_ppo_npz_is_refused_by_evaluate(runs: Path, tmp_path: Path, name: str, edit: Any,
                                                   expect: str) -> None:
    """Items 6, 7: an all-NaN ``ppo.npz`` was scored; a wrong-size array in it was a traceback."""
    run = tmp_path / "run"
    shutil.copytree(runs / "ppo", run)
    path = run / "model" / "ppo.npz"
    with np.load(path, allow_pickle=False) as z:
        state = {k: z[k] for k in z.files}
    with path.open("wb") as fh:
        np.savez(fh, **edit(state))
    before = _snapshot(run)
    _one_line_exit_2(["evaluate", str(run), "--rounds", "2"], f"error: model {run / 'model'} {expect}")
    assert _snapshot(run) == before


def test_engine_evaluate_names_its_table_as_the_simulators(runs: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Friction: the engine's table said "score ratio (robocode)", the simulator's "score share", unexplained."""
    monkeypatch.setattr("confront.engine.tank_export.evaluate_tank_policy",
                        lambda policy, scen, opp, rounds, seed, visible=False: (None, 0.25))
    res = CliRunner().invoke(cli, ["evaluate", str(runs / "ppo"), "--engine", "robocode", "--rounds", "2",
                                   "--opponents", "1v1:SpinBot"])
    assert res.exit_code == 0, (res.output, res.exception)
    assert "| opponent | battles | score share (robocode) |" in res.output and "0.5 is even" in res.output
    assert "| 1v1:SpinBot | 1 | 0.250 |" in res.output and "score ratio" not in res.output


def test_share_by_opponent_figure_counts_windows_of_rounds(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Friction: the per-opponent figure's x axis said "session" but counted 10-round windows."""
    import confront.plots

    drawn: dict[str, str] = {}
    plot_curves = confront.plots.plot_curves

    def recorded(curves: Any, path: Any, **kw: Any) -> Path:
        drawn[Path(path).name] = kw.get("xlabel", "session")
        return plot_curves(curves, path, **kw)

    monkeypatch.setattr(confront.plots, "plot_curves", recorded)
    cfg = load_experiment("demo", [*PPO[:1], 'league.opponents=["1v1:SpinBot"]', *PPO[2:5], "train.rounds=20",
                                   "train.session_rounds=10", "train.checkpoint_every=20"])
    train_run(cfg, tmp_path / "run", progress=False)
    assert drawn["share_by_opponent.png"] == "window of 10 rounds" and drawn["score_ratio.png"] == "session"


def test_a_run_training_in_a_folder_keeps_it_from_a_second_train_run(runs: Path, tmp_path: Path) -> None:
    """Item 2 as the issue reproduced it: one ``train_run`` is training in a pre-made folder (paused inside its
    first step); a second ``train_run`` into it (exist_ok, as with a pre-made empty --out) is refused, and so is
    ``confront train --out`` and ``--resume``; the first run's files stay as they were."""
    busy = tmp_path / "busy"
    busy.mkdir()
    code = ("import sys, time; from pathlib import Path\n"
            "from confront.train.factory import train_run\nfrom confront.train.spec import load_experiment\n"
            "from confront.train.paper_sim import SMDPTrainer\n"
            "def paused(self, *args):\n    print('training', flush=True)\n    time.sleep(120)\n"
            "SMDPTrainer.advance = paused\n"
            "train_run(load_experiment('demo', sys.argv[2:]), Path(sys.argv[1]), exist_ok=True, progress=False)\n")
    proc = subprocess.Popen([sys.executable, "-c", code, str(busy), *PAPER], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == "training"
        before = _snapshot(busy)
        with pytest.raises(FileExistsError, match=f"being written by another run \\(process {proc.pid}\\)"):
            train_run(load_experiment("demo", PAPER), busy, exist_ok=True, progress=False)
        _one_line_exit_2(["train", "--resume", str(busy), "--quiet"], "being written by another run")
        assert _snapshot(busy) == before and proc.poll() is None
    finally:
        proc.kill()
        proc.wait()
