"""PPO hyper-parameters: the one configuration of the PPO learner (``confront.learning.ppo``) and of a config's
``[ppo]`` section, validated once where a config is read (``confront.config.from_dict``: bounds and types).

Apart from ``ppo.py`` (which loads torch) so that reading a config does not load torch.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from confront.config import field

__all__ = ["PPOConfig"]


@dataclass(frozen=True)
class PPOConfig:
    """PPO hyper-parameters (confront.learning.ppo)."""

    hidden: int = field(128, ge=1, le=4096)
    critic_hidden: int = field(0, ge=0, le=4096, doc="the critic's width (0: hidden): 64 updates 1.29x faster but "
                               "trained worse greedy 1v1 play on its one seed (docs/learning.md)")
    lr: float = field(2.5e-3, gt=0.0, le=1.0, doc="Adam step (measured: 2.5e-3 learned ~2x faster than 1e-3)")
    rollout_steps: int = field(32, ge=1, le=4096)
    epochs: int = field(4, ge=1, le=100, doc="passes over each rollout (the demo uses 2 x 2: docs/learning.md)")
    minibatches: int = field(4, ge=1, le=1024)
    gamma: float = field(0.97, ge=0.0, le=1.0, doc="discount per decision (T turns): a horizon of ~33 decisions")
    gae_lambda: float = field(0.95, ge=0.0, le=1.0)
    clip: float = field(0.2, gt=0.0, le=10.0)
    ent_coef: float = field(0.01, ge=0.0, le=10.0)
    ent_coef_end: float = field(0.01, ge=0.0, le=10.0, doc="entropy coefficient after ent_anneal_updates")
    ent_anneal_updates: int = field(0, ge=0, doc="updates over which ent_coef goes linearly to ent_coef_end (0: off)")
    vf_coef: float = field(0.5, ge=0.0, le=100.0)
    value_warmup_updates: int = field(0, ge=0, doc="the first updates train the critic alone (the actor keeps its "
                                      "initial policy, e.g. tank.skill_prior's, until the advantages mean something)")
    max_grad_norm: float = field(0.5, gt=0.0)
    reward_scale: float = field(0.01, gt=0.0, doc="score points -> reward units")
    team_critic: bool = field(True, doc="the critic also sees the mean view of the tank's team (MAPPO-style)")
    overlap: bool = field(False, doc="update on a second thread while the next rollout is collected (acting one "
                          "update behind, decoupled PPO); false: collect, then update (docs/learning.md)")
    ema_decay: float = field(0.0, ge=0.0, lt=1.0, doc="> 0: a Polyak average of the actor after each update "
                             "(decay per update), the policy the finished run saves and plays; 0: the last actor")
    anneal_lr: bool = field(False, doc="the Adam step falls linearly from lr to 0 over train.rounds (CleanRL's "
                            "anneal_lr)")
    threads: int = field(2, ge=1, le=256, doc="torch threads of the update (acting uses one): 2 updates 1.7x faster "
                         "than 1 on the idle 2-core machine; the float sums, hence the run's bits, depend on it")
    precision: Literal["fp32", "bf16", "bf16-hidden"] = field(
        "fp32", doc="the update's layers: fp32; bf16 (all but the output layer as bfloat16 products under autocast, "
        "float32 sums and weights: a 1.5x faster update on CPUs with bfloat16 instructions, but worse 1v1 play where "
        "measured); bf16-hidden (the hidden-to-hidden layer only); docs/learning.md")
