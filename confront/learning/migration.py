"""Robot migration on a binary tree (paper §6.2, Table 1, Figure 9) and the SSAQ / Greedy / Dgreedy comparison.

Nodes are numbered heap-style 1 .. 2^N - 1 (children of k: 2k, 2k+1). From the root the robot picks left (0)
or right (1) at each of the N - 1 branchings; entering node 2^N - 1 pays +1000, every other end 0. Q_k is the
value of entering node k, Q(k // 2, k % 2); on the rewarding path its limit is gamma^(N - layer(k)) * 1000.

Convergence of Q_k: the first episode after which |Q_k - Q_k*| <= tol * Q_k* for every remaining episode
(tol = 1%); runs that never converge within the horizon are reported as censored (NaN).
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np

from confront.learning.base import Transition, check_int, check_range
from confront.learning.factory import make_learner

__all__ = [
    "METHODS",
    "PAPER_SSAQ",
    "TRACKED",
    "BinaryTreeMigration",
    "MigrationResult",
    "convergence_episode",
    "convergence_table",
    "format_summary",
    "paper_claims",
    "q_limit",
    "plot_migration",
    "run_migration",
]

TRACKED = (3, 7, 15)
PAPER_SSAQ = {3: 214, 7: 168, 15: 122}  # §6.2: SSAQ's convergence episodes for Q_3, Q_7, Q_15
LABELS = {"ssaq": "SSAQ", "greedy": "Greedy-policy", "dgreedy": "Dgreedy-policy"}
# method -> (learner kind, its exploration); all use Table 1's alpha, gamma, epsilon, eta, T_max, T_min
METHODS = {"ssaq": "ssaq", "greedy": "qlearning_egreedy", "dgreedy": "qlearning_dgreedy"}


class BinaryTreeMigration(gymnasium.Env):
    """The migration map as a Gymnasium environment: observation = node index, actions = left/right."""

    def __init__(self, layers: int = 10, reward: float = 1000.0) -> None:
        check_int("layers", layers, 2, 30)
        self.layers = layers
        self.reward = float(reward)
        self.goal = 2**layers - 1
        self.first_leaf = 2 ** (layers - 1)
        self.observation_space = gymnasium.spaces.Discrete(2**layers)
        self.action_space = gymnasium.spaces.Discrete(2)
        self.node = 1

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[int, dict]:
        super().reset(seed=seed)
        self.node = 1
        return self.node, {}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict]:
        if action not in (0, 1):
            raise ValueError(f"bad value action={action!r}: must be 0 (left) or 1 (right)")
        if self.node >= self.first_leaf:
            raise ValueError("episode is over: call reset()")
        self.node = 2 * self.node + int(action)  # heap numbering: children of k are 2k and 2k + 1
        reward = self.reward if self.node == self.goal else 0.0
        return self.node, reward, self.node >= self.first_leaf, False, {}


def q_limit(node: int, layers: int, gamma: float, reward: float = 1000.0) -> float:
    """Limit of Q_node for a node on the rewarding path: gamma^(steps from node to the goal) * reward."""
    layer = int(node).bit_length()  # root is layer 1
    return reward * gamma ** (layers - layer)  # Q(k) = r + gamma max Q(child) down the path (Eq. 4)


def convergence_episode(values: np.ndarray, limit: float, tol: float = 0.01) -> float:
    """First episode (1-based) from which every value stays within ``tol * |limit|`` of ``limit``; NaN if none."""
    ok = np.abs(np.asarray(values) - limit) <= tol * abs(limit)
    if not ok[-1]:
        return float("nan")
    bad = np.flatnonzero(~ok)
    return float(bad[-1] + 2) if bad.size else 1.0


@dataclass
class MigrationResult:
    """Per-episode Q_3, Q_7, Q_15 per method and seed, their limits and convergence episodes."""

    q: dict[str, np.ndarray]  # method -> (seeds, episodes, 3)
    limits: np.ndarray  # (3,)
    convergence: dict[str, np.ndarray]  # method -> (seeds, 3), NaN = not converged
    first_goal: dict[str, np.ndarray]  # method -> (seeds,), first episode that reached the goal
    settings: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> dict[str, dict[str, dict[str, float]]]:
        """method -> "Q3"/"Q7"/"Q15" -> median, q25, q75 of the convergence episode, the same for the episodes
        from the first goal reached to convergence (``after_goal_*``), converged (count), seeds.

        Censored runs count as +inf, so a median stays honest when a few runs fail."""
        out: dict[str, dict[str, dict[str, float]]] = {}
        for m, conv in self.convergence.items():
            out[m] = {}
            for j, node in enumerate(TRACKED):
                c = conv[:, j]
                row = {"converged": float(np.isfinite(c).sum()), "seeds": float(c.size)}
                for prefix, vals in (("", c), ("after_goal_", c - self.first_goal[m] + 1)):
                    filled = np.where(np.isfinite(vals), vals, np.inf)
                    q25, med, q75 = np.quantile(filled, [0.25, 0.5, 0.75], method="lower")
                    row.update({f"{prefix}median": float(med), f"{prefix}q25": float(q25),
                                f"{prefix}q75": float(q75)})
                out[m][f"Q{node}"] = row
        return out


def _run_one(kind: str, seed: int, episodes: int, layers: int, params: dict[str, Any]
             ) -> tuple[np.ndarray, float]:
    """Q_3, Q_7, Q_15 after every episode, and the first episode that reached the goal (NaN if none)."""
    rng = np.random.default_rng(seed)
    env = BinaryTreeMigration(layers)
    learner = make_learner(kind, n_states=2**layers, n_actions=2, **params)
    steps = layers - 1
    out = np.empty((episodes, len(TRACKED)))
    rows = np.array([k // 2 for k in TRACKED])
    cols = np.array([k % 2 for k in TRACKED])
    obs = np.empty(steps, dtype=np.int64)
    act = np.empty(steps, dtype=np.int64)
    rew = np.empty((steps, 1))
    nxt = np.empty(steps, dtype=np.int64)
    done = np.zeros(steps, dtype=bool)
    done[-1] = True
    first_goal = float("nan")
    for e in range(episodes):
        s, _ = env.reset()
        for i in range(steps):
            a = int(learner.act(np.array([s]), rng)[0])
            s2, r, _, _, _ = env.step(a)
            obs[i], act[i], rew[i, 0], nxt[i] = s, a, r, s2
            s = s2
        # one learn call per episode: no state repeats within an episode, so this equals online updates
        learner.learn(Transition(obs, act, rew, nxt, done))
        out[e] = learner.q[rows, cols]  # type: ignore[attr-defined]
        if s == env.goal and first_goal != first_goal:
            first_goal = float(e + 1)
    return out, first_goal


def run_migration(
    methods: tuple[str, ...] = ("ssaq", "greedy", "dgreedy"),
    seeds: int = 30,
    episodes: int = 4000,
    layers: int = 10,
    alpha: float = 0.3,
    gamma: float = 0.9,
    exploit: float = 0.9,
    eta: float = 0.9,
    t_max: float = 0.1,
    t_min: float = 0.01,
    exploit_decay: float = 0.99,
    tol: float = 0.01,
    seed: int = 0,
    workers: int = 1,
) -> MigrationResult:
    """Run every method on ``seeds`` seeds (Table 1 defaults); seed i of every method uses the same stream.

    ``workers`` > 1 runs seeds in that many processes (results are identical)."""
    for m in methods:
        if m not in METHODS:
            raise ValueError(f"bad value method={m!r}: must be one of {', '.join(METHODS)}")
    check_int("seeds", seeds, 1)
    check_int("episodes", episodes, 1)
    check_range("tol", tol, 0.0, 1.0, lo_open=True)
    check_int("workers", workers, 1, 256)
    params = {"alpha": alpha, "gamma": gamma, "exploit": exploit, "eta": eta, "t_max": t_max, "t_min": t_min,
              "exploit_decay": exploit_decay}
    limits = np.array([q_limit(k, layers, gamma) for k in TRACKED])
    q: dict[str, np.ndarray] = {}
    conv: dict[str, np.ndarray] = {}
    first: dict[str, np.ndarray] = {}
    jobs = [(METHODS[m], seed + i, episodes, layers, params) for m in methods for i in range(seeds)]
    if workers > 1:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            done = list(pool.map(_run_one, *zip(*jobs, strict=True)))
    else:
        done = [_run_one(*job) for job in jobs]
    for k, m in enumerate(methods):
        chunk = done[k * seeds:(k + 1) * seeds]
        runs = np.stack([c[0] for c in chunk])
        first[m] = np.array([c[1] for c in chunk])
        q[m] = runs
        conv[m] = np.array([[convergence_episode(runs[i, :, j], limits[j], tol) for j in range(len(TRACKED))]
                            for i in range(seeds)])
    settings = {**params, "layers": layers, "episodes": episodes, "seeds": seeds, "tol": tol, "seed": seed}
    return MigrationResult(q=q, limits=limits, convergence=conv, first_goal=first, settings=settings)


def plot_migration(result: MigrationResult, path: str | Path, max_episode: int | None = None) -> list[Path]:
    """Figure 9: Q_3, Q_7, Q_15 per episode, median line and interquartile band over seeds per method.

    ``path`` is a ``.png`` file or a folder (then ``figure9_migration.png`` inside it); returns the files written.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(13, 3.8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(TRACKED))
    for j, (ax, node) in enumerate(zip(axes, TRACKED, strict=True)):
        for m, runs in result.q.items():
            vals = runs[:, :max_episode, j]
            x = np.arange(1, vals.shape[1] + 1)
            q25, med, q75 = np.quantile(vals, [0.25, 0.5, 0.75], axis=0)
            (line,) = ax.plot(x, med, label=LABELS.get(m, m), lw=1.2)
            ax.fill_between(x, q25, q75, color=line.get_color(), alpha=0.2, lw=0)
        ax.axhline(result.limits[j], color="k", ls="--", lw=0.8, label="limit")
        ax.set(title=f"({'abc'[j]}) Q_{node}", xlabel="episode", ylabel=f"Q_{node}")
        ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    out = Path(path)
    if out.suffix.lower() != ".png":
        out = out / "figure9_migration.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    return [out]


