"""The technique robots (confront.tech.*) in Robocode: listed from their jar, usable by name, as strong as issue 31
asks, and scoring in the simulator what they score in the engine."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from confront.arena.scenarios import get_scenario
from confront.arena.tech import TECH_ROBOTS as SIM_ROBOTS
from confront.arena.tech import tech_battle
from confront.engine.battle import BattleSpec, robot_class
from confront.engine.install import EngineInstall
from confront.engine.runner import EngineOptions, run_battle
from confront.engine.tech_robots import TECH_ROBOTS, main, write_tech_jar


def test_the_simulator_and_the_engine_know_the_same_robots() -> None:
    assert list(SIM_ROBOTS) == list(TECH_ROBOTS)
    assert robot_class("SurfGF") == "confront.tech.SurfGF 1.0"


def test_the_jar_holds_every_robot_with_its_properties(install: EngineInstall, tmp_path: Path) -> None:
    jar = write_tech_jar(tmp_path / "robots", install)
    assert jar.name == "confront-tech.jar"
    with zipfile.ZipFile(jar) as z:
        names = set(z.namelist())
        for robot in TECH_ROBOTS:
            assert f"confront/tech/{robot}.class" in names and f"confront/tech/{robot}.java" in names
            props = z.read(f"confront/tech/{robot}.properties").decode()
            assert f"robot.classname=confront.tech.{robot}\n" in props and "robot.version=1.0\n" in props
    assert main([str(tmp_path / "x.jar")]) == 0 and (tmp_path / "x.jar").is_file()
    assert main([]) == 2


def _share(robot: str, opponent: str, rounds: int, seed: int, extra: tuple[Path, ...] = ()) -> float:
    run = run_battle(BattleSpec((robot, opponent), rounds=rounds), EngineOptions(seed=seed, cpu_constant_ms=20.0),
                     extra_robots=extra)
    assert run.errors == ()
    totals = [r.total for r in run.results.robots]
    return totals[0] / sum(totals)


@pytest.mark.parametrize("opponent", ["Tracker", "SpinBot", "Walls", "Crazy"])
def test_the_strongest_robot_beats_the_sample_robots(install: EngineInstall, opponent: str) -> None:
    assert _share("SurfVG", opponent, rounds=10, seed=1) >= 0.85


def test_the_strongest_robot_beats_the_exported_tank(install: EngineInstall, tmp_path: Path) -> None:
    from click.testing import CliRunner

    from confront.cli.main import cli

    run_dir = Path(__file__).parents[2] / "docs" / "results" / "tanks" / "run"
    if not run_dir.is_dir():
        pytest.skip("no trained tank run in docs/results/tanks/run")
    jar = tmp_path / "tank.jar"
    res = CliRunner().invoke(cli, ["export", str(run_dir), "--out", str(jar)])
    assert res.exit_code == 0, res.output
    assert _share("SurfVG", "confront.TankBot 1.0", rounds=10, seed=1, extra=(jar,)) >= 0.70


@pytest.mark.parametrize("robots,seed", [(("OrbitVG", "SpinBot"), 1), (("SurfCircular", "OrbitLinear"), 2),
                                         (("StopGoCircular", "Fire"), 3)])
def test_shares_in_the_simulator_are_the_engines(install: EngineInstall, robots: tuple[str, str], seed: int) -> None:
    """10 rounds, one seeded battle in each: the contestants' shares within 2 points (benchmarks/technique_shares.py
    measures 100 rounds x 3 seeds)."""
    run = run_battle(BattleSpec(robots, rounds=10), EngineOptions(seed=seed, cpu_constant_ms=50.0))
    assert run.skipped_turns == {}
    eng = [r.total for r in run.results.robots]
    parts, _, _ = tech_battle(list(robots), 10, seed=seed, scenario=get_scenario("1v1"), rounds_per_battle=10)
    sim = parts.sum(axis=1)
    assert min(eng) > 0 or min(sim) > 0
    assert abs(eng[0] / sum(eng) - sim[0] / sim.sum()) <= 0.02


def test_confront_battle_plays_them_by_name_alike_in_both(install: EngineInstall) -> None:
    """``confront battle --robots SurfVG,SpinBot``: the simulator's table is Robocode's, every number."""
    from click.testing import CliRunner

    from confront.cli.main import cli

    tables = []
    for engine in ("sim", "robocode"):
        res = CliRunner().invoke(cli, ["battle", "--robots", "SurfVG,SpinBot", "--rounds", "3", "--seed", "1",
                                       "--engine", engine])
        assert res.exit_code == 0, res.output
        tables.append([[c.strip() for c in row.split("|")[3:-1]] for row in res.output.splitlines()
                       if row.startswith("| ") and row[2].isdigit()])
    assert len(tables[0]) == 2 and float(tables[0][0][0]) > 0
    assert tables[0] == tables[1]
    res = CliRunner().invoke(cli, ["battle", "--robots", "SurfVG,SpinBot", "--replay", "x.json"])
    assert res.exit_code == 2 and "sample robots only" in res.output
