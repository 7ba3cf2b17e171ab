"""Robocode's score tables from the arena's score arrays (RobotStatistics / TeamStatistics).

The kernel accumulates the six parts per robot (``state.score`` this round, ``state.score_total``
over decided rounds) and the placements. This module sums them per team (contestant), ranks them,
and gives the shares and ratios the experiments report. Robocode's results file rounds every
number half up (``(int)(x + 0.5)``); :func:`round_half_up` does the same.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .state import SCORE_PARTS

__all__ = ["ScoreRow", "round_half_up", "team_scores", "team_placements", "score_share", "score_ratio",
           "defensive_score", "results_table", "format_results"]


@dataclass(frozen=True)
class ScoreRow:
    """One contestant's battle result: total, the six parts, 1sts/2nds/3rds."""

    name: str
    total: float
    parts: dict[str, float]
    firsts: int
    seconds: int
    thirds: int


def round_half_up(x: float) -> int:
    """Robocode's rounding of result numbers: (int)(x + 0.5) (truncation toward zero, as Java casts)."""
    return int(math.trunc(x + 0.5))


def team_scores(score: np.ndarray, team: np.ndarray, n_teams: int) -> np.ndarray:
    """(B, T, 6) score parts summed over each team's robots; ``score`` is (B, R, 6), ``team`` (R,) or (B, R)."""
    s = np.asarray(score, dtype=np.float64)
    t = np.broadcast_to(np.asarray(team), s.shape[:2])
    out = np.zeros((s.shape[0], n_teams, s.shape[2]))
    for k in range(n_teams):
        out[:, k] = np.where((t == k)[..., None], s, 0.0).sum(axis=1)
    return out


def team_placements(placements: np.ndarray, team: np.ndarray, n_teams: int) -> np.ndarray:
    """(B, T, 3) placements summed per team (the leader's entry holds a team's firsts in Robocode)."""
    return team_scores(placements.astype(np.float64), team, n_teams).astype(np.int64)


def score_share(score: np.ndarray, team: np.ndarray, n_teams: int) -> np.ndarray:
    """(B, T) each team's fraction of the battle's total score (0 where nobody scored)."""
    tot = team_scores(score, team, n_teams).sum(axis=2)
    denom = tot.sum(axis=1, keepdims=True)
    return np.divide(tot, denom, out=np.zeros_like(tot), where=denom > 0)


def score_ratio(score: np.ndarray, team: np.ndarray, n_teams: int, ours: int = 0) -> np.ndarray:
    """(B,) the paper's score ratio: our team's total / (ours + all opponents')."""
    return score_share(score, team, n_teams)[:, ours]


def defensive_score(score: np.ndarray, team: np.ndarray, n_teams: int) -> np.ndarray:
    """(B, T) survival + last-survivor bonus per team (the paper leaves it undefined; our reading)."""
    return team_scores(score, team, n_teams)[..., :2].sum(axis=2)


def results_table(score_total: np.ndarray, placements_total: np.ndarray, team: np.ndarray,
                  names: list[str]) -> list[ScoreRow]:
    """One battle's contestants ranked best first; ``score_total`` (R, 6), ``names`` one per team."""
    n_teams = len(names)
    ts = team_scores(score_total[None], team, n_teams)[0]
    tp = team_placements(placements_total[None], team, n_teams)[0]
    rows = [ScoreRow(names[k], float(ts[k].sum()), dict(zip(SCORE_PARTS, map(float, ts[k]), strict=True)),
                     int(tp[k, 0]), int(tp[k, 1]), int(tp[k, 2])) for k in range(n_teams)]
    return sorted(rows, key=lambda r: -r.total)


def format_results(rows: list[ScoreRow], rounds: int) -> str:
    """Text like Robocode's results file (numbers rounded half up, share of the total in percent)."""
    grand = sum(r.total for r in rows)
    ordinal = {1: "1st", 2: "2nd", 3: "3rd"}
    lines = [f"Results for {rounds} rounds",
             "Robot Name\tTotal Score\tSurvival\tSurv Bonus\tBullet Dmg\tBullet Bonus\tRam Dmg * 2\tRam Bonus"
             "\t1sts\t2nds\t3rds"]
    for i, r in enumerate(rows, start=1):
        pct = round_half_up(100 * r.total / grand) if grand > 0 else 0
        parts = "\t".join(str(round_half_up(r.parts[p])) for p in SCORE_PARTS)
        lines.append(f"{ordinal.get(i, f'{i}th')}: {r.name}\t{round_half_up(r.total)} ({pct}%)\t{parts}"
                     f"\t{r.firsts}\t{r.seconds}\t{r.thirds}")
    return "\n".join(lines)
