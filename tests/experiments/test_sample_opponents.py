"""TrackFire and Robocode's sample team (MyFirstTeam: MyFirstLeader and MyFirstDroids) as opponents everywhere: the
configs, `confront battle`, the pool of the PPO tanks; the same names in the simulator, the configs and the engine."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from confront.arena import bots
from confront.arena.scenarios import SAMPLE_TEAMS, get_scenario
from confront.cli.main import cli
from confront.config import ConfigError
from confront.engine import battle
from confront.train import spec
from confront.train.spec import load_experiment


def test_the_opponent_names_agree_everywhere() -> None:
    members = {r for team in SAMPLE_TEAMS.values() for r in team}
    assert set(spec.SCRIPTED_BOTS) | members == set(bots.BOT_NAMES)
    assert set(spec.SCRIPTED_BOTS) <= set(battle.SAMPLE_ROBOTS)
    assert set(battle.SAMPLE_TEAM_ROBOTS) == members


def test_configs_take_them_where_they_fit() -> None:
    cfg = load_experiment("tanks", ['league.opponents=["1v1:TrackFire", "4v4:MyFirstTeam", "4v10:MyFirstTeam"]',
                                    "league.focus=[]"])
    assert cfg.league.opponents == ("1v1:TrackFire", "4v4:MyFirstTeam", "4v10:MyFirstTeam")
    assert load_experiment("demo", ["opponent.kind=MyFirstTeam"]).opponent.kind == "MyFirstTeam"
    assert load_experiment("demo", ["opponent.kind=TrackFire", "arena.scenario=1v1"]).opponent.kind == "TrackFire"
    with pytest.raises(ConfigError, match="'1v1:MyFirstTeam' is not allowed: MyFirstTeam needs teams of 2 or more"):
        load_experiment("tanks", ['league.opponents=["1v1:MyFirstTeam"]', "league.focus=[]"])
    with pytest.raises(ConfigError, match="arena.scenario = 'melee': MyFirstTeam needs teams of 2 or more robots"):
        load_experiment("demo", ["opponent.kind=MyFirstTeam", "arena.scenario=melee"])


def test_battle_cli_fills_a_side_with_the_sample_team() -> None:
    res = CliRunner().invoke(cli, ["battle", "--scenario", "4v4", "--robots", "SpinBot,MyFirstTeam", "--rounds", "4",
                                   "--seed", "2"])
    assert res.exit_code == 0, res.output
    names = ["SpinBot"] * 4 + ["MyFirstLeader"] + ["MyFirstDroid"] * 3
    parts, _ = bots.bot_battle(names, 4, seed=2, n_battles=1, scenario=get_scenario("4v4"))
    rows = {r.split("|")[2].strip(): float(r.split("|")[3]) for r in res.output.splitlines()
            if r.startswith("| ") and r[2].isdigit()}
    assert rows == {"SpinBot team 0": round(float(parts[:4].sum()), 1),
                    "MyFirstTeam team 1": round(float(parts[4:].sum()), 1)}
    bad = CliRunner().invoke(cli, ["battle", "--scenario", "1v1", "--robots", "SpinBot,MyFirstTeam"])
    assert bad.exit_code == 2 and "MyFirstTeam needs teams of 2 or more robots" in bad.output


def test_tank_pool_plays_them() -> None:
    from confront.arena.pool import PoolEntry, PoolEnv
    from confront.arena.smdp import SMDPConfig
    from confront.arena.tank import TankSpace

    config = SMDPConfig(turns_per_step=5, tank=TankSpace())
    pool = PoolEnv([PoolEntry("4v4:MyFirstTeam", "4v4", "MyFirstTeam", 2),
                    PoolEntry("1v1:TrackFire", "1v1", "TrackFire", 2)], config, seed=0)
    pool.reset()
    drivers = [env.drivers for env in pool.envs]
    assert drivers == [[None] * 4 + ["MyFirstLeader"] + ["MyFirstDroid"] * 3, [None, "TrackFire"]]
    for _ in range(60):
        pool.step(np.zeros(pool.n_agents, dtype=np.int64))
    for env in pool.envs:  # the opponents' bullets hit the learning tanks (score part bullet_damage)
        theirs = env.team_ids() != 0
        damage = env.arena.state.score_total[:, theirs, 2].sum() + env.arena.state.score[:, theirs, 2].sum()
        assert damage > 0
