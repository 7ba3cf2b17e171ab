import numpy as np
import pytest

from confront.learning import Frozen, Transition, clone_learner, load_learner, make_learner, save_learner


def test_kinds_and_presets():
    ssaq = make_learner("ssaq")
    assert (ssaq.params.exploration, ssaq.params.backup, ssaq.params.bootstrap) == ("boltzmann", "paper",
                                                                                      "expected")
    td = make_learner("qlearning_egreedy", alpha=0.2)
    assert (td.params.exploration, td.params.backup, td.params.bootstrap, td.params.alpha) == (
        "egreedy", "smdp", "max", 0.2)
    assert make_learner("qlearning_dgreedy").params.exploration == "degreedy"
    net = make_learner("dmnn", hidden=[16, 8])
    assert net.params.hidden == (16, 8) and [w.shape for w in net.weights] == [(8, 16), (16, 8), (8, 4)]
    assert net.observation == "features" and ssaq.observation == "discrete"


def test_bad_kind_key_and_value_messages():
    with pytest.raises(ValueError, match="kind='ppo'"):
        make_learner("ppo")
    with pytest.raises(ValueError, match="unknown parameter 'alhpa'"):
        make_learner("ssaq", alhpa=0.1)
    with pytest.raises(ValueError, match=r"gamma=1.5: must be in \[0.0, 1.0\]"):
        make_learner("ssaq", gamma=1.5)
    with pytest.raises(ValueError, match="grid_size"):
        make_learner("ssaq", rate="fuzzy", fuzzy={"grid_size": 1})


@pytest.mark.parametrize("kind", ["ssaq", "qlearning_egreedy", "dmnn"])
def test_save_load_round_trip_without_pickle(tmp_path, kind):
    rng = np.random.default_rng(0)
    extra = {"hidden": (6,), "rate": "fuzzy"} if kind == "dmnn" else {"n_states": 10, "rate": "fuzzy"}
    lr = make_learner(kind, fuzzy={"grid_size": 601}, **extra)
    obs = rng.normal(size=(4, 8)) if kind == "dmnn" else rng.integers(0, 10, 4)
    lr.learn(Transition(obs, np.array([0, 1, 2, 3]), rng.normal(size=(4, 2)), obs, np.zeros(4, dtype=bool)))
    path = save_learner(tmp_path / "m.npz", lr)
    with np.load(path, allow_pickle=False) as data:
        assert "__meta__" in data.files
    back = load_learner(path)
    assert back.kind == kind and back.params == lr.params
    assert back._fuzzy.params.grid_size == 601
    for k, v in lr.state_dict().items():
        assert np.array_equal(back.state_dict()[k], v)
    assert np.array_equal(back.act(obs, np.random.default_rng(1), False), lr.act(obs, np.random.default_rng(1),
                                                                                  False))
    assert isinstance(load_learner(save_learner(tmp_path / "f.npz", Frozen(lr))), Frozen)
    assert not isinstance(load_learner(tmp_path / "f.npz", frozen=False), Frozen)


def test_clone_is_independent():
    lr = make_learner("ssaq", n_states=3, n_actions=2)
    lr.q[0, 0] = 1.0
    cp = clone_learner(lr)
    cp.q[0, 0] = 2.0
    assert lr.q[0, 0] == 1.0 and cp.params == lr.params
