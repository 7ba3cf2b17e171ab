import gymnasium
import numpy as np

from confront.experiments.migration import BinaryTreeMigration
from confront.learning import make_learner
from confront.learning.envloop import run_episodes


def test_td_learner_solves_frozen_lake():
    env = gymnasium.make("FrozenLake-v1", is_slippery=False)
    rng = np.random.default_rng(0)
    lr = make_learner("qlearning_egreedy", n_states=16, n_actions=4, alpha=0.5, gamma=0.95, exploit=0.7)
    run_episodes(env, lr, rng, 600)
    assert run_episodes(env, lr, rng, 5, learn=False, explore=False, max_steps=50).tolist() == [1.0] * 5


def test_dmnn_on_one_hot_states_solves_a_small_tree():
    env = BinaryTreeMigration(layers=3, reward=1.0)
    rng = np.random.default_rng(1)
    lr = make_learner("dmnn", observation="discrete", n_inputs=8, n_actions=2, hidden=(8,), alpha=1.0,
                      awm=False, nn_rate=0.5, q_scale=1.0, t_max=0.5, t_min=0.05, eta=0.99)
    run_episodes(env, lr, rng, 300)
    assert np.allclose(run_episodes(env, lr, rng, 3, learn=False, explore=False), 1.0)
    q = lr.q_values(np.array([1, 3]))
    assert q[0, 1] > q[0, 0] and q[1, 1] > q[1, 0]


def test_actions_held_for_the_sojourn():
    env = BinaryTreeMigration(layers=5)  # 4 decisions, held 2 at a time: 2 SMDP steps per episode
    lr = make_learner("ssaq", n_states=32, n_actions=2, backup="smdp")
    rng = np.random.default_rng(2)
    run_episodes(env, lr, rng, 200, sojourn=2)
    assert lr.step == 400
    # right-right from 7 reaches the goal 31 on the second held turn: Q(7, right) = 0 + 0.9 * 1000 (smdp);
    # right-right from the root reaches 7: Q(1, right) = 0.9^2 * 900
    assert np.isclose(lr.q[7, 1], 900.0, rtol=1e-3)
    assert np.isclose(lr.q[1, 1], 729.0, rtol=1e-2)
    # only the root and layer 3 (nodes 4..7) are decision points when actions are held for 2 layers
    assert not lr.q[[2, 3, 8, 15]].any()


def test_dmnn_with_awm_and_default_scaling_learns_the_tree():
    env = BinaryTreeMigration(layers=4, reward=10.0)
    rng = np.random.default_rng(0)
    lr = make_learner("dmnn", observation="discrete", n_inputs=16, n_actions=2, hidden=(16,), alpha=0.5,
                      t_max=1.0, t_min=0.1, eta=0.995)
    run_episodes(env, lr, rng, 800)
    assert np.allclose(run_episodes(env, lr, rng, 3, learn=False, explore=False), 10.0)
    q = lr.q_values(np.array([1, 3, 7]))
    # limits 8.1, 9, 10 (paper backup, gamma 0.9); AWM's rate shrinks with the error, so it nears them slowly
    assert np.allclose(q[:, 1], [8.1, 9.0, 10.0], atol=1.0)
    assert np.all(q[:, 0] < q[:, 1] - 5)


class _TwoTreeWalkers:
    """A minimal PettingZoo-style parallel env: two agents each walk their own 3-layer tree."""

    possible_agents = ["a", "b"]

    def reset(self, seed=None, options=None):
        self.agents = list(self.possible_agents)
        self.node = {"a": 1, "b": 1}
        return dict(self.node), {ag: {} for ag in self.agents}

    def step(self, actions):
        obs, rew, term, trunc = {}, {}, {}, {}
        for ag, act in actions.items():
            self.node[ag] = 2 * self.node[ag] + act
            obs[ag] = self.node[ag]
            rew[ag] = 1.0 if self.node[ag] == 7 else 0.0
            term[ag] = self.node[ag] >= 4
            trunc[ag] = False
        self.agents = [ag for ag in self.agents if not term.get(ag, False)]
        return obs, rew, term, trunc, {ag: {} for ag in actions}


def test_parallel_agents_share_one_learner():
    from confront.learning.envloop import run_parallel_episodes

    env = _TwoTreeWalkers()
    lr = make_learner("qlearning_egreedy", n_states=8, n_actions=2, alpha=0.5, exploit=0.5)
    rng = np.random.default_rng(3)
    run_parallel_episodes(env, lr, rng, 200)
    assert lr.step == 400  # 2 SMDP steps per episode, each one batch of both agents
    assert run_parallel_episodes(env, lr, rng, 2, learn=False, explore=False).tolist() == [2.0, 2.0]
    assert np.isclose(lr.q[3, 1], 1.0) and np.isclose(lr.q[1, 1], 0.9)
