"""Figures in the style of the paper's, with 95% bootstrap bands over seeds (matplotlib, Agg backend)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from confront.files import save_figure  # noqa: E402
from confront.stats import bootstrap_ci  # noqa: E402

COLORS = ("tab:red", "tab:blue", "tab:green", "tab:orange", "tab:purple", "tab:brown", "tab:gray")


def plot_curves(curves: Mapping[str, np.ndarray], path: str | Path, *, ylabel: str, title: str = "",
                xlabel: str = "session", seed: int = 0, dashed: Mapping[str, np.ndarray] | None = None,
                hline: float | None = None) -> Path:
    """One line per arm: the mean over seeds with a 95% bootstrap band.

    ``curves[arm]`` is ``(seeds, points)`` (or ``(points,)`` for a single run); ``dashed`` adds curves drawn
    dashed in the same colours (e.g. the opponent's score, as in the paper's Figure 14).
    """
    rng = np.random.default_rng(seed)
    fig, ax = plt.subplots(figsize=(7, 4), dpi=110)
    for i, (arm, values) in enumerate(curves.items()):
        color = COLORS[i % len(COLORS)]
        v = np.atleast_2d(np.asarray(values, dtype=np.float64))
        x = np.arange(1, v.shape[1] + 1)
        mean, lo, hi = bootstrap_ci(v, rng) if v.shape[0] > 1 else (v[0], v[0], v[0])
        ax.plot(x, mean, color=color, lw=1.6, label=f"{arm} (n={v.shape[0]})")
        if v.shape[0] > 1:
            ax.fill_between(x, lo, hi, color=color, alpha=0.2, lw=0)
        if dashed is not None and arm in dashed:
            d = np.atleast_2d(np.asarray(dashed[arm], dtype=np.float64))
            ax.plot(x, np.nanmean(d, axis=0), color=color, lw=1.2, ls="--", label=f"{arm}: opponent")
    if hline is not None:
        ax.axhline(hline, color="k", lw=0.8, ls=":")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    out = save_figure(fig, path)
    plt.close(fig)
    return out


def session_plots(folder: Path, sessions: list[dict], name: str, session_rounds: int) -> list[Path]:
    """A run's figures per session: score ratio, both sides' scores and (when the rows have it) defensive score."""
    if not sessions:
        return []

    def col(key: str) -> np.ndarray:
        return np.array([s[key] for s in sessions], dtype=np.float64)

    figs = [plot_curves({name: col("score_ratio")}, folder / "score_ratio.png", ylabel="score ratio",
                        title=f"{name}: score ratio per session of {session_rounds} rounds", hline=0.5),
            plot_curves({"ours": col("score_ours"), "theirs": col("score_theirs")}, folder / "scores.png",
                        ylabel="score per session", title=f"{name}: scores")]
    if "defensive_ours" in sessions[0]:
        figs.append(plot_curves({"ours": col("defensive_ours"), "theirs": col("defensive_theirs")},
                                folder / "defensive.png", ylabel="defensive score per session",
                                title=f"{name}: defensive score (survival + last-survivor bonus)"))
    return figs
