"""A PPO tank of a config: its actions and view (``arena.tank.TankSpace``), its SMDP step, and its model files.

A run's ``model/``: ``model.json`` (kind ppo), ``actor.npz`` (w0, b0, ... as (out, in): what the exported robot
plays), ``tank.json`` (actions, view, controller) and ``ppo.npz`` (the whole learner, to continue training).
"""

from __future__ import annotations

import json
import math
import zipfile
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from confront import checkpoint as ck
from confront.arena.observe import ObservationConfig
from confront.arena.smdp import SMDPConfig
from confront.arena.tank import TankSpace
from confront.learning.ppo import PPO
from confront.train.spec import ExperimentConfig

__all__ = ["tank_space", "skill_logits", "smdp_tank_config", "save_tank_model", "load_tank_model"]


def tank_space(cfg: ExperimentConfig) -> TankSpace:
    """The config's tank actions and view."""
    t = cfg.tank
    return TankSpace(distances=tuple(t.distances), turns_deg=tuple(t.turns_deg), turn_mode=t.turn_mode,
                     fire_powers=tuple(t.fire_powers), enemy_slots=t.enemy_slots, mate_slots=t.mate_slots,
                     leads=tuple(t.leads), surf=t.surf, knowledge=t.knowledge, brain=t.brain)


BRAIN_POWER = 2.0  # the brain's gun at 400 px: min(3, 1.2 + 300 / d) (tech.py, _aim_and_fire)


def skill_logits(space: TankSpace, prior: float) -> np.ndarray:
    """(sum(dims),) initial logit bonus of the skills' choices (``tank.skill_prior``): ``prior`` on surf (the
    distance head's last entry), on the gf lead and, with the gf lead, on the fire power nearest the brain's
    (BRAIN_POWER); 0 elsewhere (all 0 without those skills)."""
    out = np.zeros(sum(space.dims))
    if space.surf:
        out[len(space.distances)] = prior
    if "gf" in space.leads:
        out[sum(space.dims[:4]) + space.leads.index("gf")] = prior
        fire = [abs(p - BRAIN_POWER) if p > 0 else math.inf for p in space.fire_powers]
        if min(fire) < math.inf:
            out[sum(space.dims[:2]) + int(np.argmin(fire))] = prior
    return out


def smdp_tank_config(cfg: ExperimentConfig) -> SMDPConfig:
    """The SMDP step of a PPO tank."""
    return SMDPConfig(turns_per_step=cfg.tank.decision_turns, tank=tank_space(cfg), reward=cfg.tank.reward,
                      observation=ObservationConfig(sensing="scanned"))


def _read_npz(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def save_tank_model(folder: Path, ppo: PPO, cfg: ExperimentConfig, meta: dict[str, Any]) -> None:
    """``model.json`` (kind ppo), ``actor.npz`` (w0, b0, ... as (out, in)), ``tank.json`` (actions, view,
    controller), ``ppo.npz`` (the whole learner, to continue training)."""
    folder.mkdir(parents=True, exist_ok=True)
    ck.write_npz(folder / "actor.npz", ppo.actor_arrays())
    ck.write_npz(folder / "ppo.npz", ppo.state_dict())
    from confront.arena.control import ControlConfig

    c = ControlConfig()
    tank = {**asdict(tank_space(cfg)), "step_turns": cfg.tank.decision_turns, "hidden": cfg.ppo.hidden,
            "team_critic": cfg.ppo.team_critic, "radar_overshoot": c.radar_overshoot,
            "aim_tolerance": c.aim_tolerance, "n_features": ppo.n_features, "dims": list(ppo.dims)}
    ck.write_atomic(folder / "tank.json", json.dumps(tank, indent=1, sort_keys=True).encode())
    info = {"format": "confront-model/1", "kind": "ppo", "observation": "tank", "n_actions": ppo.n_actions, **meta}
    ck.write_atomic(folder / "model.json", json.dumps(info, indent=1, sort_keys=True).encode())


def load_tank_model(folder: str | Path, cfg: ExperimentConfig) -> PPO:
    """The PPO learner of a run folder (or its ``model/``)."""
    p = Path(folder)
    if (p / "model").is_dir():
        p = p / "model"
    space = tank_space(cfg)
    ppo = PPO(space.n_features, space.dims, cfg.ppo)
    try:
        state = _read_npz(p / "ppo.npz")
        bad = [k for k, v in state.items() if v.dtype.kind in "fc" and not np.all(np.isfinite(v))]
        if bad:
            raise ValueError(f"its arrays {', '.join(bad[:5])} hold NaN or infinite values")
        ppo.load_state_dict(state)
    except FileNotFoundError:
        raise FileNotFoundError(f"no trained PPO model in {folder} (expected model/ppo.npz)") from None
    except (OSError, ValueError, KeyError, TypeError, RuntimeError, EOFError, zipfile.BadZipFile) as exc:
        raise ck.CheckpointError(f"model {p} cannot be read: {' '.join(str(exc).split())[:200]}") from None
    return ppo
