"""Results table: parsing the engine's results file, rounding, CSV/Markdown output."""

from __future__ import annotations

import pytest

from confront.results import BattleResults, ScoreRow, parse_results_text, round_half_up

TEXT = (
    "Results for 3 rounds\n"
    "Robot Name\t    Total Score    \tSurvival\tSurv Bonus\tBullet Dmg\tBullet Bonus\tRam Dmg * 2\tRam Bonus"
    "\t 1sts \t 2nds \t 3rds \t\n"
    "1st: confrontteams.Them4 (2)\t1602 (64%)\t950\t160\t424\t55\t13\t0\t2\t0\t0\t\n"
    "2nd: sample.Walls\t900 (36%)\t650\t0\t227\t8\t16\t0\t1\t2\t0\t\n"
)


def test_parse_results_file_values() -> None:
    res = parse_results_text(TEXT)
    assert res.rounds == 3
    assert [r.name for r in res.contestants] == ["confrontteams.Them4 (2)", "sample.Walls"]
    them = res.contestants[0]
    assert them.values() == (1602, 950, 160, 424, 55, 13, 0, 2, 0, 0)
    assert res.contestants[1].values() == (900, 650, 0, 227, 8, 16, 0, 1, 2, 0)
    assert res.score_ratio("sample.Walls") == pytest.approx(900 / 2502)


@pytest.mark.parametrize(
    "text",
    ["", "Results for x rounds\nh\n", "Results for 2 rounds\nh\n1st: a\t1 (100%)\t1\n", "Nope\n"],
)
def test_parse_rejects_bad_text(text: str) -> None:
    with pytest.raises(ValueError):
        parse_results_text(text)


def test_round_half_up_like_java() -> None:
    assert round_half_up(17.5) == 18
    assert round_half_up(2.5) == 3  # Python's round() would give 2
    assert round_half_up(14.94) == 15
    assert round_half_up(0.49) == 0


def test_rounded_row_and_tables() -> None:
    row = ScoreRow("a.B", total=226.8, survival=100, surv_bonus=20, bullet_dmg=89.0, bullet_bonus=17.8,
                   firsts=2, team="a.B")
    res = BattleResults(rounds=2, contestants=(row, ScoreRow("c.D", seconds=2, team="c.D")), robots=(row,))
    r = res.rounded().contestants[0]
    assert (r.total, r.bullet_bonus, r.bullet_dmg) == (227, 18, 89)
    csv_lines = res.to_csv().splitlines()
    assert csv_lines[0].startswith("rank,name,total,survival")
    assert csv_lines[1].startswith("1,a.B,226.8,100,20,89.0,17.8")
    md = res.to_markdown(level="robots").splitlines()
    assert md[2] == "| 1 | a.B | 226.8 | 100 | 20 | 89.0 | 17.8 | 0.0 | 0.0 | 2 | 0 | 0 |"
    with pytest.raises(ValueError, match="level"):
        res.to_csv(level="teams")
    with pytest.raises(KeyError):
        res.contestant("x.Y")
    with pytest.raises(ValueError, match="rounds"):
        BattleResults(rounds=0, contestants=())
