"""Robocode scoring: placements, survival, kill bonuses, team sums and result tables."""

import numpy as np
import pytest

from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario
from confront.arena.scoring import (
    defensive_score,
    results_table,
    score_ratio,
    score_share,
    team_scores,
)


def three_in_a_row() -> Arena:
    sc = get_scenario("melee").replace(teams=(1, 1, 1), initial_positions=((100, 300, 90), (300, 300, 0),
                                                                           (600, 300, 0)))
    a = Arena(sc, 1, order="fixed")
    a.state.energy[0, 1:] = 1.0
    return a


def test_melee_kills_placements_and_bonuses():
    a = three_in_a_row()
    cmd = a.idle_commands()
    cmd[0, 0, 4] = 3.0
    died = {}
    for _ in range(200):
        a.step(cmd)
        for i in np.flatnonzero(a.state.ev_died[0]):
            died[int(i)] = int(a.state.time[0])
        if a.state.done[0]:
            break
    # bullet 1 (turn 31) reaches B's box at x=282 after 17 moves; bullet 2 (turn 47) reaches C's at 582
    assert died == {1: 47, 2: 90}
    s = a.state
    np.testing.assert_allclose(s.score_total[0, 0], [100.0, 20.0, 2.0, 0.4, 0.0, 0.0])
    np.testing.assert_allclose(s.score_total[0, 2], [50.0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(s.score_total[0, 1], [0.0] * 6)
    assert s.placements_total[0].tolist() == [[1, 0, 0], [0, 0, 1], [0, 1, 0]]


def test_team_sums_shares_and_ratio():
    score = np.zeros((1, 4, 6))
    score[0, 0] = [50, 30, 100, 20, 2.4, 0]
    score[0, 1] = [50, 30, 0, 0, 0, 0]
    score[0, 2] = [0, 0, 40, 0, 1.2, 0.36]
    team = np.array([0, 0, 1, 1])
    ts = team_scores(score, team, 2)
    assert ts[0, 0].tolist() == pytest.approx([100, 60, 100, 20, 2.4, 0])
    assert ts[0, 1].sum() == pytest.approx(41.56)
    share = score_share(score, team, 2)
    assert share[0].tolist() == pytest.approx([282.4 / 323.96, 41.56 / 323.96])
    assert score_ratio(score, team, 2)[0] == pytest.approx(282.4 / 323.96)
    assert defensive_score(score, team, 2)[0].tolist() == pytest.approx([160.0, 0.0])
    assert score_share(np.zeros((1, 4, 6)), team, 2)[0].tolist() == [0.0, 0.0]


def test_results_text():
    score = np.array([[50.0, 10, 100, 20, 0, 0], [0.0] * 6])
    places = np.array([[1, 0, 0], [0, 1, 0]])
    text = results_table(score, places, np.array([0, 1]), ["sample.Walls", "sample.SpinBot"]).to_results_text()
    assert text.splitlines()[2] == "1st: sample.Walls\t180 (100%)\t50\t10\t100\t20\t0\t0\t1\t0\t0"
    assert text.splitlines()[3].startswith("2nd: sample.SpinBot\t0 (0%)")