def _cell(r: dict[str, float], prefix: str = "") -> str:
    return f"{r[prefix + 'median']:.0f} [{r[prefix + 'q25']:.0f}, {r[prefix + 'q75']:.0f}]"


def convergence_table(result: MigrationResult) -> str:
    """Markdown table: median [IQR] convergence episode per method and Q, the paper's SSAQ row first."""
    head = "| method | " + " | ".join(f"Q_{k}" for k in TRACKED) + " | converged runs | Q_3 after first goal |"
    lines = [head, "|" + "---|" * (len(TRACKED) + 3),
             "| paper, SSAQ | " + " | ".join(str(PAPER_SSAQ[k]) for k in TRACKED) + " | - | - |"]
    for m, rows in result.summary().items():
        cells = [_cell(rows[f"Q{k}"]) for k in TRACKED]
        conv = min(int(rows[f"Q{k}"]["converged"]) for k in TRACKED)
        seeds = int(rows[f"Q{TRACKED[0]}"]["seeds"])
        lines.append(f"| {LABELS.get(m, m)} | " + " | ".join(cells)
                     + f" | {conv}/{seeds} | {_cell(rows[f'Q{TRACKED[0]}'], 'after_goal_')} |")
    return "\n".join(lines)


def paper_claims(result: MigrationResult) -> list[dict[str, Any]]:
    """The paper's Figure 9 claims checked on ``result``: text, ours (str), holds (bool or None), detail."""
    s = result.summary()
    claims: list[dict[str, Any]] = []
    if "ssaq" in s:
        med = {k: s["ssaq"][f"Q{k}"]["median"] for k in TRACKED}
        ours = ", ".join(f"Q_{k} {med[k]:.0f}" for k in TRACKED)
        claims.append({
            "text": "SSAQ converges in 214, 168 and 122 episodes for Q_3, Q_7, Q_15",
            "ours": f"median {ours}",
            "holds": bool(all(abs(med[k] - PAPER_SSAQ[k]) <= 0.25 * PAPER_SSAQ[k] for k in TRACKED)),
            "detail": "holds if every median is within 25% of the paper's episode count",
        })
        claims.append({
            "text": "Q_15 converges first, then Q_7, then Q_3",
            "ours": ours,
            "holds": bool(np.isfinite(med[3]) and med[15] <= med[7] <= med[3]),
        })
        others = [m for m in s if m != "ssaq"]
        if others:
            worse = [f"{LABELS.get(m, m)} Q_{k} {s[m][f'Q{k}']['median']:.0f}" for m in others for k in TRACKED]
            claims.append({
                "text": "SSAQ converges faster than the Greedy and Dgreedy policies",
                "ours": f"SSAQ {ours}; " + ", ".join(worse),
                "holds": bool(all(med[k] < s[m][f"Q{k}"]["median"] for m in others for k in TRACKED)),
                "detail": "compared by the median convergence episode over seeds",
            })
    return claims


