"""Learners as bridge policies: SMDP steps, Eq. 35 rewards from the robots' energy history, live training."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import pytest

from confront.arena.control import ControlConfig, move_commands
from confront.arena.observe import ObservationConfig, reward_eq35, reward_eq35_scalar
from confront.engine.battle import BattleSpec
from confront.engine.bridge import Observation, Scan, TurnEnergy
from confront.engine.bridged import BRIDGE_BOT, run_bridged_battle
from confront.engine.export import ExportedPolicy
from confront.engine.learner_policy import LearnerPolicy, eq35, history_rewards
from confront.learning.base import Transition
from confront.learning.tabular import TabularQ


def _obs(turn: int, own: float, enemy: float, history: tuple[TurnEnergy, ...], round_: int = 0,
         ex: float = 400.0) -> Observation:
    scan = Scan("e", turn, False, 0.0, 200.0, 0.0, 0.0, enemy, ex, 500.0)
    return Observation("me", (), round_, turn, 400.0, 300.0, 0.0, 0.0, 0.0, 0.0, own, 1.0, 1, 0.0, 800.0, 600.0,
                       (scan,), history=history)


def _action(move: tuple[float, ...]) -> int:
    """The move id whose (distance, body turn) the answer carries."""
    dist, turn = move_commands(np.arange(4), ControlConfig())
    (hit,) = [a for a in range(4) if (dist[a], turn[a]) == (move[0], move[1])]
    return hit


def test_history_rewards_by_hand() -> None:
    hist = (TurnEnergy(0, 100.0, "", 0.0, 0.0),  # turn 0: no previous record, no target
            TurnEnergy(1, 97.0, "e", 100.0, 100.0),  # we lost 3, the target nothing: (-3 - 0) * 0 / 3 = 0
            TurnEnergy(2, 97.0, "e", 100.0, 84.0),  # target lost 16, gap |97 - 100| = 3: (0 + 16) * 16 / 3
            TurnEnergy(3, 95.0, "", 0.0, 0.0))  # no target: 0
    rewards, own = history_rewards(hist, None)
    assert rewards == pytest.approx([0.0, 256 / 3, 0.0]) and own == 95.0
    # the first record's reward uses the own energy carried from the previous call: (100 - 103) - (40 - 50) = 7,
    # times |50 - 40| = 10, over |103 - 50| = 53
    rewards, own = history_rewards((TurnEnergy(5, 100.0, "e", 50.0, 40.0),), 103.0)
    assert rewards == pytest.approx([70 / 53]) and own == 100.0
    # the denominator is floored at the guard: (0 + 2) * 2 / max(0.5, guard)
    assert history_rewards((TurnEnergy(1, 50.0, "e", 50.5, 48.5),), 50.0)[0] == pytest.approx([4.0])
    assert history_rewards((TurnEnergy(1, 50.0, "e", 50.5, 48.5),), 50.0, guard=0.25)[0] == pytest.approx([8.0])
    assert history_rewards((), 42.0) == ([], 42.0)


def test_plain_float_eq35_equals_the_arenas() -> None:
    rng = np.random.default_rng(2)
    vals = np.concatenate([rng.uniform(0, 100, (2000, 4)), rng.choice([0.0, 0.5, 1.0, 100.0], (500, 4))])
    for guard in (1.0, 0.25):
        for a, b, c, d in vals:
            got = eq35(float(a), float(b), float(c), float(d), guard)
            assert got == float(reward_eq35(a, b, c, d, guard)) == reward_eq35_scalar(a, b, c, d, guard)


def test_smdp_steps_learn_the_history_rewards() -> None:
    learner, ref = TabularQ(), TabularQ()
    twin = ExportedPolicy("qtable", q=np.zeros((320, 4)))
    pol = LearnerPolicy(learner, np.random.default_rng(0), step_turns=2, acting=False)
    assert pol.bridge_kwargs() == {"every": 2, "controller": pol.control, "history": True, "acting": None}
    o1 = _obs(1, 100.0, 100.0, (TurnEnergy(0, 100.0, "", 0.0, 0.0),))
    m1 = pol(o1)  # first decision: nothing to learn yet
    assert pol.decisions == 1 and pol.updates == 0 and pol.reward_turns == 0
    assert all(math.isnan(v) for v in m1[2:])  # gun, radar, fire: the robot's own controller
    o3 = _obs(3, 97.0, 84.0, (TurnEnergy(1, 97.0, "e", 100.0, 100.0), TurnEnergy(2, 97.0, "e", 100.0, 84.0)),
              ex=100.0)
    m3 = pol(o3)
    s1, s3 = (twin.learner_observation(o, "discrete") for o in (o1, o3))
    assert s1[0] != s3[0]  # the enemy moved to another sector: the step's next state is the new observation
    # the step (s1, a1, r_1..r_2, s3) was learned as the simulator's SMDP step: the same update as by hand
    ref.learn(Transition(s1, np.array([_action(m1)]), np.array([[0.0, 256 / 3]]), s3, np.array([False])))
    assert pol.updates == 1 and learner.step == 1
    np.testing.assert_array_equal(learner.q, ref.q)
    # death: the last record's reward (-2 own, target unchanged: 0) closes the step as terminal
    pol.end_episode("me", 0, (TurnEnergy(3, 95.0, "e", 84.0, 84.0),))
    ref.learn(Transition(s3, np.array([_action(m3)]), np.array([[0.0]]), s3, np.array([True])))
    assert pol.updates == 2
    np.testing.assert_array_equal(learner.q, ref.q)
    assert pol.reward_turns == 3 and pol.reward_sum == pytest.approx(256 / 3)
    assert pol.reward_max == pytest.approx(256 / 3)
    pol.end_episode("me", 0, (TurnEnergy(4, 90.0, "e", 84.0, 70.0),))  # nothing open any more
    assert pol.updates == 2 and pol.reward_turns == 3
    # a new round starts a new chain: its first record earns nothing
    pol(_obs(1, 100.0, 100.0, (TurnEnergy(0, 100.0, "e", 100.0, 60.0),), round_=1))
    assert pol.reward_turns == 3
    pol.end_all()  # a step without any turn yet: nothing to learn
    assert pol.updates == 2
    with pytest.raises(ValueError, match="step_turns"):
        LearnerPolicy(learner, np.random.default_rng(0), step_turns=0)


def test_acting_robots_learn_from_the_moves_taken_and_get_every_change() -> None:
    """Observations that carry the robot's move: that move is learned, every learned row and the temperature
    after it are queued for the robots, and the policy file of the next hello is the table as it is then."""
    learned: list[int] = []

    class Spy(TabularQ):  # a tabular learner learns one transition at a time (learn_one: learn's bits)
        def learn_one(self, s: int, a: int, rewards: Sequence[float], s_next: int, done: bool) -> dict[str, float]:
            learned.append(a)
            return super().learn_one(s, a, rewards, s_next, done)

    learner = Spy()
    pol = LearnerPolicy(learner, np.random.default_rng(0), step_turns=2)
    acting = pol.bridge_kwargs()["acting"]
    assert acting is not None and acting.explore == "boltzmann" and acting.max_lag == pol.max_lag == 1
    start = acting.hello_lines()
    assert start[0].split()[:2] == ["acting", "boltzmann"] and float(start[0].split()[2]) == pytest.approx(0.1)
    assert "\n".join(start[1:]) + "\n" == ExportedPolicy("qtable", q=learner.q, step_turns=2).to_text()
    twin = ExportedPolicy("qtable", q=np.zeros((320, 4)))
    hist: tuple[TurnEnergy, ...] = (TurnEnergy(0, 100.0, "", 0.0, 0.0),)
    prev_state = -1
    for k, (own, enemy, ex, move) in enumerate([(100.0, 100.0, 400.0, 2), (97.0, 84.0, 100.0, 0),
                                                (97.0, 80.0, 700.0, 3), (90.0, 70.0, 400.0, 1)]):
        obs = replace(_obs(2 * k + 1, own, enemy, hist, ex=ex), action=move)
        assert all(math.isnan(v) for v in pol(obs))  # nothing to answer
        lines = acting.updates()
        if k == 0:
            assert lines == []  # nothing learned yet
        else:
            row = " ".join(repr(float(v)) for v in learner.q[prev_state])
            temperature = learner.params.exploration_params().temperature(learner.step)
            assert lines == [f"Q {prev_state} {row}", f"X {temperature!r} 0"]  # 0: the temperature still falls
        prev_state = int(twin.learner_observation(obs, "discrete")[0])
        hist = (TurnEnergy(2 * k + 1, own, "e", enemy, enemy - 3),
                TurnEnergy(2 * k + 2, own, "e", enemy - 3, enemy - 3))
    assert learned == [2, 0, 3] and pol.updates == 3 == learner.step and pol.decisions == 4
    assert "\n".join(acting.hello_lines()[1:]) + "\n" == ExportedPolicy("qtable", q=learner.q, step_turns=2).to_text()
    learner.load_state_dict({**learner.state_dict(), "q": np.ones((320, 4)), "step": np.array(7)})  # e.g. resumed
    assert "\n".join(acting.hello_lines()[1:]) + "\n" == ExportedPolicy("qtable", q=np.ones((320, 4)),
                                                                         step_turns=2).to_text()
    assert LearnerPolicy(learner, np.random.default_rng(0), explore=False).robot_acting().explore == "greedy"


def test_learners_robots_wait_only_for_updates_that_change_their_move() -> None:
    """A learner's robots wait for the rows they draw from (WAIT row), and for every update while the exploration
    parameter still changes: FIXED is 1 from the step where the annealed temperature has reached T_min exactly
    (T_n = T_min + (T_max - T_min) eta^n: 0.01 + 0.09 * 0.9^n rounds to 0.01 from about n = 380 on)."""
    learner = TabularQ()
    pol = LearnerPolicy(learner, np.random.default_rng(0), step_turns=2)
    acting = pol.robot_acting()
    assert acting is not None and acting.wait == "row" and acting.hello_lines()[0].endswith(" 1 row 0")
    first = next(n for n in range(2000) if learner._explore.temperature(n) == 0.01)
    assert 300 < first < 500 and learner._explore.temperature(first - 1) > 0.01
    for step, fixed in ((first - 1, False), (first, True), (10**6, True)):
        learner.step = step
        assert pol._param_fixed() is fixed and acting.hello_lines()[0].endswith(f" 1 row {int(fixed)}")
    learner.step = first - 1
    hist = (TurnEnergy(0, 100.0, "", 0.0, 0.0),)
    pol(replace(_obs(1, 100.0, 100.0, hist), action=0))
    pol(replace(_obs(3, 97.0, 84.0, (TurnEnergy(1, 97.0, "e", 100.0, 100.0),)), action=1))
    assert acting.updates()[-1] == "X 0.01 1"  # the update that reached T_min says so
    greedy = LearnerPolicy(TabularQ(), np.random.default_rng(0), explore=False).robot_acting()
    assert greedy is not None and greedy.hello_lines()[0].split()[-2:] == ["row", "1"]  # no parameter to wait for


@pytest.mark.parametrize("mode", ["acting", "python"])
def test_recorded_engine_stream_gives_the_table_of_the_code_before(mode: str) -> None:
    """A real engine training run's stream (tests/fixtures/bridge) fed to the learner policy, parsed as the server
    parses it: the same Q table bit for bit, steps, decisions and update lines as the code before the
    one-transition path (issue 11: cheaper, the same learning)."""
    import gzip
    import json
    from pathlib import Path

    from confront.engine.bridge import parse_history, parse_observation
    from confront.train.paper_model import build_learner
    from confront.train.spec import load_experiment

    fixtures = Path(__file__).parents[1] / "fixtures" / "bridge"
    cfg = load_experiment("demo", ["arena.scenario=1v1", "opponent.kind=SpinBot", "learner.kind=ssaq"])
    obs_cfg = ObservationConfig(target=cfg.arena.target)
    learner = build_learner(cfg, obs_cfg.n_features, 4)
    pol = LearnerPolicy(learner, np.random.default_rng([cfg.train.seed, 0]), observation=obs_cfg,
                        step_turns=cfg.arena.decision_turns, acting=mode == "acting")
    acting = pol.robot_acting() if mode == "acting" else None
    lines = 0
    with gzip.open(fixtures / f"ssaq_1v1_spinbot_{mode}.txt.gz", "rt") as f:
        for row in f:
            head, rest = row.rstrip("\n").split("\t", 1)
            who = json.loads(head)
            if who.get("end"):
                pol.end_episode(who["robot"], who["round"], parse_history(rest))
            else:
                hello = {"name": who["robot"], "team": "", "round": who["round"], "width": 800.0, "height": 600.0}
                pol(parse_observation(rest, hello, acting=acting is not None))
            lines += len(acting.updates()) if acting is not None else 0
    expected = np.load(fixtures / f"ssaq_1v1_spinbot_{mode}.expected.npz")
    assert learner.q.tobytes() == expected["q"].tobytes()
    assert learner.step == pol.updates == int(expected["step"]) > 100
    assert pol.decisions == int(expected["decisions"]) and lines == int(expected["update_lines"])


def test_observation_without_history_is_refused() -> None:
    pol = LearnerPolicy(TabularQ(), np.random.default_rng(0), step_turns=2)
    pol(_obs(1, 100.0, 100.0, ()))
    with pytest.raises(ValueError, match="history=True"):
        pol(_obs(3, 100.0, 100.0, ()))


@pytest.mark.engine
@pytest.mark.parametrize("acting", [True, False])
def test_tabular_learner_trains_live_in_engine(install, acting: bool) -> None:
    """Decided in Python (one round trip per decision), or by the robot from its own copy of the Q table."""
    learner = TabularQ()
    q0 = learner.q.copy()
    pol = LearnerPolicy(learner, np.random.default_rng(1), step_turns=4, acting=acting)
    assert (pol.bridge_kwargs()["acting"] is not None) == acting
    res = run_bridged_battle(BattleSpec((BRIDGE_BOT, "SittingDuck"), rounds=2), pol, **pol.bridge_kwargs())
    assert res.ok, (res.failures, res.server_errors)
    turns = sum(int(r["turns"]) for r in res.run.summary["round_scores"])
    # one round trip per T = 4 turns, and a reward for every turn played after the first decision
    assert res.decisions == pol.decisions <= turns / 4 + 2
    assert pol.reward_turns >= 4 * (pol.decisions - 2) - sum(res.run.skipped_turns.values())
    assert pol.updates >= pol.decisions - 2 > 20  # every SMDP step but the last open ones is learned
    assert learner.step == pol.updates
    assert not np.array_equal(learner.q, q0)
    assert pol.reward_max > 0  # it hit the duck


def test_learners_without_a_q_table_are_decided_in_python() -> None:
    """A DMNN (or any learner other than TabularQ) keeps the round trip per decision: no copy for the robots."""
    from confront.learning.dmnn import DMNN, DMNNParams

    pol = LearnerPolicy(DMNN(DMNNParams(n_inputs=7), np.random.default_rng(0)), np.random.default_rng(0),
                        step_turns=2)
    assert pol.robot_acting() is None and pol.bridge_kwargs()["acting"] is None
    move = pol(_obs(1, 100.0, 100.0, (TurnEnergy(0, 100.0, "", 0.0, 0.0),)))
    assert _action(move) in range(4) and pol.decisions == 1


def test_a_lost_end_line_drops_the_step_at_the_robots_next_round_and_is_counted() -> None:
    """The engine can stop a dying robot before its end line goes out. Its open step has no reward turn (they
    come with the next message), so it cannot be learned: it is dropped at the robot's first decision of the next
    round (or by end_all after the battle), leaves the table as it was, and is counted."""
    learner = TabularQ()
    pol = LearnerPolicy(learner, np.random.default_rng(0), step_turns=2, acting=False)
    pol(_obs(1, 100.0, 100.0, (TurnEnergy(0, 100.0, "", 0.0, 0.0),)))
    pol(_obs(3, 97.0, 84.0, (TurnEnergy(1, 97.0, "e", 100.0, 100.0), TurnEnergy(2, 97.0, "e", 100.0, 84.0)),
             ex=100.0))
    assert pol.updates == 1 and set(pol._tanks) == {("me", 0)}
    q = learner.q.copy()
    pol(_obs(1, 100.0, 100.0, (TurnEnergy(0, 100.0, "", 0.0, 0.0),), round_=1))  # no end line for round 0
    assert pol.lost_ends == 1 and set(pol._tanks) == {("me", 1)} and pol.updates == 1
    np.testing.assert_array_equal(learner.q, q)
    other = replace(_obs(1, 100.0, 100.0, (TurnEnergy(0, 100.0, "", 0.0, 0.0),), round_=2), robot="mate")
    pol(other)  # another robot's later round leaves this robot's step alone
    assert set(pol._tanks) == {("me", 1), ("mate", 2)} and pol.lost_ends == 1
    pol.end_episode("me", 1, (TurnEnergy(2, 99.0, "e", 100.0, 100.0),))  # an end line that came: not counted
    assert pol.lost_ends == 1 and pol.updates == 2
    pol.end_all()  # the battle ended with the mate's step open: dropped and counted
    assert pol.lost_ends == 2 and not pol._tanks
