"""The technique robots (confront.arena.tech) as opponents everywhere the sample robots are: the configs
(``opponent.kind``, ``league.opponents``), the paper's trainer, the PPO league, the engine's names."""

from __future__ import annotations

from typing import get_args, get_type_hints

import numpy as np
import pytest
from click.testing import CliRunner

from confront.arena import tech
from confront.arena.tank import BRAINS
from confront.cli.main import cli
from confront.config import ConfigError
from confront.engine import battle, tech_robots
from confront.train import spec
from confront.train.paper_sim import SMDPTrainer
from confront.train.ppo_engine import engine_entries
from confront.train.ppo_sim import TankTrainer
from confront.train.spec import load_experiment


def test_the_technique_robot_names_agree_everywhere() -> None:
    assert spec.TECH_BOTS == tuple(tech.TECH_ROBOTS) == tuple(tech_robots.TECH_ROBOTS)
    assert battle.robot_class("SurfGF") == "confront.tech.SurfGF 1.0"  # the engine's class of the simulator's twin
    brains = get_args(get_type_hints(spec.TankSection)["brain"])
    assert brains == BRAINS and set(BRAINS) <= set(tech.TECH_ROBOTS)  # the config's brains are the tank's


def test_paper_trainer_against_surfgf_teams() -> None:
    """``opponent.kind = "SurfGF"``: the demo's 4 DMNN tanks against 4 SurfGF; a few rounds, the SurfGFs fire and
    score."""
    cfg = load_experiment("demo", ["opponent.kind=SurfGF", "arena.battles=2", "train.rounds=4",
                                   "train.session_rounds=4"])
    assert cfg.opponent.kind == "SurfGF"
    trainer = SMDPTrainer.from_config(cfg)
    env = trainer.loop.env
    assert env.drivers == [None] * 4 + ["SurfGF"] * 4 and env.tech is not None and env.bots is None
    while trainer.rounds_done < 2:
        trainer.advance(4)
    rows = trainer.rows
    assert sum(r["score_theirs"] for r in rows) > 0
    s = env.arena.state
    assert (s.score_total[:, 4:, 2] + s.score[:, 4:, 2]).sum() > 0  # SurfGF's bullets hit the tanks


def test_ppo_league_against_orbitgf_and_surfvg(tmp_path) -> None:
    """``league.opponents = ["1v1:OrbitGF", "4v4:SurfVG"]``: the pool plays them, every entry's rounds end with the
    technique robots scoring."""
    cfg = load_experiment("demo", ['learner.kind="ppo"', 'league.opponents=["1v1:OrbitGF", "4v4:SurfVG"]',
                                   "league.focus=[]", "league.battles=2", "ppo.rollout_steps=16", "ppo.hidden=32",
                                   "train.rounds=8", "train.session_rounds=8"])
    assert cfg.league.opponents == ("1v1:OrbitGF", "4v4:SurfVG")
    assert engine_entries(cfg) == cfg.league.opponents  # the engine plays them too (confront.tech.*)
    trainer = TankTrainer(cfg)
    assert [env.drivers for env in trainer.pool.envs] == [[None, "OrbitGF"], [None] * 4 + ["SurfVG"] * 4]
    for _ in range(40):
        trainer.update()
        if {r["opponent"] for r in trainer.rows} == set(cfg.league.opponents):
            break
    by = {e: [r for r in trainer.rows if r["opponent"] == e] for e in cfg.league.opponents}
    assert all(by.values()), {e: len(v) for e, v in by.items()}
    for env in trainer.pool.envs:  # the technique robots fired and hit
        theirs = env.team_ids() != 0
        s = env.arena.state
        assert (s.score_total[:, theirs, 2].sum() + s.score[:, theirs, 2].sum()) > 0
        assert np.all(env.tech.guns[theirs] >= 0)


@pytest.mark.parametrize(("override", "message"), [
    ("opponent.kind=SurfGG", "opponent.kind = 'SurfGG' is not allowed: use one of td, SittingDuck"),
    ('league.opponents=["1v1:SurfGG"]', "league.opponents entry '1v1:SurfGG' is not allowed"),
])
def test_bad_names_are_one_line_errors_listing_the_technique_robots(override: str, message: str) -> None:
    extra = ['learner.kind="ppo"', "league.focus=[]"] if override.startswith("league") else []
    with pytest.raises(ConfigError) as err:
        load_experiment("demo", [override, *extra])
    text = str(err.value)
    assert message in text and "SurfVG" in text and "RiskGF" in text and "\n" not in text
    args = ["config", "show", "demo"] + [a for e in [override, *extra] for a in ("--set", e)]
    res = CliRunner().invoke(cli, args)
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error: ") and "SurfVG" in lines[0]


def test_evaluate_cli_tables_the_technique_robots(tmp_path) -> None:
    """``confront evaluate RUN --opponents SurfVG,4v4:RiskGF``: a row per technique robot (a bare name is 1v1)."""
    from confront.train.factory import train_run

    cfg = load_experiment("demo", ['learner.kind="ppo"', 'league.opponents=["1v1:OrbitLinear"]', "league.focus=[]",
                                   "league.battles=2", "ppo.rollout_steps=16", "ppo.hidden=32", "train.rounds=4",
                                   "train.session_rounds=4", "train.replay=false"])
    train_run(cfg, tmp_path / "run", progress=False)
    res = CliRunner().invoke(cli, ["evaluate", str(tmp_path / "run"), "--opponents", "SurfVG,4v4:RiskGF",
                                   "--rounds", "2", "--seed", "1"])
    assert res.exit_code == 0, res.output
    rows = [line for line in res.output.splitlines() if line.startswith("| 1v1:SurfVG |")
            or line.startswith("| 4v4:RiskGF |")]
    assert len(rows) == 2 and all(float(r.split("|")[3]) < 1.0 for r in rows), res.output  # they score
