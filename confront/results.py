"""Battle results as a table of Robocode's score parts, per contestant and per robot (simulator and engine).

The same type is filled by the real engine (exact doubles from its score snapshots, or the integers of a
results file) and by the simulator. Columns follow Robocode's results table.
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields, replace

# Columns of Robocode's results table, in its order ("Ram Dmg * 2" is already doubled by the engine).
SCORE_FIELDS: tuple[str, ...] = (
    "total", "survival", "surv_bonus", "bullet_dmg", "bullet_bonus", "ram_dmg", "ram_bonus",
    "firsts", "seconds", "thirds",
)
ENGINE_HEADERS: tuple[str, ...] = (
    "Total Score", "Survival", "Surv Bonus", "Bullet Dmg", "Bullet Bonus", "Ram Dmg * 2", "Ram Bonus",
    "1sts", "2nds", "3rds",
)
_LINE = re.compile(r"^(\d+)(?:st|nd|rd|th): (.+)$")


def round_half_up(x: float) -> int:
    """Robocode's rounding of scores in results: (int)(x + 0.5)."""
    return int(math.floor(x + 0.5))


@dataclass(frozen=True)
class ScoreRow:
    """Score parts of one robot or one contestant (a single robot or a whole team), summed over rounds."""

    name: str
    total: float = 0.0
    survival: float = 0.0
    surv_bonus: float = 0.0
    bullet_dmg: float = 0.0
    bullet_bonus: float = 0.0
    ram_dmg: float = 0.0
    ram_bonus: float = 0.0
    firsts: int = 0
    seconds: int = 0
    thirds: int = 0
    team: str = ""

    @classmethod
    def of(cls, name: str, total: float, parts: Sequence[float], places: Sequence[int] = (0, 0, 0),
           team: str = "") -> ScoreRow:
        """A row from the six score parts after the total (survival .. ram bonus, table order) and the counts of
        1sts, 2nds and 3rds."""
        survival, surv_bonus, bullet_dmg, bullet_bonus, ram_dmg, ram_bonus = parts
        firsts, seconds, thirds = places
        return cls(name, total, survival, surv_bonus, bullet_dmg, bullet_bonus, ram_dmg, ram_bonus, firsts, seconds,
                   thirds, team)

    def rounded(self) -> ScoreRow:
        """The row as the engine prints it: every score part rounded half up."""
        r = [round_half_up(getattr(self, f)) for f in SCORE_FIELDS[:7]]
        return ScoreRow.of(self.name, r[0], r[1:], (self.firsts, self.seconds, self.thirds), self.team)

    def values(self) -> tuple[float, ...]:
        """The ten score columns in table order."""
        return tuple(getattr(self, f) for f in SCORE_FIELDS)


@dataclass(frozen=True)
class BattleResults:
    """Results of one battle: contestants sorted best first, the robots of each, and run diagnostics."""

    rounds: int
    contestants: tuple[ScoreRow, ...]
    robots: tuple[ScoreRow, ...] = ()
    skipped_turns: int = 0
    engine: str = "robocode"

    def __post_init__(self) -> None:
        if self.rounds < 1:
            raise ValueError(f"rounds must be >= 1, got {self.rounds}")

    def contestant(self, name: str) -> ScoreRow:
        """The contestant row called ``name``."""
        for row in self.contestants:
            if row.name == name:
                return row
        raise KeyError(f"no contestant named {name!r}; have {[r.name for r in self.contestants]}")

    def score_ratio(self, name: str) -> float:
        """Total score of contestant ``name`` over the sum of all totals (0 when nobody scored)."""
        all_total = sum(r.total for r in self.contestants)
        return self.contestant(name).total / all_total if all_total > 0 else 0.0

    def rounded(self) -> BattleResults:
        """Copy with every score rounded as the engine's results file does."""
        return replace(
            self,
            contestants=tuple(r.rounded() for r in self.contestants),
            robots=tuple(r.rounded() for r in self.robots),
        )

    def to_csv(self, level: str = "contestants") -> str:
        """CSV text (header + rows) of the contestants or the robots table."""
        rows = self._rows(level)
        buf = io.StringIO()
        names = [f.name for f in fields(ScoreRow)]
        writer = csv.DictWriter(buf, fieldnames=["rank", *names], lineterminator="\n")
        writer.writeheader()
        for rank, row in enumerate(rows, 1):
            writer.writerow({"rank": rank, **asdict(row)})
        return buf.getvalue()

    def to_markdown(self, level: str = "contestants", digits: int = 1) -> str:
        """A Markdown table of the contestants or the robots, with Robocode's column names."""
        rows = self._rows(level)
        head = "| # | Name | " + " | ".join(ENGINE_HEADERS) + " |"
        sep = "|---|---|" + "---:|" * len(ENGINE_HEADERS)
        lines = [head, sep]
        for rank, row in enumerate(rows, 1):
            cells = [f"{v:.{digits}f}" if isinstance(v, float) else str(v) for v in row.values()]
            lines.append(f"| {rank} | {row.name} | " + " | ".join(cells) + " |")
        return "\n".join(lines) + "\n"

    def to_results_text(self) -> str:
        """Text like the engine's ``-results`` file: numbers rounded half up, share of the total in percent."""
        grand = sum(r.total for r in self.contestants)
        ordinal = {1: "1st", 2: "2nd", 3: "3rd"}
        lines = [f"Results for {self.rounds} rounds", "Robot Name\t" + "\t".join(ENGINE_HEADERS)]
        for i, r in enumerate(self.contestants, start=1):
            pct = round_half_up(100 * r.total / grand) if grand > 0 else 0
            parts = "\t".join(str(round_half_up(getattr(r, f))) for f in SCORE_FIELDS[1:7])
            lines.append(f"{ordinal.get(i, f'{i}th')}: {r.name}\t{round_half_up(r.total)} ({pct}%)\t{parts}"
                         f"\t{r.firsts}\t{r.seconds}\t{r.thirds}")
        return "\n".join(lines)

    def _rows(self, level: str) -> tuple[ScoreRow, ...]:
        if level == "contestants":
            return self.contestants
        if level == "robots":
            return self.robots
        raise ValueError(f"level must be 'contestants' or 'robots', got {level!r}")


def parse_results_text(text: str) -> BattleResults:
    """Parse the engine's ``-results`` file (tab-separated, integers) into :class:`BattleResults`."""
    lines = [ln for ln in text.splitlines() if ln.strip()]
    if not lines or not lines[0].startswith("Results for "):
        raise ValueError("not a Robocode results file: first line must be 'Results for N rounds'")
    try:
        rounds = int(lines[0].split()[2])
    except (IndexError, ValueError):
        raise ValueError(f"bad results title line: {lines[0]!r}") from None
    rows = []
    for line in lines[2:]:
        cells = [c.strip() for c in line.split("\t")]
        cells = [c for c in cells if c != ""]
        m = _LINE.match(cells[0]) if cells else None
        if m is None or len(cells) != 11:
            raise ValueError(f"bad results row: {line!r}")
        total = float(cells[1].split()[0])
        rows.append(ScoreRow.of(m.group(2), total, [float(c) for c in cells[2:8]], [int(c) for c in cells[8:11]],
                                team=m.group(2)))
    return BattleResults(rounds=rounds, contestants=tuple(rows))
