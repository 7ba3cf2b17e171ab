"""The ``confront`` command. Each subcommand is a thin layer over a function of the package."""

from __future__ import annotations

import json
import re
import shlex
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

import click

from confront.checkpoint import CheckpointError
from confront.config import ConfigError
from confront.runs import Interrupted, command

USER_ERRORS: tuple[type[BaseException], ...] = (ConfigError, CheckpointError, FileExistsError, FileNotFoundError,
                                               NotADirectoryError, IsADirectoryError)
# optional packages (pyproject extras): a command that needs a missing one is a user's set-up, not a bug
EXTRAS = {"ray": "distributed", "pyarrow": "parquet", "stable_baselines3": "baselines", "torch": "baselines"}
SEED = click.IntRange(0, 2**32 - 1)
COUNT = click.IntRange(min=1)
ROUNDS = click.IntRange(1, 2**31 - 1)  # Robocode's numRounds is a Java int
ROBOCODE_CRASH = re.compile(rb"Exception in thread \"main\" [\w.$]+|java\.awt\.(AWTError|HeadlessException)")


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _short_path(name: object, limit: int = 100) -> str:
    text = str(name)
    return text if len(text) <= limit else f"{text[:limit // 2 - 2]}...{text[-(limit // 2 - 1):]}"


def _os_error(exc: OSError) -> str:
    """A file system's refusal (read-only, full, a name too long, no permission) in one line naming the path."""
    why = exc.strerror or _one_line(str(exc)) or type(exc).__name__
    where = [_short_path(f) for f in (exc.filename, exc.filename2) if f is not None]
    return f"{' -> '.join(where)}: {why}" if where else why


