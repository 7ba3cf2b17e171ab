"""Learners as bridge policies: SMDP steps, Eq. 35 rewards, live training in the engine."""

from __future__ import annotations

import math

import numpy as np
import pytest

from confront.engine.battle import BattleSpec
from confront.engine.bridge import Observation, Scan
from confront.engine.bridged import BRIDGE_BOT, run_bridged_battle
from confront.engine.learner_policy import LearnerPolicy
from confront.learning.tabular import TabularQ


def _obs(turn: int, own: float, enemy: float) -> Observation:
    scan = Scan("e", turn, False, 0.0, 200.0, 0.0, 0.0, enemy, 400.0, 500.0)
    return Observation("me", (), 0, turn, 400.0, 300.0, 0.0, 0.0, 0.0, 0.0, own, 1.0, 1, 0.0, 800.0, 600.0, (scan,))


def test_smdp_steps_and_eq35_rewards() -> None:
    learner = TabularQ()
    pol = LearnerPolicy(learner, np.random.default_rng(0), step_turns=2)
    a1 = pol(_obs(1, 100.0, 100.0))  # decision turn
    assert not math.isnan(a1[0]) and pol.decisions == 1
    a2 = pol(_obs(2, 97.0, 100.0))  # we lost 3: Eq. 35 = (-3 - 0) * 0 / ... = 0
    assert math.isnan(a2[0]) and math.isnan(a2[1])
    pol(_obs(3, 97.0, 84.0))  # enemy lost 16, energy gap |97 - 100| = 3: (0 + 16) * 16 / 3
    assert pol.rewards == pytest.approx([0.0, 16 * 16 / 3])
    assert pol.updates == 1 and learner.step == 1  # the first SMDP step (T = 2) was learned
    pol.end_episode("me", 0)  # the new step has no turn yet: nothing to learn
    assert pol.updates == 1
    pol(_obs(3, 97.0, 84.0))  # round 0 was ended above, so this starts a fresh step
    pol(_obs(4, 97.0, 84.0))
    pol.end_episode("me", 0)  # a one-turn terminal step
    assert pol.updates == 2
    with pytest.raises(ValueError, match="step_turns"):
        LearnerPolicy(learner, np.random.default_rng(0), step_turns=0)


@pytest.mark.engine
def test_tabular_learner_trains_live_in_engine(install) -> None:
    learner = TabularQ()
    q0 = learner.q.copy()
    pol = LearnerPolicy(learner, np.random.default_rng(1), step_turns=4)
    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SittingDuck"), rounds=2), pol)
    assert res.ok, (res.failures, res.server_errors)
    assert pol.updates >= pol.decisions - 2 > 20  # every SMDP step but the last open ones is learned
    assert learner.step == pol.updates
    assert not np.array_equal(learner.q, q0)
    assert any(r > 0 for r in pol.rewards)  # it hit the duck
