"""How fast does the DMNN learn from noisy rewards? A contextual bandit at roughly the battle's signal to noise.

7 features uniform in [-1, 1], 4 actions, Q*(x, a) = 3 tanh(x W)_a, reward = Q* + N(0, 5^2), batches of 32 random
actions, no bootstrap. Prints, after each fifth of the updates, the RMSE of Q and the share of states whose
greedy action is Q*'s, for the DMNN with AWM (both rate units) and without AWM.
No assertions.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from confront.learning import Transition, make_learner  # noqa: E402


def run(updates: int, noise: float, seed: int, **params: object) -> list[tuple[float, float]]:
    """(RMSE of Q, greedy agreement) after each fifth of ``updates``."""
    rng = np.random.default_rng(seed)
    net = make_learner("dmnn", rng=np.random.default_rng(seed + 1), n_inputs=7, n_actions=4, hidden=(16,),
                       **params)
    w = rng.normal(size=(7, 4))

    def q_star(x: np.ndarray) -> np.ndarray:
        return 3.0 * np.tanh(x @ w)

    out = []
    for i in range(updates):
        x = rng.uniform(-1, 1, (32, 7))
        a = rng.integers(0, 4, 32)
        r = q_star(x)[np.arange(32), a] + noise * rng.standard_normal(32)
        net.learn(Transition(x, a, r[:, None], x, np.ones(32, dtype=bool)))
        if (i + 1) % (updates // 5) == 0:
            xt = rng.uniform(-1, 1, (2000, 7))
            q = net.q_values(xt)
            out.append((float(np.sqrt(((q - q_star(xt)) ** 2).mean())),
                        float((q.argmax(1) == q_star(xt).argmax(1)).mean())))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--updates", type=int, default=3000)
    ap.add_argument("--noise", type=float, default=5.0)
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    arms = {
        "AWM (default: E in network units)": {},
        "AWM, rate_units=q": {"rate_units": "q"},
        "without AWM (nn_rate 0.9)": {"awm": False},
    }
    marks = [args.updates // 5 * k for k in range(1, 6)]
    print(f"\nmean over {args.seeds} seeds: RMSE of Q / greedy agreement with Q* (chance 0.25)\n")
    print("| DMNN 7-16-4, td_clip 5, q_scale 10 | " + " | ".join(f"{m} updates" for m in marks) + " |")
    print("|---|" + "---|" * len(marks))
    for name, params in arms.items():
        res = np.array([run(args.updates, args.noise, s, **params) for s in range(args.seeds)]).mean(axis=0)
        print(f"| {name} | " + " | ".join(f"{e:.2f} / {g:.2f}" for e, g in res) + " |")


if __name__ == "__main__":
    main()