class Group(click.Group):
    """A click group that turns user mistakes into one line on stderr and exit code 2: bad options and
    arguments, configs, checkpoints, files, a missing engine or optional package."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except click.exceptions.Exit:
            raise
        except click.UsageError as exc:
            where = f" (see `{exc.ctx.command_path} --help`)" if exc.ctx is not None else ""
            click.echo(f"error: {_one_line(exc.format_message())}{where}", err=True)
            sys.exit(2)
        except Interrupted as stop:  # Ctrl-C during training: the checkpoint saved and how to go on
            click.echo(f"{stop}\ncontinue with: {command()} train --resume {shlex.quote(str(stop.run))}", err=True)
            sys.exit(130)
        except USER_ERRORS + _engine_errors() as exc:
            click.echo(f"error: {_one_line(str(exc))}", err=True)
            sys.exit(2)
        except OSError as exc:  # after the FileNotFoundError & co. above, whose messages are the project's own
            click.echo(f"error: {_one_line(_os_error(exc))}", err=True)
            sys.exit(2)
        except ModuleNotFoundError as exc:
            top = (exc.name or "").split(".")[0]
            if top not in EXTRAS:
                raise
            click.echo(f"error: this command needs the optional package {top!r}: "
                       f"pip install 'confront[{EXTRAS[top]}]'", err=True)
            sys.exit(2)


def _engine_errors() -> tuple[type[BaseException], ...]:
    try:
        from confront.engine import EngineNotFoundError
    except ImportError:
        return ()
    return (EngineNotFoundError,)


WATCH = click.option("--watch", is_flag=True, help="With --engine robocode: show the battles in Robocode's own window "
                     "as they play, at its display speed (needs a display).")


def set_option(f: Callable[..., Any]) -> Callable[..., Any]:
    return click.option(
        "--set", "overrides", multiple=True, metavar="KEY=VALUE",
        help="Override a config key, e.g. --set learner.alpha=0.2 (repeatable).",
    )(f)


@click.group(cls=Group, context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(package_name="confront")
def cli() -> None:
    """confront: fuzzy RL and curriculum transfer for teams of Robocode tanks."""


@cli.command()
@click.option("--out", type=click.Path(path_type=Path), default=None,
              help="Run folder (default runs/tanks-demo-<time>; with --paper runs/demo-<time>).")
@click.option("--rounds", type=COUNT, default=None, help="Rounds to train (default from the demo config).")
@click.option("--seed", type=SEED, default=None)
@click.option("--paper", is_flag=True, help="Train the paper's 4v4 fuzzy DMNN arm instead (config demo).")
@click.option("--contrast", is_flag=True, help="Also train the paper's arm and plot both against the TD team.")
@set_option
def demo(out: Path | None, rounds: int | None, seed: int | None, paper: bool, contrast: bool,
         overrides: tuple[str, ...]) -> None:
    """Train PPO tanks against the TD team, a dodging team and sample robots, then print and plot the results."""
    from confront.experiments.demo import run_demo

    if paper and contrast:
        raise click.UsageError("--contrast trains both arms; leave out --paper")
    run_demo(out=out, rounds=rounds, seed=seed, overrides=overrides, paper=paper, contrast=contrast)


@cli.command()
@click.option("-c", "--config", "config", default="demo", show_default=True,
              help="Experiment name (see `confront config list`) or a TOML file.")
@click.option("--out", type=click.Path(path_type=Path), default=None, help="Run folder to create.")
@click.option("--resume", type=click.Path(path_type=Path, exists=True, file_okay=False), default=None,
              help="Continue the run in this folder from its latest checkpoint (with its own config).")
@click.option("--seed", type=SEED, default=None)
@click.option("--engine", type=click.Choice(["sim", "robocode"]), default="sim", show_default=True,
              help="Train in the simulator or live in the real Robocode engine (checkpointed per battle).")
@click.option("--init", "init", type=click.Path(path_type=Path, exists=True, file_okay=False), default=None,
              help="PPO: start from this run's model (model/ppo.npz), e.g. fine-tune a simulator run with "
                   "--engine robocode (train.init).")
@click.option("--address", default=None, metavar="ray://HOST:PORT|HOST:PORT|auto",
              help="PPO: collect the rollouts on Ray actors of this cluster (one learner here; "
                   "docs/learning.md, \"Scale-out on Ray\").")
@click.option("--workers", type=COUNT, default=None,
              help="With --address: rollout workers, one CPU each (default 1; a resumed run keeps its own).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
@set_option
def train(config: str, out: Path | None, resume: Path | None, seed: int | None, engine: str, init: Path | None,
          address: str | None, workers: int | None, quiet: bool, overrides: tuple[str, ...]) -> None:
    """Train one arm of an experiment; --resume RUN continues a killed run from its latest checkpoint; --address
    collects PPO's rollouts on Ray actors."""
    from confront.train.factory import train_run
    from confront.train.loop import print_summary
    from confront.train.spec import load_experiment

    if resume is not None:  # a resumed run continues with its own config.toml and folder
        given = [name for name, value in (("--set", overrides), ("--out", out), ("--seed", seed), ("--init", init))
                 if value not in (None, ())]
        if click.get_current_context().get_parameter_source("config") is click.core.ParameterSource.COMMANDLINE:
            given.insert(0, "-c")
        if given:
            raise click.UsageError(f"--resume continues {resume} with its own config and folder: drop "
                                   f"{', '.join(given)} (or start a new run without --resume)")
    if resume is not None:
        summary = train_run(None, resume, resume=True, progress=not quiet, engine=engine, address=address,
                            workers=workers)
    else:
        extra: tuple[str, ...] = (f"train.seed={seed}",) if seed is not None else ()
        if init is not None:  # absolute: the run's config.toml must find it from anywhere
            extra += (f"train.init={json.dumps(str(init.resolve()))}",)
        cfg = load_experiment(config, overrides + extra)
        summary = train_run(cfg, out, progress=not quiet, engine=engine, address=address, workers=workers)
    print_summary(summary)


@cli.command()
@click.argument("run", type=click.Path(path_type=Path, exists=True, file_okay=False))
@click.option("--engine", type=click.Choice(["sim", "robocode"]), default="sim", show_default=True)
@click.option("--opponents", default=None, metavar="LIST",
              help="Comma list of opponents (default: the run's). PPO tank runs: league entries SCENARIO:NAME, "
                   "e.g. 1v1:SpinBot,4v4:td (a bare NAME is 1v1:NAME); paper runs: td or a scripted robot "
                   "(SpinBot, Walls, Tracker, RamFire, ...) or a sample team (MyFirstTeam).")
@click.option("--rounds", type=ROUNDS, default=100, show_default=True)
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--play", type=click.Choice(["sampled", "greedy"]), default=None,
              help="PPO tanks: sample each action head (the default, as `confront export` plays) or take its "
              "maximum. Paper policies always play greedily.")