def format_summary(result: MigrationResult) -> str:
    """A plain-text table of the convergence episodes (median [q25, q75]) per method and Q."""
    lines = [f"{'method':<9} {'Q':<4} {'converged':>9} {'episode median [IQR]':>24} {'after first goal [IQR]':>24}"]
    for m, rows in result.summary().items():
        for name, r in rows.items():
            a = f"{r['median']:.0f} [{r['q25']:.0f}, {r['q75']:.0f}]"
            b = f"{r['after_goal_median']:.0f} [{r['after_goal_q25']:.0f}, {r['after_goal_q75']:.0f}]"
            lines.append(f"{m:<9} {name:<4} {r['converged']:>4.0f}/{r['seeds']:<4.0f} {a:>24} {b:>24}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    """``python -m confront.learning.migration``: run the comparison, print the table, draw Figure 9."""
    import argparse

    ap = argparse.ArgumentParser(description=main.__doc__)
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--episodes", type=int, default=4000)
    ap.add_argument("--layers", type=int, default=10)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--plot", default="figure9.png")
    args = ap.parse_args(argv)
    res = run_migration(seeds=args.seeds, episodes=args.episodes, layers=args.layers, workers=args.workers)
    print(format_summary(res))
    print(f"limits Q3, Q7, Q15: {', '.join(f'{x:.2f}' for x in res.limits)}")
    print(convergence_table(res))
    print(f"plot: {plot_migration(res, args.plot)[0]}")


if __name__ == "__main__":
    main()
