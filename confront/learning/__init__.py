"""confront.learning: the paper's learners behind one interface (see docs/learning.md)."""

from confront.learning.base import Learner, Transition
from confront.learning.dmnn import DMNN, DMNNParams
from confront.learning.envloop import run_episodes, run_parallel_episodes
from confront.learning.factory import clone_learner, load_learner, make_learner, save_learner, transfer_from
from confront.learning.fuzzy import FuzzyLearningRate, FuzzyParams, paper_learning_rate, plot_fuzzy
from confront.learning.sharing import team_act, team_learn
from confront.learning.tabular import TabularParams, TabularQ
from confront.learning.transfer import CurriculumStage, Frozen, TransferParams, TransferPolicy, transfer_epsilon

__all__ = [
    "DMNN",
    "CurriculumStage",
    "DMNNParams",
    "Frozen",
    "FuzzyLearningRate",
    "FuzzyParams",
    "Learner",
    "TabularParams",
    "TabularQ",
    "TransferParams",
    "TransferPolicy",
    "Transition",
    "clone_learner",
    "load_learner",
    "make_learner",
    "paper_learning_rate",
    "plot_fuzzy",
    "run_episodes",
    "run_parallel_episodes",
    "save_learner",
    "team_act",
    "team_learn",
    "transfer_epsilon",
    "transfer_from",
]
