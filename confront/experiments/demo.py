"""``confront demo``: the main job in small — PPO tanks learn to beat the TD team, a dodging team and sample
robots (config ``tanks-demo``); ``--paper`` trains the paper's 4v4 fuzzy DMNN arm instead (config ``demo``)."""

from __future__ import annotations

from pathlib import Path

import click

from confront.experiments.spec import load_experiment
from confront.runs import new_run_name


def run_demo(out: Path | None = None, rounds: int | None = None, seed: int | None = None,
             overrides: tuple[str, ...] = (), paper: bool = False) -> dict:
    """Train the demo config, print the score table, write plots; return the summary."""
    from confront.experiments.train import print_summary, train_run

    extra = list(overrides)
    if rounds is not None:
        extra.append(f"train.rounds={rounds}")
    if seed is not None:
        extra.append(f"train.seed={seed}")
    name = "demo" if paper else "tanks-demo"
    base = load_experiment(name, tuple(overrides))
    if rounds is not None and rounds < base.train.session_rounds:  # --rounds 8: sessions of 8 rounds, said aloud
        extra.append(f"train.session_rounds={rounds}")
        click.echo(f"note: --rounds {rounds} is below the demo's session of {base.train.session_rounds} rounds; "
                   f"sessions of {rounds} rounds", err=True)
    cfg = load_experiment(name, tuple(extra))
    out = out or Path("runs") / new_run_name(cfg.name)
    click.echo(f"confront demo: {cfg.description}")
    summary = train_run(cfg, out, progress=True)
    print_summary(summary)
    click.echo(
        "\nNext:\n"
        f"  open {out}/plots/*.png                    the learning curves\n"
        f"  tensorboard --logdir {out}/tb             shares per opponent, losses, entropy, decisions/s\n"
        f"  confront evaluate {out} --rounds 100      play the trained team greedily\n"
        f"  confront export {out} --out MyTank.jar    a Robocode robot that runs the policy without Python\n"
        "  confront train -c tanks                    the whole league (every sample robot, 1v1 and teams)\n"
        "  confront demo --paper                      the paper's fuzzy DMNN arm, for contrast\n"
    )
    return summary
