"""The paper's learners of a config (§3-4): the scenario, the SMDP step, the shared learner, curriculum transfer
(§5, Eq. 33-34) and the model files a run leaves (``model/learner.npz`` + ``model.json``, no pickle).

Used by both paper trainers (``paper_sim``, ``paper_engine``), the TD team (``league``) and the studies.
"""

from __future__ import annotations

import json
import os
import tempfile
import zipfile
from pathlib import Path
from typing import Any

from confront import checkpoint as ck
from confront.arena.scenarios import Scenario, get_scenario, load_scenario, scenario_names
from confront.arena.smdp import SMDPConfig
from confront.config import ConfigError
from confront.learning.base import Learner
from confront.learning.factory import load_learner, make_learner, save_learner
from confront.learning.transfer import TransferParams, TransferPolicy
from confront.train.spec import ExperimentConfig

__all__ = ["scenario_of", "smdp_config", "build_learner", "with_transfer", "save_model", "load_model"]


def scenario_of(name: str) -> Scenario:
    """A named scenario or a scenario TOML file (a ConfigError naming it when it is neither)."""
    try:
        return load_scenario(name) if name.endswith(".toml") else get_scenario(name)
    except (OSError, ValueError, TypeError, RecursionError) as exc:  # TOML and Unicode errors are ValueErrors
        raise ConfigError(f"scenario {name!r} cannot be used ({str(exc).splitlines()[0][:200]}): give one of "
                          f"{', '.join(scenario_names())} or a scenario .toml file") from None


def smdp_config(cfg: ExperimentConfig) -> SMDPConfig:
    """The SMDP step of the paper's learners: T turns per decision, the action set, what a tank observes."""
    from confront.arena.observe import ObservationConfig

    return SMDPConfig(turns_per_step=cfg.arena.decision_turns, fire_power_actions=cfg.arena.fire_power_actions,
                      observation=ObservationConfig(target=cfg.arena.target, sensing=cfg.arena.sensing))


def build_learner(cfg: ExperimentConfig, n_features: int, n_actions: int) -> Learner:
    """The learning team's learner from the config (shared by every tank: parameter sharing, §4.2)."""
    lc = cfg.learner
    common: dict[str, Any] = dict(n_actions=n_actions, gamma=lc.gamma, alpha=lc.alpha, rate=lc.learning_rate,
                                  backup=lc.backup, exploration="boltzmann", t_max=lc.t_max, t_min=lc.t_min, eta=lc.eta)
    if lc.kind == "ssaq":
        return make_learner("ssaq", n_states=320, **common)
    if lc.kind == "random":
        return make_learner("random", n_actions=n_actions)
    return make_learner("dmnn", n_inputs=n_features, observation="features", hidden=lc.hidden, awm=lc.awm,
                        momentum=lc.momentum, nn_rate=lc.nn_rate, output=lc.output, q_scale=lc.q_scale,
                        td_clip=lc.td_clip, init_seed=cfg.train.seed, **common)


def with_transfer(cfg: ExperimentConfig, learner: Learner) -> tuple[Learner, dict[str, Any]]:
    """Curriculum transfer (``transfer.source``): the learner wrapped to act from the source model with Eq. 34's
    epsilon (and started from its weights with ``init_from_source``); the learner itself when there is none."""
    tc = cfg.transfer
    if not tc.source:
        return learner, {}
    source, _ = load_model(tc.source)
    if (source.n_actions, source.observation) != (learner.n_actions, learner.observation):
        raise ck.CheckpointError(
            f"transfer.source {tc.source} has {source.n_actions} actions on {source.observation} observations; "
            f"this task needs {learner.n_actions} on {learner.observation} (Eq. 33)")
    if tc.init_from_source:
        learner.load_state_dict(source.state_dict())
    return TransferPolicy(learner, source, TransferParams(tc.epsilon0, tc.decay, 0, tc.floor)), \
        {"transfer_source": tc.source}


def save_model(folder: Path, learner: Learner, meta: dict[str, Any]) -> None:
    """``learner.npz`` (kind, parameters and state; no pickle) + ``model.json`` (the task it was trained on)."""
    folder.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=folder, prefix=".learner.", suffix=".npz")  # unique: writers may race
    os.close(fd)
    tmp = Path(name)
    try:
        save_learner(tmp, learner.current if isinstance(learner, TransferPolicy) else learner)
        os.replace(tmp, folder / "learner.npz")
    finally:
        tmp.unlink(missing_ok=True)
    info = {"format": "confront-model/1", "kind": learner.kind, "observation": learner.observation,
            "n_actions": learner.n_actions, **meta}
    ck.write_atomic(folder / "model.json", json.dumps(info, indent=1, sort_keys=True).encode())


def load_model(folder: str | Path) -> tuple[Learner, dict[str, Any]]:
    """Load a learner written by :func:`save_model` (a run folder, its ``model/``, or a model folder)."""
    p = Path(folder)
    if (p / "model").is_dir():
        p = p / "model"
    try:
        info = json.loads((p / "model.json").read_text(encoding="utf-8"))
    except (FileNotFoundError, NotADirectoryError):
        raise FileNotFoundError(f"no trained model in {folder} (expected model/model.json)") from None
    except (ValueError, OSError, RecursionError) as exc:  # JSON and Unicode errors are ValueErrors
        raise ck.CheckpointError(f"model {p} has a corrupt model.json ({str(exc)[:200]})") from None
    if not isinstance(info, dict) or info.get("format") != "confront-model/1":
        what = info.get("format") if isinstance(info, dict) else type(info).__name__
        raise ck.CheckpointError(f"{p} is not a confront model (format {what!r})")
    try:
        learner = load_learner(p / "learner.npz", frozen=False)
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile) as exc:
        raise ck.CheckpointError(f"model {p} cannot be read: {str(exc)[:200]}") from None
    return learner, info
