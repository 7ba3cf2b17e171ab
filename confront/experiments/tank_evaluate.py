"""PPO tank runs played without learning: shares per league entry in the simulator (:func:`evaluate_tanks`), and
the ``confront evaluate`` tables of a tank run in the simulator and, as the exported TankBot, in Robocode.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
import numpy as np

from confront.config import load_toml
from confront.learning.ppo import PPO
from confront.train.league import build_pool
from confront.train.loop import share_by_opponent
from confront.train.ppo_model import load_tank_model
from confront.train.spec import ExperimentConfig, config_from_dict

if TYPE_CHECKING:
    from confront.engine.tank_export import Play

__all__ = ["evaluate_tanks", "league_entries", "evaluate_tank_cli", "evaluate_tank_engine_cli"]


def evaluate_tanks(cfg: ExperimentConfig, ppo: PPO, rounds: int, seed: int = 10_000,
                   opponents: tuple[str, ...] | None = None, battles: int = 16, explore: bool = False
                   ) -> dict[str, dict[str, float]]:
    """Greedy play (sampled with ``explore``) against each league entry for ``rounds`` rounds: share (pooled)
    and win rate per entry."""
    from dataclasses import replace

    league = replace(cfg.league, opponents=opponents or cfg.league.opponents, focus=())
    ecfg = replace(cfg, league=league)
    pool, snap = build_pool(ecfg, seed, battles=battles)
    snap.load(ppo.actor_arrays())
    obs = pool.reset()
    rows: list[dict[str, Any]] = []
    done = {e.name: 0 for e in pool.entries}
    while min(done.values()) < rounds:
        joint, *_ = ppo.act(obs, explore=explore)
        st = pool.step(joint)
        for r in st.rounds:
            name = str(r["opponent"])
            if done[name] < rounds:
                rows.append(r)
                done[name] += 1
        obs = st.obs
    shares = share_by_opponent(rows)
    return {k: {"share": shares[k], "win_rate": float(np.mean([r["won"] for r in rows if r["opponent"] == k])),
                "rounds": done[k]} for k in shares}


SHARE = ("score share: our team's Robocode score / both teams' scores (0.5 is even), the same measure in the "
         "simulator and in Robocode")


def league_entries(opponents: str | None, cfg: ExperimentConfig) -> tuple[str, ...]:
    """``--opponents`` as league entries: ``SCENARIO:OPPONENT`` kept, a bare name is ``1v1:NAME``."""
    if not opponents:
        return tuple(cfg.league.opponents)
    names = [o.strip() for o in opponents.split(",") if o.strip()]
    return tuple(n if ":" in n else f"1v1:{n}" for n in names)


def evaluate_tank_cli(run: Path, opponents: str | None, rounds: int, seed: int, play: Play = "sampled"
                      ) -> dict[str, dict[str, float]]:
    """Shares of a PPO run per league entry in the simulator, printed as a table; ``play``: ``"sampled"``
    draws each head from its softmax, ``"greedy"`` takes its first maximum."""
    if play not in ("sampled", "greedy"):
        raise ValueError(f"play must be 'sampled' or 'greedy', got {play!r}")
    from dataclasses import replace

    cfg = config_from_dict(load_toml(run / "config.toml"))
    entries = league_entries(opponents, cfg)
    try:
        cfg = replace(cfg, league=replace(cfg.league, opponents=entries, focus=()))
    except ValueError as exc:  # the config's words for what the user typed as --opponents
        raise click.UsageError(str(exc).replace("league.opponents entry", "--opponents entry")) from None
    ppo = load_tank_model(run, cfg)
    res = evaluate_tanks(cfg, ppo, rounds, seed=seed, explore=play == "sampled")
    click.echo(f"\n{run}: {play} policy, {rounds} rounds per opponent (simulator, seed {seed})\n{SHARE}\n")
    click.echo("| opponent | rounds | score share (simulator) | win rate |\n|---|---:|---:|---:|")
    for name in entries:
        r = res[name]
        click.echo(f"| {name} | {r['rounds']} | {r['share']:.3f} | {r['win_rate']:.2f} |")
    return res


def evaluate_tank_engine_cli(run: Path, opponents: str | None, rounds: int, seed: int,
                             seeds: int = 1, play: Play = "sampled", visible: bool = False) -> dict[str, list[float]]:
    """The exported TankBot (a jar, no Python, playing ``play``) in the real engine against each scripted league
    entry, ``seeds`` battles of ``rounds`` rounds (engine seeds ``seed``, ``seed + 1``, ...): our score ratio
    per battle. ``visible``: each battle in Robocode's battle window."""
    from confront.arena.bots import BOT_NAMES
    from confront.arena.scenarios import SAMPLE_TEAMS
    from confront.arena.tech import TECH_ROBOTS
    from confront.engine.tank_export import evaluate_tank_policy, load_tank_policy

    cfg = config_from_dict(load_toml(run / "config.toml"))
    policy = load_tank_policy(run, play)
    out: dict[str, list[float]] = {}
    click.echo(f"\n{run}: the exported TankBot ({play}) in Robocode, {rounds} rounds x {seeds} battle(s) per "
               f"opponent\n{SHARE}\n")
    click.echo("| opponent | battles | score share (robocode) |\n|---|---:|---:|")
    for entry in league_entries(opponents, cfg):
        scen, _, opp = entry.partition(":")
        if opp not in BOT_NAMES and opp not in SAMPLE_TEAMS and opp not in TECH_ROBOTS:
            click.echo(f"| {entry} | - | simulator only |")
            continue
        out[entry] = [evaluate_tank_policy(policy, scen, opp, rounds=rounds, seed=seed + k, visible=visible)[1]
                      for k in range(seeds)]
        click.echo(f"| {entry} | {seeds} | {' / '.join(f'{v:.3f}' for v in out[entry])} |")
    return out
