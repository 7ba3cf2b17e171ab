"""A learner (``confront.learning``) as a bridge policy: evaluate it, or train it live in the real engine.

Run with the bridge's decision mode (``run_bridged_battle(..., **policy.bridge_kwargs())``: ``every`` =
``step_turns``, the fixed gun/radar ``controller`` in Java every turn, ``history=True``): each BridgeBot tank
asks only in its decision turns (1, 1 + T, ...), and the learner picks one of the paper's four moves
(parameter sharing: one learner for every tank). The per-turn reward is the paper's Eq. 35, computed from the
robot's per-turn energy records (``Observation.history``, :class:`~confront.engine.bridge.TurnEnergy`) on the
tank's energy and its target's (the nearest enemy by last scans, as the Java controller picks it). With
``train=True`` each finished SMDP step (the decision, the T per-turn rewards r_t..r_{t+T-1}, the next
decision's observation) is passed to ``learner.learn`` at once; ``end_episode`` (death or round end) adds the
last rewards and learns the open step as terminal. With ``acting`` (the default) and a tabular learner the
robots pick the moves themselves from their own copy of the Q table, kept current by every update
(:meth:`LearnerPolicy.robot_acting`), so the engine does not wait for a round trip per decision.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from confront.arena.control import ControlConfig, move_commands
from confront.arena.observe import ObservationConfig
from confront.engine.bridge import Observation, RobotActing, TurnEnergy
from confront.engine.export import ExportedPolicy
from confront.learning.base import Learner, Transition
from confront.learning.exploration import ExplorationParams
from confront.learning.tabular import TabularQ


def eq35(own_prev: float, own_now: float, enemy_prev: float, enemy_now: float, guard: float = 1.0) -> float:
    """``confront.arena.observe.reward_eq35`` on plain floats (the same operations, so the same double; a test
    checks this): about 10x cheaper than the NumPy function called on scalars."""
    delta = (own_now - own_prev) - (enemy_now - enemy_prev)
    return delta * abs(enemy_prev - enemy_now) / max(abs(own_prev - enemy_prev), guard)


def history_rewards(history: Sequence[TurnEnergy], own_prev: float | None,
                    guard: float = 1.0) -> tuple[list[float], float | None]:
    """Eq. 35 per history record, and the last record's own energy (to carry to the next call).

    ``own_prev`` is the own energy of the record before ``history[0]`` (None: there was none, so the first
    record only starts the chain). A record without a target (``target == ""``) earns 0.
    """
    rewards: list[float] = []
    for h in history:
        if own_prev is not None:
            # Eq. 35 on (own, target) energies at the previous record and at this one; no target: 0
            r = 0.0 if h.target == "" else eq35(own_prev, h.energy, h.target_previous, h.target_energy, guard)
            rewards.append(r)
        own_prev = h.energy
    return rewards, own_prev


@dataclass
class _Tank:
    """One tank's open SMDP step in one round (``obs`` None before its first decision)."""

    obs: np.ndarray | None = None
    action: int = 0
    rewards: list[float] = field(default_factory=list)
    own: float | None = None  # own energy at the last history record


