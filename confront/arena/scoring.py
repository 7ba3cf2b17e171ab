"""Robocode's score tables from the arena's score arrays (RobotStatistics / TeamStatistics).

The kernel accumulates the six parts per robot (``state.score`` this round, ``state.score_total``
over decided rounds) and the placements. This module sums them per team (contestant), ranks them,
and gives the shares and ratios the experiments report. Robocode's results file rounds every
number half up (``(int)(x + 0.5)``); :func:`round_half_up` does the same.
"""

from __future__ import annotations

import numpy as np

from confront.results import BattleResults, ScoreRow

__all__ = ["team_scores", "team_placements", "score_share", "score_ratio", "defensive_score", "results_table"]


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
                  names: list[str], rounds: int = 1) -> BattleResults:
    """One battle's contestants ranked best first; ``score_total`` (R, 6), ``names`` one per team."""
    n_teams = len(names)
    ts = team_scores(score_total[None], team, n_teams)[0]
    tp = team_placements(placements_total[None], team, n_teams)[0]
    rows = [ScoreRow.of(names[k], float(ts[k].sum()), [float(v) for v in ts[k]], [int(v) for v in tp[k, :3]],
                        team=names[k]) for k in range(n_teams)]
    rows.sort(key=lambda r: -r.total)
    return BattleResults(rounds=rounds, contestants=tuple(rows), engine="sim")
