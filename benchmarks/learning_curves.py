"""Do our learners learn in the battle? Learning curves of several arms against the frozen TD team (4v4).

Arms (each trained, or just played, for ``--rounds`` rounds per seed in the same battles as ``confront train``):

- ``dmnn``: the ``awm`` experiment's DMNN (as configured, plus any ``--set`` overrides),
- ``random``: uniform random macro moves (same gun/radar controller),
- ``frozen``: the same DMNN at its initial weights, greedy, never learning,
- ``td``: a fresh copy of the TD team's own tabular learner (epsilon-greedy Q-learning) on our side,
- ``ssaq``: tabular SSAQ,
- ``mirror``: the trained TD team itself on our side, greedy (a symmetry check: about 0.5),
- ``dodge``: a hand-written stochastic policy, no learning: forward or backward at random while the target is
  to the side (relative-angle bins right/left), a random turn otherwise; ``dodge_det``: the same, deterministic
  (always forward / always clockwise). They show what a policy over the paper's state can reach.

Diagnostics: with ``--reward score`` the learners are trained on the change of the team's score margin (ours -
theirs, Robocode's score) per SMDP step instead of Eq. 35; with ``--reward approach`` on the distance each tank
closed to its target (px / 100), a signal the state determines (the last table then shows the mean distance to
the target, px, to see whether the learners learn to close in).

Prints the mean score ratio per block of rounds (sessions of 10 pooled into ``--blocks`` blocks) with a 95%
t-interval over seeds, and the first-vs-last block difference. Set ``CONFRONT_CACHE`` to a scratch folder.
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

ARMS = ("dmnn", "random", "frozen", "td", "ssaq", "mirror", "dodge", "dodge_det")


def dodge_policy(stochastic: bool, n_actions: int):  # noqa: ANN201 - a Learner built on the uniform policy
    """Hand-written reference: move perpendicular to the line to the target (paper's discrete state)."""
    from confront.learning.uniform import UniformParams, UniformPolicy

    class Dodge(UniformPolicy):
        def act(self, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
            rel = np.asarray(obs) // 80  # state = (rel_bin * 4 + heading_bin) * 20 + dist_bin
            side = (rel == 1) | (rel == 3)
            if stochastic:
                return np.where(side, rng.integers(0, 2, rel.shape), rng.integers(2, 4, rel.shape)).astype(np.int64)
            return np.where(side, 0, 2).astype(np.int64)

    return Dodge(UniformParams(n_actions=n_actions), kind="random")


def parse_value(text: str) -> object:
    """A learner parameter value from the command line: bool, int, float or string."""
    if text in ("true", "false"):
        return text == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def run_arm(arm: str, seed: int, rounds: int, overrides: tuple[str, ...],
            learner_params: tuple[tuple[str, object], ...] = (), reward: str = "eq35") -> np.ndarray:
    """(3, rounds // 10): per session of one arm at one seed, the score ratio, our tanks' mean Eq. 35 reward per
    SMDP step and their mean distance to the target (px); ``learner_params`` rebuild the DMNN; ``reward`` is what
    the learners are trained on (module docstring)."""
    from confront.learning.factory import clone_learner, make_learner
    from confront.learning.transfer import Frozen
    from confront.train.league import td_learner
    from confront.train.loop import run_rounds, session_rows
    from confront.train.paper_sim import SMDPTrainer
    from confront.train.spec import load_experiment

    sets = [f"train.seed={seed}", f"train.rounds={rounds}", "train.replay=false", *overrides]
    if arm == "ssaq":
        sets.append("learner.kind=ssaq")
    cfg = load_experiment("awm", sets)
    trainer = SMDPTrainer.from_config(cfg)
    loop = trainer.loop
    n_actions = loop.env.n_actions
    if learner_params and arm in ("dmnn", "frozen"):
        lr = loop.side.learner
        loop.side.learner = make_learner(lr.kind, **{**lr.params.to_dict(), **dict(learner_params)})
    if arm == "random":
        loop.side.learner = make_learner("random", n_actions=n_actions)
    elif arm == "frozen":
        loop.learning = False
    elif arm == "td":
        loop.side.learner = td_learner(cfg, n_actions)
    elif arm in ("dodge", "dodge_det"):
        loop.side.learner = dodge_policy(arm == "dodge", n_actions)
    elif arm == "mirror":
        assert loop.side.opponent is not None
        opp = loop.side.opponent
        loop.side.learner = Frozen(clone_learner(opp.inner if isinstance(opp, Frozen) else opp))
        loop.learning = False
    reward_kind = reward
    sessions = rounds // 10
    reward = np.zeros((3, sessions))  # per session of rounds: summed Eq. 35 reward, tank-steps, summed distance
    diag = loop.env.max_distance
    env_step = loop.env.step
    team = loop.side.ours
    last = np.zeros(loop.env.n_battles)  # (our team's score - theirs) so far in each battle's round

    def step(actions: np.ndarray):  # noqa: ANN202 - records our tanks' rewards per session, then steps
        res = env_step(actions)
        ours = res.active & team[None, :]
        k = min(loop.rounds_done // 10, sessions - 1)
        reward[0, k] += res.rewards.sum(axis=2)[ours].sum()
        reward[1, k] += ours.sum()
        before = loop.feats[..., 4] * diag  # feature 4: distance to the target / max_distance (before the step)
        after = (np.where(res.round_done[:, None], res.final_features[..., 4], res.features[..., 4])
                 if res.final_features is not None else res.features[..., 4]) * diag
        reward[2, k] += before[ours].sum()
        if reward_kind == "approach":
            res.rewards = np.repeat(((before - after) / 100.0 / res.rewards.shape[2])[..., None],
                                    res.rewards.shape[2], axis=2)
        margin = res.info["score"].sum(axis=2)
        margin = margin[:, team].sum(axis=1) - margin[:, ~team].sum(axis=1)
        if reward_kind == "score":  # every tank of ours gets the change of the team's score margin, spread over T
            gain = (margin - last)[:, None, None] / res.rewards.shape[2]
            res.rewards = np.broadcast_to(gain, res.rewards.shape).copy()
        last[:] = np.where(res.round_done, 0.0, margin)
        return res

    loop.env.step = step  # type: ignore[method-assign]
    run_rounds(trainer, rounds, progress=False, desc=arm)
    ratio = np.array([s["score_ratio"] for s in session_rows(loop.rows[:rounds], 10)])
    return np.stack([ratio, reward[0] / np.maximum(reward[1], 1), reward[2] / np.maximum(reward[1], 1)])


def interval(values: np.ndarray) -> tuple[float, float, float]:
    """Mean and 95% t-interval over seeds."""
    m = float(values.mean())
    if len(values) < 2:
        return m, m, m
    h = float(stats.t.ppf(0.975, len(values) - 1) * values.std(ddof=1) / np.sqrt(len(values)))
    return m, m - h, m + h


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--arms", default=",".join(ARMS), help="comma-separated subset of " + ", ".join(ARMS))
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--rounds", type=int, default=500)
    ap.add_argument("--blocks", type=int, default=5, help="blocks of rounds in the table")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--reward", choices=("eq35", "score", "approach"), default="eq35",
                    help="what the learners are trained on")
    ap.add_argument("--set", dest="sets", action="append", default=[], help="config override for every arm")
    ap.add_argument("--learner", action="append", default=[],
                    help="KEY=VALUE: a DMNN parameter beyond the config (e.g. rate_units=network)")
    args = ap.parse_args()
    arms = [a for a in args.arms.split(",") if a]
    for a in arms:
        if a not in ARMS:
            raise SystemExit(f"unknown arm {a!r}: use {', '.join(ARMS)}")
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    extra = tuple((k, parse_value(v)) for k, _, v in (t.partition("=") for t in args.learner))
    jobs = [(a, s) for a in arms for s in seeds]
    t0 = time.time()
    with ProcessPoolExecutor(args.workers) as pool:
        futs = {job: pool.submit(run_arm, job[0], job[1], args.rounds, tuple(args.sets), extra,
                                  args.reward) for job in jobs}
        curves = {job: f.result() for job, f in futs.items()}
    n_sess = args.rounds // 10
    edges = np.linspace(0, n_sess, args.blocks + 1).astype(int)
    heads = [f"rounds {10 * lo + 1}-{10 * hi}" for lo, hi in zip(edges[:-1], edges[1:], strict=True)]
    print(f"\n{len(list(seeds))} seeds x {args.rounds} rounds, overrides {args.sets + args.learner or 'none'}, "
          f"trained on {args.reward}, "
          f"{time.time() - t0:.0f} s; mean [95% t-interval over seeds]")
    for row, what in ((0, "score ratio"), (1, "mean Eq. 35 reward per tank and SMDP step"),
                      (2, "mean distance to the target, px")):
        print(f"\n{what}\n")
        table(arms, seeds, curves, row, edges, heads)


def table(arms: list[str], seeds: range, curves: dict, row: int, edges: np.ndarray, heads: list[str]) -> None:
    """One markdown table: arms x blocks of rounds, mean [95% t-interval over seeds]."""
    print("| arm | " + " | ".join(heads) + " | last - first block |")
    print("|---|" + "---|" * (len(heads) + 1))
    for a in arms:
        per_seed = np.stack([curves[(a, s)][row] for s in seeds])  # (S, sessions)
        blocks = np.stack([per_seed[:, lo:hi].mean(axis=1) for lo, hi in zip(edges[:-1], edges[1:], strict=True)],
                          axis=1)
        cells = ["{:.3f} [{:.3f}, {:.3f}]".format(*interval(blocks[:, k])) for k in range(blocks.shape[1])]
        diff = "{:+.3f} [{:+.3f}, {:+.3f}]".format(*interval(blocks[:, -1] - blocks[:, 0]))
        print(f"| {a} | " + " | ".join(cells) + f" | {diff} |")


if __name__ == "__main__":
    main()
