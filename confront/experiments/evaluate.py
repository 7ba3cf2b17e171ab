"""Evaluating, exporting, replaying and battling: the commands that use a trained model or scripted robots."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
import numpy as np

from confront.arena.scenarios import Scenario
from confront.arena.smdp import TeamBattleEnv
from confront.config import load_toml
from confront.learning.base import Learner
from confront.results import BattleResults, ScoreRow
from confront.train.episodes import Loop, Side
from confront.train.paper_model import load_model, scenario_of, smdp_config
from confront.train.spec import ExperimentConfig, config_from_dict

if TYPE_CHECKING:
    from confront.engine.tank_export import Play

SIM_SEEDS = 5  # simulator seeds per opponent: the simulator is cheap, and their spread shows a ratio's noise
SIM_BATTLES = 16  # battles side by side in a simulator evaluation
PARTS = ("survival", "last_survivor", "bullet_damage", "bullet_kill_bonus", "ram_damage", "ram_kill_bonus")


def _run_config(run: Path) -> ExperimentConfig:
    if not (run / "config.toml").exists():
        raise FileNotFoundError(f"{run} is not a run folder (no config.toml)")
    return config_from_dict(load_toml(run / "config.toml"))


def results_from_rows(rows: list[dict[str, Any]], names: tuple[str, str]) -> BattleResults:
    """Team-level score table (Robocode's columns) from per-round rows of a simulator run."""
    out = []
    for side, name in zip(("ours", "theirs"), names, strict=True):
        parts = {p: sum(float(r[f"{p}_{side}"]) for r in rows) for p in PARTS}
        wins = sum(1 for r in rows if (r["won"] if side == "ours" else (r["decided"] and not r["won"])))
        out.append(ScoreRow(name, sum(parts.values()), parts["survival"], parts["last_survivor"],
                            parts["bullet_damage"], parts["bullet_kill_bonus"], parts["ram_damage"],
                            parts["ram_kill_bonus"], firsts=wins, seconds=len(rows) - wins, team=name))
    out.sort(key=lambda r: -r.total)
    return BattleResults(rounds=max(1, len(rows)), contestants=tuple(out), engine="sim")


def sim_evaluate(cfg: ExperimentConfig, learner: Learner, opponent: str, rounds: int, seed: int,
                 td_model: str | None = None, battles: int = SIM_BATTLES, opponent_learner: Learner | None = None
                 ) -> list[dict[str, Any]]:
    """Play ``learner`` greedily (no exploration, no learning) against ``opponent`` in the simulator; ``"td"``:
    the TD team of ``td_model``, or ``opponent_learner`` (greedy, e.g. the dodge's move values) when given.

    The rounds are shared out over the battles beforehand (``rounds // battles``, one more for the first
    ``rounds % battles``) and each battle's first rounds are kept: taking the first ``rounds`` rounds to
    finish anywhere would favour short rounds (the longer ones still running are cut)."""
    if rounds < 1:
        raise ValueError(f"rounds must be >= 1, got {rounds}")
    n_b = min(battles, rounds)
    env = TeamBattleEnv(scenario_of(cfg.arena.scenario), n_battles=n_b, seed=seed,
                        opponents=opponent, config=smdp_config(cfg))
    team = env.team_ids()
    side = Side(learner, ours=team == 0)
    if opponent == "td":
        if opponent_learner is not None:
            side.opponent = opponent_learner
        elif not td_model:
            raise FileNotFoundError("evaluating against the TD team needs the run's TD model (summary.json td_model)")
        else:
            side.opponent, _ = load_model(td_model)
        side.theirs = team != 0
    loop = Loop(env, side, seed=seed, learning=False)
    quota = [rounds // n_b + (b < rounds % n_b) for b in range(n_b)]
    per: list[list[dict[str, Any]]] = [[] for _ in range(n_b)]
    while any(len(rows) < q for rows, q in zip(per, quota, strict=True)):
        for row in loop.step():
            per[row["battle"]].append(row)
    out = [row for rows, q in zip(per, quota, strict=True) for row in rows[:q]]
    for k, row in enumerate(out):
        row["round"] = k + 1
    return out


def exported_policy(learner: Learner, cfg: ExperimentConfig) -> Any:
    """The learner as the engine's ExportedPolicy (the same greedy decisions, in Java or through the bridge)."""
    from confront.engine.export import ExportedPolicy

    if cfg.arena.fire_power_actions:
        raise click.UsageError("export supports the paper's four moves only (arena.fire_power_actions = false)")
    return ExportedPolicy.from_learner(learner, observation=smdp_config(cfg).observation,
                                       step_turns=cfg.arena.decision_turns)


def disjoint_seeds(seed: int, n: int, rounds: int, battles: int = SIM_BATTLES) -> list[int]:
    """``n`` evaluation seeds from ``seed`` whose battles share no seed: battle b of a run with seed s is
    seeded s + b (``Arena.seed``), so consecutive seeds would replay all but one battle."""
    step = min(battles, rounds)
    return [seed + k * step for k in range(n)]


def sim_ratios(cfg: ExperimentConfig, learner: Learner, opponent: str, rounds: int, seeds: list[int],
               td_model: str | None = None) -> list[float]:
    """Our score ratio in the simulator against ``opponent`` over ``rounds`` rounds, one per seed."""
    return [results_from_rows(sim_evaluate(cfg, learner, opponent, rounds, s, td_model), ("ours", opponent))
            .score_ratio("ours") for s in seeds]


def evaluate_cli(run: Path, engine: str, opponents: str | None, rounds: int, seed: int,
                 sim_seeds: int = SIM_SEEDS, play: Play | None = None, watch: bool = False) -> None:
    """Score tables of the run's policy per opponent, in the simulator (seed ``seed``, and the range
    over ``sim_seeds`` runs with disjoint battle seeds from ``seed`` on) and with ``engine="robocode"`` in the
    real engine (``watch``: in Robocode's battle window). ``play``: PPO tanks sample their heads (``"sampled"``,
    the default) or take the maximum (``"greedy"``); paper policies play greedily and take no ``play``."""
    if sim_seeds < 1:
        raise ValueError(f"sim_seeds must be >= 1, got {sim_seeds}")
    _check_watch(watch, engine)
    from confront.engine.tank_export import is_tank_run

    if is_tank_run(run):  # PPO tanks: per league entry (the engine: the exported TankBot)
        from confront.experiments.tank_evaluate import evaluate_tank_cli

        evaluate_tank_cli(run, opponents, rounds, seed, play=play or "sampled")
        if engine == "robocode":
            from confront.experiments.tank_evaluate import evaluate_tank_engine_cli

            evaluate_tank_engine_cli(run, opponents, rounds, seed, play=play or "sampled", visible=watch)
        return
    if play is not None:
        raise click.UsageError("--play is for PPO tank runs (paper policies play greedily)")
    cfg = _run_config(run)
    learner, _ = load_model(run)
    summary = json.loads((run / "summary.json").read_text()) if (run / "summary.json").exists() else {}
    names = [o.strip() for o in (opponents or cfg.opponent.kind).split(",") if o.strip()]
    from confront.arena.bots import BOT_NAMES
    from confront.arena.scenarios import SAMPLE_TEAMS, opponent_members
    from confront.arena.tech import TECH_ROBOTS

    for name in names:
        if name != "td" and name not in BOT_NAMES and name not in SAMPLE_TEAMS and name not in TECH_ROBOTS:
            raise click.UsageError(f"unknown opponent {name!r} in --opponents: use td, {', '.join(BOT_NAMES)}, a "
                                   f"sample team ({', '.join(SAMPLE_TEAMS)}) or a technique robot "
                                   f"({', '.join(TECH_ROBOTS)})")
        try:
            opponent_members(scenario_of(cfg.arena.scenario), name)
        except ValueError as err:
            raise click.UsageError(f"--opponents {name} in the run's scenario {cfg.arena.scenario}: {err}") from None
    seeds = disjoint_seeds(seed, sim_seeds, rounds)
    lines = [f"| opponent | rounds | score ratio (simulator) | simulator, {sim_seeds} seeds (min-max) "
             "| score ratio (robocode) | difference |", "|---|---:|---:|---:|---:|---:|"]
    for name in names:
        rows = sim_evaluate(cfg, learner, name, rounds, seed, summary.get("td_model"))
        sim = results_from_rows(rows, ("ours", name))
        sim_ratio = sim.score_ratio("ours")
        spread = [sim_ratio] + sim_ratios(cfg, learner, name, rounds, seeds[1:], summary.get("td_model"))
        click.echo(f"\n{name} in the simulator ({rounds} rounds):\n{sim.to_markdown()}")
        real = ""
        diff = ""
        if engine == "robocode":
            if name == "td":
                raise click.UsageError("the TD team is not available in the real engine: pass --opponents "
                                       "SpinBot,Walls,Tracker,RamFire")
            from confront.engine.evaluate import evaluate_policy

            res, ratio = evaluate_policy(exported_policy(learner, cfg), cfg.arena.scenario, name, rounds=rounds,
                                         seed=seed, visible=watch)
            click.echo(f"{name} in Robocode ({rounds} rounds, {res.skipped_turns} skipped turns):\n"
                       f"{res.to_markdown()}")
            real, diff = f"{ratio:.3f}", f"{ratio - sim_ratio:+.3f}"
        lines.append(f"| {name} | {rounds} | {sim_ratio:.3f} | {min(spread):.3f}-{max(spread):.3f} | {real} | {diff} |")
    click.echo("\n" + "\n".join(lines) + f"\n(simulator seeds {', '.join(map(str, seeds))}: no battle in common)")


def sim_bot_battle(scenario: str, robots: list[str], rounds: int, seed: int, n_battles: int = 1) -> BattleResults:
    """Scripted robots in the simulator: one name per team (a team is filled with copies of its robot, or with a
    sample team's leader and droids).

    ``n_battles = 1`` plays one battle of ``rounds`` rounds as Robocode does (robots such as Corners remember
    across rounds; with the engine's seed the start positions and processing order are the engine's); more
    battles split the rounds for speed (battle b is seeded ``seed + b``). Technique robots (``confront.arena.tech``)
    keep their battle memory for 35 rounds, as the Java robots' static fields live for a RoboRumble battle.
    """
    from confront.arena.bots import bot_battle
    from confront.arena.scoring import results_table
    from confront.arena.tech import TECH_ROBOTS, tech_battle

    sc = scenario_of(scenario)
    team = np.asarray(sc.team_ids())
    names = _robot_names(sc, robots)
    if any(n in TECH_ROBOTS for n in names):
        parts, places, _ = tech_battle(names, rounds, seed=seed, n_battles=n_battles, scenario=sc)
    else:
        parts, places = bot_battle(names, rounds, seed=seed, n_battles=n_battles, scenario=sc)
    labels = [name if size == 1 else f"{name} team {k}"
              for k, (name, size) in enumerate(zip(robots, sc.teams, strict=True))]
    return results_table(parts, places, team, labels, rounds=rounds)


def _robot_names(sc: Scenario, robots: list[str]) -> list[str]:
    """One bot name per robot from one name per team (copies of a robot, or a sample team's leader and droids)."""
    from confront.arena.scenarios import team_members

    if len(robots) != len(sc.teams):
        raise click.UsageError(f"scenario {sc.name} has {len(sc.teams)} teams: give {len(sc.teams)} robots, "
                               f"got {','.join(robots)}")
    try:
        return [n for name, size in zip(robots, sc.teams, strict=True) for n in team_members(name, size)]
    except ValueError as err:
        raise click.UsageError(str(err)) from None


def record_bot_round(scenario: str, robots: list[str], seed: int, out: Path) -> Path:
    """The first round of a scripted battle (the same battle as ``sim_bot_battle`` with one battle) as a replay
    file ``out`` (.json or .json.gz) with a GIF and an HTML player beside it."""
    from confront.arena import replay as rp
    from confront.arena.bots import ScriptedBots
    from confront.arena.core import Arena

    sc = scenario_of(scenario)
    arena = Arena(sc.replace(max_turns=100000), 1, seed=seed)
    names = _robot_names(sc, robots)
    bots = ScriptedBots(arena, names)
    replay = rp.new_replay(arena, [f"{n} ({i})" for i, n in enumerate(names)])
    cmd = arena.idle_commands()
    rp.record_frame(replay, arena)
    while not arena.state.done[0]:
        bots.commands(cmd)
        arena.step(cmd)
        rp.record_frame(replay, arena)
    out.parent.mkdir(parents=True, exist_ok=True)
    path = replay.save(out)
    stem = out.name.removesuffix(".gz").removesuffix(".json").removesuffix(".replay")
    rp.write_gif(replay, out.with_name(stem + ".gif"))
    rp.write_html(replay, out.with_name(stem + ".html"), title=f"confront: {' vs '.join(robots)}")
    return Path(path)


def _check_watch(watch: bool, engine: str) -> None:
    """``--watch`` shows Robocode's own battle window: the real engine only, and a display."""
    if not watch:
        return
    if engine != "robocode":
        raise click.UsageError("--watch shows Robocode's own battle window: use it with --engine robocode "
                               "(simulator battles are watched with --replay or confront replay)")
    from confront.engine.install import require_display

    try:
        require_display("--watch")
    except ValueError as err:
        raise click.UsageError(str(err)) from None


def battle_cli(scenario: str, robots: str | None, engine: str, rounds: int, seed: int,
               replay_out: Path | None, battles: int = 1, watch: bool = False) -> None:
    _check_watch(watch, engine)
    sc = scenario_of(scenario)
    from confront.arena.bots import BOT_NAMES
    from confront.arena.scenarios import SAMPLE_TEAMS
    from confront.arena.tech import TECH_ROBOTS

    default = [("SpinBot", "Walls", "Tracker", "RamFire", "Crazy", "Fire", "Corners", "SittingDuck")[i % 8]
               for i in range(len(sc.teams))]
    names = [r.strip() for r in robots.split(",")] if robots else default
    for n in names:
        if n not in BOT_NAMES and n not in SAMPLE_TEAMS and n not in TECH_ROBOTS:
            raise click.UsageError(f"unknown robot {n!r}: use {', '.join(BOT_NAMES)}, a sample team "
                                   f"({', '.join(SAMPLE_TEAMS)}) or a technique robot ({', '.join(TECH_ROBOTS)})")
    if replay_out is not None and any(n in TECH_ROBOTS for n in names):
        raise click.UsageError("--replay records battles of sample robots only")
    if battles < 1:
        raise click.UsageError(f"--battles must be >= 1, got {battles}")
    if engine == "robocode":
        from confront.engine.runner import run_scenario

        if replay_out is not None:
            raise click.UsageError("--replay records simulator battles only")
        if len(names) != 2:
            raise click.UsageError("--engine robocode battles take two sides: --robots OURS,THEIRS")
        run = run_scenario(sc.name, names[0], names[1], rounds=rounds, seed=seed, visible=watch)
        click.echo(f"Robocode, {sc.name}, {rounds} rounds ({run.turns} turns, {run.elapsed_s:.1f} s, "
                   f"{sum(run.skipped_turns.values())} skipped turns):\n{run.results.to_markdown()}")
        return
    where = sc.name if not scenario.endswith(".toml") else scenario
    res = sim_bot_battle(where, names, rounds, seed, n_battles=battles)
    click.echo(f"simulator, {sc.name}, {rounds} rounds:\n{res.to_markdown()}")
    if replay_out is not None:
        path = record_bot_round(where, names, seed, replay_out)
        click.echo(f"replay of the first round: {path} (and .gif, .html beside it)")


def run_jar(run: Path, folder: Path, play: Play = "sampled") -> Path:
    """A trained run's robot as a jar in ``folder``: ``confront-TankBot.jar`` for PPO tanks (playing ``play``),
    ``confront-PolicyBot.jar`` for the paper's policies; always the same name per robot, so that a newer export
    replaces an older one in a robots folder (both would hold the same robot class)."""
    from confront.engine.export import export_robot
    from confront.engine.tank_export import export_tank_robot, is_tank_run, load_tank_policy

    if is_tank_run(run):
        return export_tank_robot(load_tank_policy(run, play), Path(folder) / "confront-TankBot.jar")
    if not (run / "config.toml").is_file():
        raise FileNotFoundError(f"{run} is not a trained run folder (no config.toml): give a run or a robot jar")
    learner, _ = load_model(run)
    return export_robot(exported_policy(learner, _run_config(run)), Path(folder) / "confront-PolicyBot.jar")


def export_cli(run: Path, out: Path, name: str | None) -> None:
    from confront.engine.export import ROBOTS_FOLDER_HINT, export_robot

    if out.exists() and not out.is_dir() and out.suffix != ".jar":
        raise FileExistsError(f"--out {out} is an existing file: give a robots folder or a .jar path")
    cfg = _run_config(run)
    learner, _ = load_model(run)
    folder = export_robot(exported_policy(learner, cfg), out)
    click.echo(f"wrote the robot confront.PolicyBot and the team confront.PolicyTeam (4 PolicyBots) to {folder}: copy "
               f"it into Robocode's robots folder ({ROBOTS_FOLDER_HINT}; no Python needed to run it)"
               + (f", or open Robocode with it: confront robocode {folder}" if folder.suffix == ".jar" else ""))




def replay_cli(source: Path, out: Path | None) -> None:
    from confront.arena.replay import export_replays

    try:
        written = export_replays(source, out)
    except ValueError as exc:
        raise FileNotFoundError(str(exc)) from None
    for path in written:
        click.echo(f"wrote {path}")


BENCHES = {"sim": "sim_throughput.py", "learner": "learner_throughput.py", "env": "env_throughput.py",
           "bridge": "bridge_throughput.py", "reproduce": "reproduce_time.py", "train": "train_throughput.py"}


JSON_BENCHES = ("sim", "env")  # scripts whose --json prints their records as the last line


def bench_cli(what: str, as_json: bool = False) -> None:
    root = Path(__file__).resolve().parents[2] / "benchmarks"
    if not root.is_dir():
        raise FileNotFoundError("benchmarks/ is not here: run `confront bench` from a source checkout")
    for key in (BENCHES if what == "all" else [what]):
        script = root / BENCHES[key]
        click.echo(f"== {script.name}")
        subprocess.run([sys.executable, str(script), *(["--json"] if as_json and key in JSON_BENCHES else [])],
                       check=False)
