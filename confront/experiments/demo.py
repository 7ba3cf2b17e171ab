"""``confront demo``: the main job in small — train a 4v4 fuzzy DMNN team against the TD team, then report."""

from __future__ import annotations

from pathlib import Path

import click

from confront.experiments.spec import load_experiment
from confront.runs import new_run_name


def run_demo(out: Path | None = None, rounds: int | None = None, seed: int | None = None,
             overrides: tuple[str, ...] = ()) -> dict:
    """Train the demo config, print the score table, write plots and a replay; return the summary."""
    from confront.experiments.train import print_summary, train_run

    extra = list(overrides)
    if rounds is not None:
        extra.append(f"train.rounds={rounds}")
    if seed is not None:
        extra.append(f"train.seed={seed}")
    base = load_experiment("demo", tuple(overrides))
    if rounds is not None and rounds < base.train.session_rounds:  # --rounds 8: sessions of 8 rounds, said aloud
        extra.append(f"train.session_rounds={rounds}")
        click.echo(f"note: --rounds {rounds} is below the demo's session of {base.train.session_rounds} rounds; "
                   f"sessions of {rounds} rounds", err=True)
    cfg = load_experiment("demo", tuple(extra))
    out = out or Path("runs") / new_run_name("demo")
    click.echo(f"confront demo: {cfg.description}")
    summary = train_run(cfg, out, progress=True)
    print_summary(summary)
    click.echo(
        "\nNext:\n"
        f"  open {out}/plots/*.png                       the learning curves\n"
        f"  open {out}/replays/*.html                    watch a battle in the browser\n"
        f"  confront evaluate {out} --rounds 100         play the trained team greedily\n"
        f"  confront evaluate {out} --engine robocode    the same inside the real Robocode engine\n"
        "  confront reproduce all --seeds 10             every experiment of the paper, with a report\n"
    )
    return summary