@WATCH
def evaluate(run: Path, engine: str, opponents: str | None, rounds: int, seed: int, play: str | None,
             watch: bool) -> None:
    """Play a trained policy (simulator or real engine) and print its score table."""
    from confront.engine.tank_export import Play
    from confront.experiments.evaluate import evaluate_cli

    evaluate_cli(run, engine=engine, opponents=opponents, rounds=rounds, seed=seed, play=cast(Play | None, play),
                 watch=watch)


@cli.command()
@click.argument("experiment", type=click.Choice(["migration", "awm", "fuzzy", "transfer", "baselines", "all"]))
@click.option("--seeds", type=COUNT, default=None, help="Seeds per arm, at least 1 (default 10; migration alone 1000).")
@click.option("--rounds", type=ROUNDS, default=None, help="Rounds per arm (default from the config).")
@click.option("--engine", type=click.Choice(["sim", "robocode"]), default="sim", show_default=True)
@click.option("--out", type=click.Path(path_type=Path), default=None, help="Output folder (default results/).")
@click.option("--workers", type=COUNT, default=None, help="Parallel worker processes (default: all cores).")
@set_option
def reproduce(experiment: str, seeds: int | None, rounds: int | None, engine: str, out: Path | None,
              workers: int | None, overrides: tuple[str, ...]) -> None:
    """Re-run an experiment of the paper over seeds: metrics, figures with bands and report.md."""
    from confront.experiments.reproduce import reproduce_cli

    reproduce_cli(experiment, seeds=seeds, rounds=rounds, engine=engine, out=out, workers=workers,
                  overrides=overrides)


@cli.command()
@click.argument("grid", type=click.Path(path_type=Path, exists=True, dir_okay=False))
@click.option("--out", type=click.Path(path_type=Path), required=True, help="Sweep folder (resumable).")
@click.option("--address", default=None, help="Ray cluster address (default: start Ray locally).")
@click.option("--seeds", type=int, default=None, help="Seeds per config (overrides the grid file).")
def sweep(grid: Path, out: Path, address: str | None, seeds: int | None) -> None:
    """Run a grid of configs x seeds on Ray; re-running resumes and skips finished trials."""
    from confront.experiments.sweep import sweep_cli

    sweep_cli(grid, out=out, address=address, seeds=seeds)


@cli.command()
@click.option("--scenario", default="1v1", show_default=True)
@click.option("--robots", default=None, help="Comma list of robots/teams (default: the scenario's).")
@click.option("--engine", type=click.Choice(["sim", "robocode"]), default="sim", show_default=True)
@click.option("--rounds", type=ROUNDS, default=10, show_default=True)
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--battles", type=COUNT, default=1, show_default=True,
              help="Simulator: split the rounds over this many parallel battles (faster; battle b has seed+b).")
@click.option("--replay", "replay_out", type=click.Path(path_type=Path), default=None,
              help="Also record the first round to this replay file (.json or .json.gz, plus .gif and .html; "
                   "simulator only).")
@WATCH
def battle(scenario: str, robots: str | None, engine: str, rounds: int, seed: int, battles: int,
           replay_out: Path | None, watch: bool) -> None:
    """Run a battle of scripted robots in the simulator or the real engine and print Robocode's score table."""
    from confront.experiments.evaluate import battle_cli

    battle_cli(scenario=scenario, robots=robots, engine=engine, rounds=rounds, seed=seed, replay_out=replay_out,
               battles=battles, watch=watch)


@cli.command()
@click.argument("robots", nargs=-1, type=click.Path(path_type=Path, exists=True))
@click.option("--workdir", type=click.Path(path_type=Path, file_okay=False), default=None,
              help="Robocode's working directory (default: Debian's, ~/.local/share/robocode/1.9.3.9).")