class LearnerPolicy:
    """Bridge policy around a :class:`~confront.learning.base.Learner` (see the module docstring)."""

    def __init__(
        self,
        learner: Learner,
        rng: np.random.Generator,
        train: bool = True,
        explore: bool = True,
        observation: ObservationConfig | None = None,
        control: ControlConfig | None = None,
        step_turns: int = 4,
        acting: bool = True,
        max_lag: int = 1,
    ) -> None:
        if step_turns < 1:
            raise ValueError(f"step_turns must be >= 1, got {step_turns}")
        self.learner = learner
        self.rng = rng
        self.train = train
        self.explore = explore
        self.step_turns = step_turns
        self.obs_config = observation or ObservationConfig()
        self.control = control or ControlConfig()
        self.acting = acting
        self.max_lag = max_lag
        self._updates: list[str] = []  # lines for the robots' own copies (robot_acting), drained by the bridge
        self._sync = False  # a robot_acting() copy exists: queue every change of the Q table
        self._text: tuple[list[str], list[str]] | None = None  # the policy file: head lines, one line per Q row
        self._text_step = -1  # the learner's step the cached rows belong to
        self._explore: ExplorationParams | None = None  # the tabular learner's exploration (robot_acting)
        # the twin builds the learner's observation; its Q table is never used
        self._twin = ExportedPolicy("qtable", q=np.zeros((320, 4)), observation=self.obs_config,
                                    control=self.control, step_turns=step_turns)
        self._tanks: dict[tuple[str, int], _Tank] = {}
        self.updates = 0
        self.decisions = 0
        self.lost_ends = 0  # steps closed without the robot's end line (at its next round, or by end_all)
        self.reward_turns = 0
        self.reward_sum = 0.0
        self.reward_max = -math.inf

    def bridge_kwargs(self) -> dict[str, Any]:
        """The ``run_bridged_battle`` settings this policy needs: a decision every ``step_turns`` turns, the
        gun/radar controller in Java, per-turn energy history, and (``acting`` and a tabular learner) robots
        that pick their moves from their own copy of the Q table (:meth:`robot_acting`)."""
        return {"every": self.step_turns, "controller": self.control, "history": True,
                "acting": self.robot_acting() if self.acting else None}

    def robot_acting(self) -> RobotActing | None:
        """The robots pick the moves themselves, from a copy of the learner's Q table with its exploration
        (Boltzmann at its temperature, epsilon-greedy at its threshold; greedy with random ties when not
        exploring), and Python only learns: every changed Q row and the exploration parameter after each update
        go to every robot, and a robot waits when ``max_lag`` of its observations are not yet taken in. With
        ``max_lag`` = 1 the move at decision k is drawn from the table with every update up to the step that
        ended at decision k - 1 (the simulator's also has the step ending at k). None for learners other than
        :class:`~confront.learning.tabular.TabularQ` (their moves are then decided in Python)."""
        learner = self.learner
        if not isinstance(learner, TabularQ) or learner.q.shape != (320, 4):
            return None
        self._sync = True
        explore = self._explore = learner.params.exploration_params()
        kind = "greedy" if not self.explore else "boltzmann" if explore.kind == "boltzmann" else "egreedy"

        def model() -> str:
            if self._text is None or self._text_step != learner.step:  # e.g. a checkpoint was loaded
                lines = ExportedPolicy("qtable", q=learner.q, observation=self.obs_config, control=self.control,
                                       step_turns=self.step_turns).to_text().splitlines()
                n = len(learner.q)
                self._text, self._text_step = (lines[:-n], lines[-n:]), learner.step
            head, rows = self._text
            return "\n".join(head + rows) + "\n"

        return RobotActing(model=model, explore=kind, param=self._param, max_lag=self.max_lag,
                           seed=lambda: int(self.rng.integers(1 << 62)), updates=self._drain, wait="row",
                           fixed=self._param_fixed)

    def _param(self, step: int | None = None) -> float:
        """The learner's exploration parameter now (or after ``step`` updates): the temperature (Boltzmann) or the
        exploitation threshold."""
        explore = self._explore  # the learner's (frozen) parameters, made once by robot_acting
        assert explore is not None
        if step is None:
            step = self.learner.step  # type: ignore[attr-defined]
        return explore.temperature(step) if explore.kind == "boltzmann" else explore.threshold(step)

    def _param_fixed(self) -> bool:
        """No later update changes the robots' exploration parameter: it does not explore, or the schedule has
        reached its limit (the annealed temperature or the decaying threshold are monotone in the step)."""
        return not self.explore or self._param() == self._param(1 << 62)

    def _drain(self) -> list[str]:
        out, self._updates = self._updates, []
        return out

    def _add_rewards(self, tank: _Tank, history: Sequence[TurnEnergy]) -> None:
        rewards, tank.own = history_rewards(history, tank.own, self.obs_config.reward_guard)
        if tank.obs is not None:  # rewards before the first decision belong to no step
            tank.rewards += rewards
            self.reward_turns += len(rewards)
            self.reward_sum += sum(rewards)
            self.reward_max = max([self.reward_max, *rewards])

    def _learn(self, tank: _Tank, next_obs: np.ndarray, done: bool) -> None:
        if self.train and tank.obs is not None and tank.rewards:
            if isinstance(self.learner, TabularQ):  # one transition on Python numbers: the same bits, 4x cheaper
                self.learner.learn_one(int(tank.obs[0]), tank.action, tank.rewards, int(next_obs[0]), done)
            else:
                self.learner.learn(Transition(tank.obs, np.array([tank.action]), np.array([tank.rewards]),
                                              next_obs, np.array([done])))
            self.updates += 1
            if self._sync:  # the robots' copies: the row that changed, and the exploration parameter now
                s = int(tank.obs[0])
                row = " ".join(map(repr, self.learner.q[s].tolist()))  # type: ignore[attr-defined]
                self._updates.append(f"Q {s} {row}")
                if self._text is not None and self._text_step == self.learner.step - 1:  # type: ignore[attr-defined]
                    self._text[1][s] = row  # the policy file of the next hello, kept current row by row
                    self._text_step += 1
                if self.explore:
                    self._updates.append(f"X {self._param()!r} {int(self._param_fixed())}")

    def __call__(self, obs: Observation) -> tuple[float, float, float, float, float]:
        """A decision turn: learn the step that ends here, pick the next move; gun, radar, fire are NaN (the
        robot's controller aims). A robot's first decision of a round closes any step it left open in an earlier
        round (the engine can stop a dying robot's thread before its end line goes out): the step's reward turns
        would have come with that line, so it is dropped unlearned and counted in ``lost_ends``."""
        key = (obs.robot, obs.round)
        if key not in self._tanks:
            for robot, round_ in [k for k in self._tanks if k[0] == obs.robot and k[1] < obs.round]:
                self._close_unended(robot, round_)
        tank = self._tanks.setdefault(key, _Tank())
        if tank.obs is not None and not obs.history:
            raise ValueError(f"no energy history in {obs.robot}'s observation of turn {obs.turn}: "
                             "run the bridge with history=True (LearnerPolicy.bridge_kwargs())")
        self._add_rewards(tank, obs.history)
        x = self._twin.learner_observation(obs, self.learner.observation)
        self._learn(tank, x, done=False)
        if obs.action >= 0:  # the robot has moved itself (robot_acting): learn from the move it took
            tank.obs, tank.action, tank.rewards = x, obs.action, []
            self.decisions += 1
            return (math.nan,) * 5
        tank.obs, tank.action, tank.rewards = x, int(self.learner.act(x, self.rng, explore=self.explore)[0]), []
        self.decisions += 1
        dist, turn = move_commands(np.array([tank.action]), self.control)
        return (float(dist[0]), float(turn[0]), math.nan, math.nan, math.nan)

    def end_episode(self, robot: str, round_: int, history: Sequence[TurnEnergy] = ()) -> None:
        """The tank died or its round ended: add the last turns' rewards and learn its open step as terminal."""
        tank = self._tanks.pop((robot, round_), None)
        if tank is not None and tank.obs is not None:
            self._add_rewards(tank, history)
            self._learn(tank, tank.obs, done=True)

    def end_all(self) -> None:
        """Close every step still open (a battle ended without a tank's end message): learned as terminal if it
        has reward turns, else dropped; each counts in ``lost_ends``."""
        for robot, round_ in list(self._tanks):
            self._close_unended(robot, round_)

    def _close_unended(self, robot: str, round_: int) -> None:
        """Close a step whose end line never came (counted in ``lost_ends``)."""
        self.lost_ends += self._tanks[(robot, round_)].obs is not None
        self.end_episode(robot, round_)
