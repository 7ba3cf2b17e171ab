"""The command line: resolved configs, and user mistakes as one line on stderr with exit code 2."""

import subprocess
import sys
import tomllib

import pytest
from click.testing import CliRunner

from confront.cli.main import cli


def test_config_show_prints_full_resolved_config() -> None:
    result = CliRunner().invoke(cli, ["config", "show", "awm", "--set", "learner.alpha=0.2"])
    assert result.exit_code == 0, result.output
    data = tomllib.loads(result.output)
    assert data["learner"]["alpha"] == 0.2
    assert data["learner"]["momentum"] == 0.95  # Table 2
    assert data["train"]["rounds"] == 500 and data["train"]["session_rounds"] == 10
    assert set(data) >= {"arena", "opponent", "learner", "transfer", "train"}


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--set", "learner.alpha=2"], "error: learner.alpha = 2.0 is out of range: must be > 0.0 and <= 1.0"),
        (["--set", "learner.alpah=0.2"], "error: unknown key 'learner.alpah': allowed keys here are"),
        (["--set", "train.rounds=many"], "error: train.rounds = 'many' has the wrong type: expected an integer"),
        (["--set", "learner.kind=\"dqn\""], "error: learner.kind = 'dqn' is not allowed: use one of 'dmnn', 'ssaq'"),
        (["--set", "learner.t_min=0.5"], "error: learner.t_min = 0.5 must not exceed learner.t_max = 0.1"),
        (["--set", "rounds"], "error: --set 'rounds' must look like key.path=value"),
    ],
)
def test_bad_overrides_exit_2_with_one_line(args: list[str], message: str) -> None:
    proc = subprocess.run([sys.executable, "-m", "confront.cli.main", "config", "show", "demo", *args],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.startswith(message)
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "Traceback" not in proc.stderr


def test_unknown_experiment_and_bad_toml(tmp_path) -> None:
    result = CliRunner().invoke(cli, ["config", "show", "nosuch"])
    assert result.exit_code == 2
    bad = tmp_path / "bad.toml"
    bad.write_text("[learner\nalpha = 1")
    result = CliRunner().invoke(cli, ["config", "show", str(bad)])
    assert result.exit_code == 2
    assert "is not valid TOML" in result.output


def test_help_texts_say_what_a_newcomer_needs() -> None:
    """Issue 34 frictions: --opponents' format and names, the demo's real default folder, replay --out a folder."""
    from click.testing import CliRunner

    from confront.cli.main import cli

    def help_of(*cmd: str) -> str:
        return " ".join(CliRunner().invoke(cli, [*cmd, "--help"]).output.split())

    assert "SCENARIO:NAME, e.g. 1v1:SpinBot,4v4:td" in help_of("evaluate")
    assert "runs/tanks-demo-<time>" in help_of("demo")
    assert "Folder to write the GIF and HTML player into" in help_of("replay")


def test_readme_uses_the_demos_run_and_test_script_reports_parts() -> None:
    """Issue 34 frictions: the README's Robocode block trained a second demo; scripts/test.sh printed only dots."""
    from pathlib import Path

    root = Path(__file__).parents[2]
    readme = root / "README.md"
    block = readme.read_text().split("Your trained tanks in Robocode itself", 1)[1].split("```", 2)[1]
    assert "demo" not in block.replace("runs/tanks-demo-*", "").replace("the demo above", "")
    assert "runs/tanks-demo-*" in block
    script = (root / "scripts" / "test.sh").read_text()
    assert "== pip install" in script and "== summary" in script and "for part in tests/" in script


def test_bench_json_passes_through(monkeypatch) -> None:  # noqa: ANN001 - pytest's MonkeyPatch
    """Issue 34 friction: `confront bench sim` printed no JSON last line; --json asks the script for it."""
    from click.testing import CliRunner

    from confront.cli.main import cli

    calls: list[list[str]] = []
    monkeypatch.setattr("subprocess.run", lambda cmd, check: calls.append(list(cmd)))
    assert CliRunner().invoke(cli, ["bench", "sim", "--json"]).exit_code == 0
    assert calls[-1][-2].endswith("sim_throughput.py") and calls[-1][-1] == "--json"
    res = CliRunner().invoke(cli, ["bench", "learner", "--json"])
    assert res.exit_code == 2 and "--json is for sim and env" in res.output


def test_a_stopped_training_says_how_to_continue(monkeypatch, tmp_path) -> None:  # noqa: ANN001 - pytest's fixtures
    """Issue 34 friction: Ctrl-C printed only "Aborted!"; now the saved checkpoint and the resume command."""
    from click.testing import CliRunner

    import confront.cli.main as main
    from confront.runs import Interrupted

    def stopped(*args: object, **kwargs: object) -> None:
        raise Interrupted(tmp_path / "my run", 40, tmp_path / "my run" / "checkpoints" / "round-000040")

    monkeypatch.setattr("confront.experiments.demo.run_demo", stopped)
    res = CliRunner().invoke(main.cli, ["demo", "--rounds", "8"])
    assert res.exit_code == 130, res.output
    lines = res.stderr.strip().splitlines()
    assert lines[0] == f"stopped after 40 rounds; saved {tmp_path}/my run/checkpoints/round-000040"
    assert lines[1].startswith("continue with: ") and lines[1].endswith(f"train --resume '{tmp_path}/my run'")