def robocode(robots: tuple[Path, ...], workdir: Path | None) -> None:
    """Open Robocode's own program (its window and New Battle dialog) with the Java 17 flags Debian's launcher
    lacks, after copying ROBOTS into its robots folder: robot jars (confront export), or trained run folders
    (exported here as confront-TankBot.jar / confront-PolicyBot.jar)."""
    import tempfile

    from confront.engine.desktop import open_robocode, robocode_workdir
    from confront.engine.install import find_engine, require_display
    from confront.experiments.evaluate import run_jar

    install = find_engine()
    with tempfile.TemporaryDirectory(prefix="confront-robocode-") as tmp:
        try:
            require_display("Robocode's window")  # before exporting anything
            jars = [run_jar(r, Path(tmp)) if r.is_dir() else r for r in robots]
            if len({j.name for j in jars}) < len(jars):  # they would land on one file of the robots folder
                raise ValueError("two of the robots are one jar name (two runs of one kind, or a jar of that name): "
                                 "give one of them")
            proc = open_robocode(install, jars, workdir, wait=False)  # checks the jars; copies them in
        except ValueError as err:
            raise click.UsageError(str(err)) from None
    wd = robocode_workdir(install, workdir)
    log = wd / "confront-robocode.log"
    click.echo(f"Robocode (working directory {wd}; {len(jars)} robot jar(s) copied into its robots folder): "
               "close its window to return")
    proc.wait()
    crashed = ROBOCODE_CRASH.search(log.read_bytes()[-(1 << 20):]) if log.is_file() else None
    if proc.returncode != 0:
        raise click.ClickException(f"Robocode exited with code {proc.returncode} (see {log})")
    if crashed:  # Robocode exits 0 after an uncaught exception of its window
        raise click.ClickException(f"Robocode failed ({crashed.group(0).decode()}; see {log})")


@cli.command()
@click.argument("run", type=click.Path(path_type=Path, exists=True, file_okay=False))
@click.option("--out", type=click.Path(path_type=Path), required=True, help="Robots folder or .jar to write.")
@click.option("--play", type=click.Choice(["sampled", "greedy"]), default=None,
              help="PPO tanks: draw each action head from its softmax, as it trained (Robocode's seeded random; "
              "the default), or take the first maximum of each head.")
def export(run: Path, out: Path, play: str | None) -> None:
    """Export a trained policy as a standalone Robocode robot (no Python needed to run it)."""
    from confront.engine.tank_export import Play, export_tank_cli, is_tank_run
    from confront.experiments.evaluate import export_cli

    if out.suffix not in ("", ".jar") and not out.is_dir():  # x.zip would silently become a folder named x.zip
        raise click.UsageError(f"--out {out} must be a robots folder (a name without a suffix, or an existing folder) "
                               "or a .jar")
    if is_tank_run(run):  # a PPO run over the tank view: confront.TankBot
        export_tank_cli(run, out=out, play=cast(Play, play or "sampled"))  # click checked it is one of the two
        return
    if play is not None:
        raise click.UsageError("--play is for PPO tank runs (paper policies play their own rule)")
    export_cli(run, out=out, name=None)


@cli.command()
@click.argument("candidate")
@click.argument("folder", type=click.Path(path_type=Path))
@click.option("--mode", type=click.Choice(["1v1", "teams", "melee"]), default="1v1", show_default=True,
              help="1v1; teams (a team of --team-size of the candidate against as many of each robot, or each team "
              "jar); melee (the candidate among up to 9 others).")
@click.option("--seeds", type=COUNT, default=1, show_default=True, help="Battles per opponent (engine seeds 0..N-1).")
@click.option("--rounds", type=COUNT, default=None, help="Rounds per battle (default: the RoboRumble's, 35; teams 10).")
@click.option("--field", default=None, help="WIDTHxHEIGHT (default 800x600; melee 1000x1000; teams 1200x1200).")
@click.option("--cpu-constant", type=float, default=10.0, show_default=True, help="Robot time per turn, ms.")
@click.option("--team-size", type=click.IntRange(1, 10), default=4, show_default=True)
@click.option("--workers", type=COUNT, default=None, help="Battles at once on this machine (default: its cores).")
@click.option("--address", default=None, help="Run each battle as a task on this Ray cluster (ray://HOST:PORT, auto).")
@click.option("--timeout", type=click.FloatRange(min=1), default=None,
              help="Seconds after which a battle's JVM is killed (default from rounds and robots).")
@click.option("--out", type=click.Path(path_type=Path, file_okay=False), default=None,
              help="Output folder (resumable; default rumbles/<candidate>-<mode>).")
