"""What a training battle in Robocode leaves behind, as data.

- :func:`round_rows`: the runner's per-round scores (``round_scores``: every robot's battle totals at each round's
  end) as the rows of ``metrics/rounds.csv``, with the simulator's columns (both engine trainers).
- :func:`read_scores`: the runner's per-turn score log (``-Dconfront.scores``: a line "round turn alive s_0 ...
  s_n-1" whenever a score or a life changed), per round a :class:`ScoreLog`.
- :func:`read_decisions`: what each TankBot logged per decision (``-Dconfront.tank.log``), as :class:`Decision`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from confront.arena.state import SCORE_PARTS

__all__ = ["ENGINE_PARTS", "round_rows", "DECISION_SUFFIX", "Decision", "read_decisions", "ScoreLog", "read_scores"]

# simulator score part -> the engine's score snapshot key [Robocode RobotStatistics; ram_dmg already x2]
ENGINE_PARTS: dict[str, str] = {
    "survival": "survival", "last_survivor": "surv_bonus", "bullet_damage": "bullet_dmg",
    "bullet_kill_bonus": "bullet_bonus", "ram_damage": "ram_dmg", "ram_kill_bonus": "ram_bonus",
}
DECISION_SUFFIX = ".decisions"  # TankBot.LOG_SUFFIX


def round_rows(round_scores: list[dict[str, Any]], ours: int = 0) -> list[dict[str, Any]]:
    """Rows of ``metrics/rounds.csv`` (the simulator's columns) from the runner's per-round scores.

    Each entry holds every robot's battle totals at the end of a round; a round's parts are the differences
    to the previous round's totals, so they add up to the engine's results. ``ours`` is our contestant index;
    every other contestant is theirs. A round is decided when at most one contestant has a robot alive.
    """
    rows: list[dict[str, Any]] = []
    before: list[dict[str, float]] | None = None
    for i, rnd in enumerate(round_scores):
        robots = rnd["robots"]
        if before is not None and len(before) != len(robots):
            raise ValueError(f"round {rnd.get('round')} has {len(robots)} robots, the round before {len(before)}")
        prev = before or [{k: 0.0 for k in ENGINE_PARTS.values()} for _ in robots]
        # this round's part = battle total now - battle total after the previous round
        delta = [{k: float(r["score"][k]) - p[k] for k in ENGINE_PARTS.values()}
                 for r, p in zip(robots, prev, strict=True)]
        before = [{k: float(r["score"][k]) for k in ENGINE_PARTS.values()} for r in robots]
        mine = [j for j, r in enumerate(robots) if r["contestant"] == ours]
        other = [j for j, r in enumerate(robots) if r["contestant"] != ours]
        if not mine or not other:
            raise ValueError(f"round {rnd.get('round')} has no robots of contestant {ours} or no opponents")
        alive_o = sum(bool(robots[j]["alive"]) for j in mine)
        alive_t = sum(bool(robots[j]["alive"]) for j in other)
        decided = len({r["contestant"] for r in robots if r["alive"]}) <= 1
        parts_o = {p: sum(delta[j][k] for j in mine) for p, k in ENGINE_PARTS.items()}
        parts_t = {p: sum(delta[j][k] for j in other) for p, k in ENGINE_PARTS.items()}
        total_o, total_t = sum(parts_o.values()), sum(parts_t.values())
        row: dict[str, Any] = {"battle": 0, "turns": int(rnd["turns"]), "decided": decided,
                               "score_ours": total_o, "score_theirs": total_t,
                               "score_ratio": total_o / (total_o + total_t) if total_o + total_t > 0 else 0.5,
                               # defensive score: survival + last-survivor bonus, as the simulator's rows
                               "defensive_ours": parts_o["survival"] + parts_o["last_survivor"],
                               "defensive_theirs": parts_t["survival"] + parts_t["last_survivor"],
                               "won": decided and alive_o > 0, "alive_ours": alive_o, "alive_theirs": alive_t}
        for p in SCORE_PARTS:
            row[f"{p}_ours"] = parts_o[p]
            row[f"{p}_theirs"] = parts_t[p]
        row["round"] = i + 1
        rows.append(row)
    return rows


@dataclass(frozen=True)
class Decision:
    """One logged TankBot decision: robot name, round (0-based), turn (``getTime()``), joint action, the view
    (float64, as Java computed it), the uniform draws, and with the log's detail what the view was made of:
    (own values (13), enemy rows, mate rows) as TankCheck's "V" request."""

    robot: str
    round: int
    turn: int
    action: int
    view: np.ndarray
    draws: np.ndarray
    detail: tuple[list[float], list[list[float]], list[list[float]]] | None = None


def _nums(text: str) -> list[float]:
    return [float(x) for x in text.split()]


def _rows(text: str) -> list[list[float]]:
    return [_nums(r) for r in text.split("|")] if text.strip() else []


def read_decisions(folder: Path) -> list[Decision]:
    """Every decision TankBot logged into ``folder`` (one file per robot), by robot, round and turn."""
    out: list[Decision] = []
    for path in sorted(Path(folder).glob(f"*{DECISION_SUFFIX}")):
        for line in path.read_text(encoding="utf-8").splitlines():
            p = line.split("\t")
            if len(p) < 6:
                raise ValueError(f"{path.name}: a decision line has {len(p)} fields, expected 6 or 9")
            detail = (_nums(p[6]), _rows(p[7]), _rows(p[8])) if len(p) >= 9 else None
            out.append(Decision(p[0], int(p[1]), int(p[2]), int(p[3]), np.array(_nums(p[4])),
                                np.array(_nums(p[5])), detail))
    out.sort(key=lambda d: (d.robot, d.round, d.turn))
    return out


@dataclass(frozen=True)
class ScoreLog:
    """One round of the runner's per-turn scores: the logged turns (K,) ascending, each robot's life (K, R) and
    current-round score (K, R) from that turn on (a turn not logged is the one before it unchanged; before the
    first line every score is 0 and every robot alive)."""

    turns: np.ndarray
    alive: np.ndarray
    score: np.ndarray

    def at(self, turn: int) -> int:
        """The row in force after ``turn`` (-1: before the first line)."""
        return int(np.searchsorted(self.turns, turn, side="right")) - 1

    def margin(self, turn: int, ours: np.ndarray) -> float:
        """Our robots' score (``ours`` (R,) bool) minus the others' after ``turn``."""
        k = self.at(turn)
        return 0.0 if k < 0 else float(self.score[k][ours].sum() - self.score[k][~ours].sum())

    def decided(self, contestant: np.ndarray) -> int | None:
        """The first turn at which at most one contestant (``contestant`` (R,) ints) has a robot alive."""
        for k in range(len(self.turns)):
            if len(set(contestant[self.alive[k]].tolist())) <= 1:
                return int(self.turns[k])
        return None


def read_scores(path: Path, n_robots: int) -> dict[int, ScoreLog]:
    """The runner's score log (``-Dconfront.scores``) per round."""
    rounds: dict[int, tuple[list[int], list[list[bool]], list[list[float]]]] = {}
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        p = line.split()
        if len(p) != 3 + n_robots or len(p[2]) != n_robots:
            raise ValueError(f"score log line {line[:80]!r} does not have {n_robots} robots")
        t, a, s = rounds.setdefault(int(p[0]), ([], [], []))
        t.append(int(p[1]))
        a.append([c == "1" for c in p[2]])
        s.append([float(x) for x in p[3:]])
    return {r: ScoreLog(np.array(t, dtype=np.int64), np.array(a, dtype=bool).reshape(-1, n_robots),
                        np.array(s, dtype=np.float64).reshape(-1, n_robots)) for r, (t, a, s) in rounds.items()}
