"""What the tank's skills alone do: a fixed policy in the tanks-tech actions (always surf, the gf lead, one fire
power, the nearest target) against league entries, no learning; or, with ``--prior P``, the untrained PPO policy
whose heads carry that skill prior (what training starts from). The reference for docs/learning.md, "Tanks against
the technique robots": prints the share per entry, then one JSON line."""

from __future__ import annotations

import argparse
import json
import os

import numpy as np

from confront.arena.tech import TECH_ROBOTS
from confront.learning.ppo import PPO
from confront.train.league import build_pool
from confront.train.loop import share_by_opponent
from confront.train.ppo_model import skill_logits, tank_space
from confront.train.spec import load_experiment


def play(entries: list[str], power: float, lead: str, rounds: int, battles: int, seed: int,
         prior: float | None = None) -> dict[str, float]:
    """Shares per entry of the fixed skill policy (or the untrained policy of skill prior ``prior``) over ``rounds``
    rounds in all."""
    cfg = load_experiment("tanks-tech", ["league.opponents=" + json.dumps(entries), f"league.battles={battles}",
                                         "league.prioritise=false"])
    space = tank_space(cfg)
    pool, _ = build_pool(cfg, seed)
    heads = (len(space.distances), space.turns_deg.index(0.0) if 0.0 in space.turns_deg else 0,
             space.fire_powers.index(power), 0, space.leads.index(lead))  # surf is the distance head's last entry
    ppo = None if prior is None else PPO(pool.n_features, pool.action_dims, cfg.ppo, seed=0,
                                         init_logits=skill_logits(space, prior))
    obs, rows = pool.reset(), []
    while len(rows) < rounds:
        if ppo is not None:
            action = ppo.act(obs)[0]
        else:
            action = np.ravel_multi_index(tuple(np.full(len(obs), h) for h in heads), space.dims)
        st = pool.step(action)
        rows += st.rounds
        obs = st.obs
    return share_by_opponent(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--entries", default=",".join([f"1v1:{t}" for t in TECH_ROBOTS] + ["4v4:SurfVG", "4v4:RiskGF"]))
    ap.add_argument("--power", type=float, default=2.0)
    ap.add_argument("--lead", default="gf")
    ap.add_argument("--rounds", type=int, default=1700)
    ap.add_argument("--battles", type=int, default=4)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--prior", type=float, help="play the untrained PPO policy with this tank.skill_prior instead")
    args = ap.parse_args()
    shares = play(args.entries.split(","), args.power, args.lead, args.rounds, args.battles, args.seed, args.prior)
    for e, v in shares.items():
        print(f"{e:22s} {v:.3f}")
    print(json.dumps({"bench": "skill_reference", "load": os.getloadavg()[0], "power": args.power,
                      "lead": args.lead, "prior": args.prior, "rounds": args.rounds, "shares": shares}))


if __name__ == "__main__":
    main()