@click.option("--one-cpu", is_flag=True, help="Each battle's JVM on one CPU of its own, C1 compiler only (faster on a "
              "small machine; the engine's thread races may go the other way: docs/engine.md).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def rumble(candidate: str, folder: Path, mode: str, seeds: int, rounds: int | None, field: str | None,
           cpu_constant: float, team_size: int, workers: int | None, address: str | None, timeout: float | None,
           out: Path | None, one_cpu: bool, quiet: bool) -> None:
    """CANDIDATE (a trained run folder, a robot jar or a class such as sample.Tracker) against every robot of the
    jars in FOLDER, in the real engine: a table per opponent (APS, survival, bullet damage, 95% interval)."""
    from confront.experiments.rumble import rumble_cli

    rumble_cli(candidate, folder, mode=mode, seeds=seeds, rounds=rounds, field=field, cpu_constant=cpu_constant,
               team_size=team_size, workers=workers, address=address, out=out, timeout=timeout, one_cpu=one_cpu,
               quiet=quiet)


@cli.command()
@click.argument("source", type=click.Path(path_type=Path, exists=True))
@click.option("--out", type=click.Path(path_type=Path, file_okay=False), default=None,
              help="Folder to write the GIF and HTML player into (default: beside each replay file).")
def replay(source: Path, out: Path | None) -> None:
    """Write a GIF and a self-contained HTML player for a replay file or a run's replays."""
    from confront.experiments.evaluate import replay_cli

    replay_cli(source, out=out)


@cli.command()
@click.argument("what", type=click.Choice(["sim", "learner", "env", "bridge", "reproduce", "train", "all"]),
                default="sim")
@click.option("--plot", type=click.Path(path_type=Path), is_flag=False, flag_value=Path("sim_scaling.png"),
              default=None, help="sim only: write the scaling figure (throughput against batch size and threads) "
                                 "to this PNG (default sim_scaling.png) instead of the table.")
@click.option("--json", "as_json", is_flag=True,
              help="sim and env: also print the records as one JSON list on the last line.")
def bench(what: str, plot: Path | None, as_json: bool) -> None:
    """Run a benchmark script from benchmarks/ and print its table."""
    from confront.experiments.evaluate import JSON_BENCHES, bench_cli

    if as_json and what not in JSON_BENCHES:
        raise click.UsageError(f"--json is for {' and '.join(JSON_BENCHES)}")
    if plot is None:
        bench_cli(what, as_json=as_json)
        return
    if what != "sim":
        raise click.UsageError("--plot is for `confront bench sim`")
    import subprocess

    script = Path(__file__).resolve().parents[2] / "benchmarks" / "sim_throughput.py"
    if not script.is_file():
        raise FileNotFoundError("benchmarks/ is not here: run `confront bench` from a source checkout")
    subprocess.run([sys.executable, str(script), "--plot", str(plot), *(["--json"] if as_json else [])], check=False)


@cli.group(cls=Group)
def config() -> None:
    """Show experiment configs."""


@config.command("list")
def config_list() -> None:
    """List the packaged experiment configs."""
    from confront.train.spec import list_experiments

    for name in list_experiments():
        click.echo(name)


@config.command("show")
@click.argument("experiment")
@set_option
def config_show(experiment: str, overrides: tuple[str, ...]) -> None:
    """Print the fully resolved config of EXPERIMENT (a name or a TOML file) as TOML."""
    from confront.config import to_dict, to_toml
    from confront.train.spec import load_experiment

    click.echo(to_toml(to_dict(load_experiment(experiment, overrides))), nl=False)


@cli.group(cls=Group)
def plot() -> None:
    """Draw the paper's figures that need no training."""


@plot.command("fuzzy")
@click.option("--out", type=click.Path(path_type=Path), default=Path("fuzzy_learning_rate.png"), show_default=True)
def plot_fuzzy_cmd(out: Path) -> None:
    """Figure 13: the fuzzy learning rate as a function of the reward."""
    from confront.learning.fuzzy import plot_fuzzy

    try:
        written = plot_fuzzy(out)
    except ValueError as err:
        raise click.UsageError(str(err)) from None
    click.echo(f"wrote {written}")


def main() -> None:
    cli(prog_name="confront")


if __name__ == "__main__":
    main()
