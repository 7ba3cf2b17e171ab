"""Reference policies in the tank actions, no learning: what the controller alone does against each opponent
and what is left to learn. Our team plays uniformly random tank actions, or the hand-written strafer with a
fixed lead and fire power; prints the score share per opponent (the table in docs/learning.md), then JSON."""

from __future__ import annotations

import argparse
import json
import os

import numpy as np

from confront.train.league import build_pool, strafe_policy
from confront.train.loop import share_by_opponent
from confront.train.ppo_model import tank_space
from confront.train.spec import load_experiment

OPPONENTS = ["1v1:SpinBot", "1v1:Walls", "1v1:dodge", "4v4:dodge", "4v4:td", "1v1:strafe"]
POLICIES = {"uniformly random tank actions": None, "strafe, circular lead, power 1": ("circular", 1.0),
            "strafe, no lead, power 1": ("none", 1.0), "strafe, no lead, power 3": ("none", 3.0),
            "strafe, circular lead, power 2": ("circular", 2.0)}


def play(name: str, rounds: int, battles: int, seed: int) -> dict[str, float]:
    """Shares per opponent of one reference policy over ``rounds`` rounds in all."""
    cfg = load_experiment("tanks", ['league.opponents=' + json.dumps(OPPONENTS), f"league.battles={battles}"])
    space = tank_space(cfg)
    rng = np.random.default_rng(seed)
    strafe = strafe_policy(space)
    fixed = POLICIES[name]

    def act(obs: np.ndarray) -> np.ndarray:
        if fixed is None:
            return rng.integers(0, space.n_actions, len(obs))
        heads = list(np.unravel_index(strafe(np.zeros(len(obs)), obs, rng), space.dims))
        heads[2] = np.full_like(heads[2], space.fire_powers.index(fixed[1]))
        heads[4] = np.full_like(heads[4], space.leads.index(fixed[0]))
        return np.ravel_multi_index(tuple(heads), space.dims)

    pool, _ = build_pool(cfg, seed)
    obs, rows = pool.reset(), []
    while len(rows) < rounds:
        st = pool.step(act(obs))
        rows += st.rounds
        obs = st.obs
    return share_by_opponent(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rounds", type=int, default=500)
    ap.add_argument("--battles", type=int, default=16)
    ap.add_argument("--seed", type=int, default=5)
    args = ap.parse_args()
    out = {name: play(name, args.rounds, args.battles, args.seed) for name in POLICIES}
    print("| our team plays | " + " | ".join(OPPONENTS) + " |")
    print("|---|" + "---:|" * len(OPPONENTS))
    for name, shares in out.items():
        print(f"| {name} | " + " | ".join(f"{shares.get(o, float('nan')):.3f}" for o in OPPONENTS) + " |")
    print(json.dumps({"bench": "tank_references", "load": os.getloadavg()[0], "rounds": args.rounds, "shares": out}))


if __name__ == "__main__":
    main()
