"""Battle files, teams and scenario names (no engine needed)."""

from __future__ import annotations

import pytest

from confront.engine.battle import BattleSpec, Team, format_positions, robot_class, scenario_battle
from confront.engine.install import EngineNotFoundError, find_engine


def test_battle_file_keys() -> None:
    spec = BattleSpec(("SpinBot", "sample.Walls"), rounds=3, width=1000, height=800, gun_cooling_rate=0.2,
                      inactivity_time=100, initial_positions=((50.0, 60.0, 90.0), (None, None, None)))
    lines = dict(line.split("=", 1) for line in spec.battle_file().splitlines())
    assert lines["robocode.battleField.width"] == "1000"
    assert lines["robocode.battleField.height"] == "800"
    assert lines["robocode.battle.numRounds"] == "3"
    assert lines["robocode.battle.gunCoolingRate"] == "0.2"
    assert lines["robocode.battle.rules.inactivityTime"] == "100"
    assert lines["robocode.battle.selectedRobots"] == "sample.SpinBot,sample.Walls"
    assert lines["robocode.battle.initialPositions"] == "(50.0,60.0,90.0),(?,?,?)"
    assert spec.robot_count == 2


def test_scenarios_build_teams() -> None:
    spec = scenario_battle("4v6", "confront.ScriptBot", ["Walls", "Tracker"], rounds=5)
    ours, them = spec.contestants
    assert isinstance(ours, Team) and isinstance(them, Team)
    assert ours.members == ("confront.ScriptBot",) * 4
    assert them.members == ("sample.Walls", "sample.Tracker") * 3
    assert spec.robot_count == 10
    assert spec.selected_robots() == "confrontteams.Ours4*,confrontteams.Them6*"
    assert them.team_file().startswith("team.members=sample.Walls,sample.Tracker,sample.Walls,")
    assert scenario_battle("1v1", "SpinBot", "Walls").contestants == ("sample.SpinBot", "sample.Walls")
    melee = scenario_battle("melee", "SpinBot", ["Walls", "Tracker"])
    assert melee.contestants == ("sample.SpinBot", "sample.Walls", "sample.Tracker", "sample.Walls")


def test_a_sample_team_is_its_leader_and_droids() -> None:
    spec = scenario_battle("4v6", "SpinBot", "MyFirstTeam")
    them = spec.contestants[1]
    assert isinstance(them, Team) and them.name == "MyFirstTeam6"
    assert them.members == ("sampleteam.MyFirstLeader",) + ("sampleteam.MyFirstDroid",) * 5
    assert them.team_file().startswith("team.members=sampleteam.MyFirstLeader,sampleteam.MyFirstDroid,")
    assert robot_class("MyFirstDroid") == "sampleteam.MyFirstDroid"
    assert scenario_battle("1v1", "SpinBot", "TrackFire").contestants == ("sample.SpinBot", "sample.TrackFire")
    for scenario in ("1v1", "melee"):
        with pytest.raises(ValueError, match="MyFirstTeam needs teams of 2 or more robots"):
            scenario_battle(scenario, "SpinBot", "MyFirstTeam")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"rounds": 0}, "rounds"),
        ({"width": 300}, "field"),
        ({"gun_cooling_rate": 0.05}, "gun_cooling_rate"),
        ({"inactivity_time": -1}, "inactivity_time"),
        ({"initial_positions": ((-5.0, 10.0, 0.0),)}, "initial position"),
        ({"initial_positions": ((1.0, 1.0, 1.0),) * 3}, "initial_positions"),
    ],
)
def test_bad_battle_values(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        BattleSpec(("SpinBot", "Walls"), **kwargs)


def test_bad_names() -> None:
    with pytest.raises(ValueError, match="unknown robot"):
        robot_class("NoSuchBot")
    with pytest.raises(ValueError, match="scenario"):
        scenario_battle("3v3", "SpinBot", "Walls")
    with pytest.raises(ValueError, match="identifier"):
        Team("bad name", ("SpinBot",))
    assert format_positions([(1, 2.5, None)]) == "(1.0,2.5,?)"


def test_missing_engine_names_install_command(tmp_path) -> None:
    with pytest.raises(EngineNotFoundError, match="apt-get install -y robocode"):
        find_engine(tmp_path / "robocode.jar")
