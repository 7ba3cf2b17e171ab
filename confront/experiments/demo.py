"""``confront demo``: the main job in small — PPO tanks learn to beat the TD team, a dodging team and sample
robots (config ``tanks-demo``); ``--paper`` trains the paper's 4v4 fuzzy DMNN arm instead (config ``demo``);
``--contrast`` trains both and draws their score share against the same TD team in one figure."""

from __future__ import annotations

from pathlib import Path

import click

from confront.runs import command, new_run_name
from confront.train.spec import load_experiment


def run_demo(out: Path | None = None, rounds: int | None = None, seed: int | None = None,
             overrides: tuple[str, ...] = (), paper: bool = False, contrast: bool = False) -> dict:
    """Train the demo config, print the score table, write plots; return the summary (with ``contrast``, also
    the paper's arm into ``<out>/paper-arm`` and ``plots/contrast.png``)."""
    from confront.train.factory import train_run
    from confront.train.loop import print_summary

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
    if contrast and not paper:
        arm = load_experiment("demo", () if seed is None else (f"train.seed={seed}",))
        click.echo(f"\nfor contrast, the paper's arm: {arm.description}")
        paper_summary = train_run(arm, out / "paper-arm", progress=True)
        print_summary(paper_summary)
        fig = plot_contrast(out, out / "paper-arm")
        summary["figures"] = [*summary.get("figures", []), str(fig)]
        click.echo(f"\ncontrast figure: {fig}")
    c = command()  # as the user started it: .venv/bin/confront after the README's commands
    replay = summary.get("replay")
    watch = (f"  open {Path(replay).parent / 'last_round.html'}\n      a recorded round of the trained team "
             "(HTML player; a GIF beside it)\n") if replay else ""
    click.echo(
        "\nNext:\n"
        f"{watch}"
        f"  open {out}/plots/*.png\n      the learning curves\n"
        f"  tensorboard --logdir {out}/tb\n      shares per opponent, losses, entropy, decisions/s\n"
        f"  {c} evaluate {out} --rounds 100\n      play the trained team per opponent (score table)\n"
        f"  {c} export {out} --out MyTank.jar\n      a Robocode robot that runs the policy without Python\n"
        f"  {c} robocode {out}\n      Robocode's own program with it (pick confront.TankTeam 1.0)\n"
        f"  {c} evaluate {out} --engine robocode --watch --opponents 1v1:SpinBot --rounds 3\n"
        "      watch it in Robocode's own window (apt-get install robocode)\n"
        f"  {c} train -c tanks\n      the whole league (every sample robot, 1v1 and teams)\n"
        f"  {c} demo --paper\n      the paper's fuzzy DMNN arm, for contrast\n"
    )
    return summary


def plot_contrast(tanks_run: Path, paper_run: Path) -> Path:
    """Score share against the 4v4 TD team per window of rounds: PPO tanks (their ``4v4:td`` rounds) and the
    paper's arm (all its rounds are against the TD team), each against its own rounds played."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from confront.runs import Run
    from confront.train.loop import share_windows

    ours = [r for r in Run(tanks_run).read_table("rounds") if r["opponent"] == "4v4:td"]
    theirs = Run(paper_run).read_table("rounds")
    fig, ax = plt.subplots(figsize=(7, 4), dpi=110)
    for rows, label in ((ours, "PPO tanks (recommended)"), (theirs, "paper's DMNN (FLM, AWM)")):
        windows = share_windows(rows, max(10, len(rows) // 20))
        ax.plot([end for end, _ in windows], [v for _, v in windows], lw=1.6, marker="o", ms=3,
                label=f"{label}, {len(rows)} rounds")
    ax.axhline(0.5, color="k", lw=0.8, ls=":")
    ax.set_xlabel("rounds played against the 4v4 TD team")
    ax.set_ylabel("score share (training)")
    ax.set_title("The same TD team: PPO tanks against the paper's arm")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = Path(tanks_run) / "plots" / "contrast.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path
