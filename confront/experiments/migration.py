"""Robot migration on a binary tree (paper §6.2, Table 1, Figure 9) and the SSAQ / Greedy / Dgreedy comparison.

Nodes are numbered heap-style 1 .. 2^N - 1 (children of k: 2k, 2k+1). From the root the robot picks left (0)
or right (1) at each of the N - 1 branchings; entering node 2^N - 1 pays +1000, every other end 0. Q_k is the
value of entering node k, Q(k // 2, k % 2); on the rewarding path its limit is gamma^(N - layer(k)) * 1000.

Convergence of Q_k: the first episode after which |Q_k - Q_k*| <= tol * Q_k* for every remaining episode
(tol = 1%); runs that never converge within the horizon are reported as censored (NaN).

Common random numbers: seed i owns one stream of uniforms, one per move (``default_rng(seed + i)``), and every
method reads the same stream: move j of episode e goes right when u[e, j] >= pi(left | node), the inverse CDF
of that method's policy. Methods compared on seed i therefore differ only by their policies, and all of them
walk the same path until the first reward (while Q = 0 every policy is 50/50). Seeds run side by side as
arrays; each method updates its tables exactly as :class:`~confront.learning.tabular.TabularQ` does.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
from numba import njit

from confront.learning.base import check_int, check_range
from confront.learning.factory import make_learner
from confront.learning.tabular import TabularParams
from confront.stats import median_ci, sign_test

__all__ = [
    "METHODS",
    "PAIRS",
    "PAPER_SSAQ",
    "TRACKED",
    "BinaryTreeMigration",
    "MigrationResult",
    "convergence_episode",
    "convergence_table",
    "format_summary",
    "paired_rows",
    "paired_table",
    "paper_claims",
    "plot_migration",
    "q_limit",
    "run_migration",
    "seed_draws",
]

TRACKED = (3, 7, 15)
PAPER_SSAQ = {3: 214, 7: 168, 15: 122}  # §6.2: SSAQ's convergence episodes for Q_3, Q_7, Q_15
LABELS = {"ssaq": "SSAQ", "greedy": "Greedy-policy", "dgreedy": "Dgreedy-policy"}
# method -> (learner kind, its exploration); all use Table 1's alpha, gamma, epsilon, eta, T_max, T_min
METHODS = {"ssaq": "ssaq", "greedy": "qlearning_egreedy", "dgreedy": "qlearning_dgreedy"}
# pairs compared seed by seed, and the direction the paper claims ("less": the first converges earlier)
PAIRS = (("ssaq", "greedy", "less"), ("ssaq", "dgreedy", "less"), ("greedy", "dgreedy", "two-sided"))
LEVEL_TOL = 0.25  # a convergence episode "matches" the paper's within +-25%
GAP_TOL = 0.5  # the paper's gaps between Q_15, Q_7 and Q_3 (46 episodes each) matched within +-50%
ALPHA = 0.05


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


def seed_draws(seed: int, seeds: int, episodes: int, moves: int, chunk: int = 250) -> Iterator[np.ndarray]:
    """Uniforms in chunks ``(seeds, n, moves)`` of at most ``chunk`` episodes; seed i's come from
    ``default_rng(seed + i)`` in episode order, so they do not depend on the other seeds or on the method."""
    gens = [np.random.default_rng(seed + i) for i in range(seeds)]
    for start in range(0, episodes, chunk):
        n = min(chunk, episodes - start)
        yield np.stack([g.random((n, moves)) for g in gens])


@dataclass
class MigrationResult:
    """Convergence episodes per method and seed (NaN = not converged), first goal, final Q_3/Q_7/Q_15, the
    per-episode quartiles of Q_3/Q_7/Q_15 over seeds, and (``keep_runs``) every seed's trajectory."""

    limits: np.ndarray  # (3,)
    convergence: dict[str, np.ndarray]  # method -> (seeds, 3)
    first_goal: dict[str, np.ndarray]  # method -> (seeds,), first episode that reached the goal
    final_q: dict[str, np.ndarray]  # method -> (seeds, 3)
    bands: dict[str, np.ndarray] = field(default_factory=dict)  # method -> (3 quartiles, episodes, 3)
    q: dict[str, np.ndarray] | None = None  # method -> (seeds, episodes, 3) when kept
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def seeds(self) -> int:
        return int(next(iter(self.convergence.values())).shape[0])

    def subset(self, idx: np.ndarray | slice) -> MigrationResult:
        """The same runs restricted to some seeds (quartile bands dropped: they pool all seeds)."""
        def pick(d: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
            return {m: v[idx] for m, v in d.items()}

        sub = replace(self, convergence=pick(self.convergence), first_goal=pick(self.first_goal),
                      final_q=pick(self.final_q), bands={}, q=pick(self.q) if self.q is not None else None)
        sub.settings = {**self.settings, "seeds": sub.seeds}
        return sub

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

    def censored(self, method: str) -> np.ndarray:
        """Convergence episodes with runs that never converged as +inf (later than any episode), ``(seeds, 3)``."""
        c = self.convergence[method]
        return np.where(np.isnan(c), np.inf, c)


def _method_params(kind: str, layers: int, params: dict[str, Any]) -> TabularParams:
    p = make_learner(kind, n_states=2**layers, n_actions=2, **params).params
    assert isinstance(p, TabularParams)
    if p.rate != "fixed":
        raise ValueError(f"migration runs tabular learners at a fixed rate, got rate={p.rate!r}")
    # one reward per move (T = 1): the paper's Eq. 10 and the textbook backup are both r + gamma V(s')
    return p


EXPLORE_CODES = {"boltzmann": 0, "egreedy": 1, "degreedy": 2}


@njit(cache=True, error_model="numpy")
def _left_prob(q0: float, q1: float, code: int, temp: float, thr: float) -> tuple[float, float]:
    """pi(left), pi(right) at one node, as :func:`~confront.learning.exploration.policy_probs` computes them."""
    if code == 0:
        z0, z1 = q0 / temp, q1 / temp
        m = max(z0, z1)
        e0, e1 = np.exp(z0 - m), np.exp(z1 - m)  # Eq. 6, shifted by the max
        return e0 / (e0 + e1), e1 / (e0 + e1)
    b0 = 1.0 if q0 >= q1 else 0.0  # greedy actions, ties share the greedy mass
    b1 = 1.0 if q1 >= q0 else 0.0
    return thr * b0 / (b0 + b1) + (1.0 - thr) / 2.0, thr * b1 / (b0 + b1) + (1.0 - thr) / 2.0


@njit(cache=True, error_model="numpy")
def _run_chunk(q: np.ndarray, u: np.ndarray, e0: int, code: int, expected: bool, alpha: float, gamma: float,
               t_max: float, t_min: float, eta: float, exploit: float, decay: float, goal: int, reward: float,
               rows: np.ndarray, cols: np.ndarray, limits: np.ndarray, tol: float, first: np.ndarray,
               last_bad: np.ndarray, ok: np.ndarray, bands: np.ndarray, order: np.ndarray, runs: np.ndarray,
               keep: bool) -> None:
    """Episodes e0 .. e0 + u.shape[1] - 1 of every seed of one method; ``q`` ``(S, 2^(N-1), 2)``, the
    trackers and ``order`` (per tracked Q, the seeds ranked by value) are updated in place."""
    seeds, n, moves = u.shape
    path = np.empty(moves + 1, np.int64)
    acts = np.empty(moves, np.int64)
    target = np.empty(moves)
    vals = np.empty((n, rows.size, seeds))
    for s in range(seeds):  # one seed's episodes in a row: its table stays in cache
        for k in range(n):
            e = e0 + k
            temp = t_min + (t_max - t_min) * eta**e  # Eq. 7 iterated from T_0 = T_max, once per episode
            thr = 1.0 - (1.0 - exploit) * decay**e if code == 2 else exploit  # Dgreedy: 1 - eps_e = (1 - eps_0) d^e
            path[0] = 1
            for i in range(moves):
                p0, _ = _left_prob(q[s, path[i], 0], q[s, path[i], 1], code, temp, thr)
                acts[i] = 1 if u[s, k, i] >= p0 else 0  # inverse CDF: the same u moves every method
                path[i + 1] = 2 * path[i] + acts[i]
            leaf = path[moves]
            # targets from the table before the episode: no (s, a) repeats, so this equals online updates
            for i in range(moves):
                if i == moves - 1:
                    target[i] = reward if leaf == goal else 0.0  # terminal: nothing bootstrapped
                else:
                    q0, q1 = q[s, path[i + 1], 0], q[s, path[i + 1], 1]
                    if expected:
                        p0, p1 = _left_prob(q0, q1, code, temp, thr)
                        v = p0 * q0 + p1 * q1  # Eq. 9: sum_a pi(a|s') Q(s', a)
                    else:
                        v = max(q0, q1)  # Eq. 4: max_a Q(s', a)
                    target[i] = gamma * v  # r = 0 off the goal
            for i in range(moves):
                q[s, path[i], acts[i]] += alpha * (target[i] - q[s, path[i], acts[i]])  # Q += alpha (target - Q)
            if leaf == goal and np.isnan(first[s]):
                first[s] = e + 1
            for j in range(rows.size):
                x = q[s, rows[j], cols[j]]
                vals[k, j, s] = x
                ok[s, j] = abs(x - limits[j]) <= tol * abs(limits[j])
                if not ok[s, j]:
                    last_bad[s, j] = e
                if keep:
                    runs[s, e, j] = x
    for k in range(n):  # quartiles over seeds per episode, linear interpolation as np.quantile
        for j in range(rows.size):
            o, x = order[j], vals[k, j]  # last episode's ranking: values move little, so insertion sort is ~linear
            for i in range(1, seeds):
                key = o[i]
                p = i - 1
                while p >= 0 and x[o[p]] > x[key]:
                    o[p + 1] = o[p]
                    p -= 1
                o[p + 1] = key
            for t, level in enumerate((0.25, 0.5, 0.75)):
                pos = level * (seeds - 1)
                lo = int(np.floor(pos))
                hi = min(lo + 1, seeds - 1)
                bands[t, e0 + k, j] = x[o[lo]] + (x[o[hi]] - x[o[lo]]) * (pos - lo)


def run_migration(
    methods: tuple[str, ...] = ("ssaq", "greedy", "dgreedy"),
    seeds: int = 1000,
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
    keep_runs: bool = False,
) -> MigrationResult:
    """Run every method on seeds ``seed .. seed + seeds - 1`` (Table 1 defaults), all seeds side by side;
    every method reads seed i's uniforms (common random numbers). ``keep_runs`` keeps every trajectory."""
    for m in methods:
        if m not in METHODS:
            raise ValueError(f"bad value method={m!r}: must be one of {', '.join(METHODS)}")
    check_int("seeds", seeds, 1)
    check_int("episodes", episodes, 1)
    check_int("layers", layers, 4, 20)
    check_range("tol", tol, 0.0, 1.0, lo_open=True)
    params = {"alpha": alpha, "gamma": gamma, "exploit": exploit, "eta": eta, "t_max": t_max, "t_min": t_min,
              "exploit_decay": exploit_decay}
    learners = {m: _method_params(METHODS[m], layers, params) for m in methods}
    limits = np.array([q_limit(k, layers, gamma) for k in TRACKED])
    rows = np.array([k // 2 for k in TRACKED])
    cols = np.array([k % 2 for k in TRACKED])
    goal, moves = 2**layers - 1, layers - 1
    tables = {m: np.full((seeds, 2 ** (layers - 1), 2), p.q_init) for m, p in learners.items()}
    last_bad = {m: np.full((seeds, len(TRACKED)), -1, dtype=np.int64) for m in methods}
    ok = {m: np.zeros((seeds, len(TRACKED)), bool) for m in methods}
    first = {m: np.full(seeds, np.nan) for m in methods}
    bands = {m: np.empty((3, episodes, len(TRACKED))) for m in methods}
    order = {m: np.tile(np.arange(seeds), (len(TRACKED), 1)) for m in methods}
    runs = {m: np.empty((seeds, episodes, len(TRACKED)) if keep_runs else (1, 1, 1)) for m in methods}
    e0 = 0
    for u in seed_draws(seed, seeds, episodes, moves):
        for m, p in learners.items():
            _run_chunk(tables[m], u, e0, EXPLORE_CODES[p.exploration], p.bootstrap == "expected", p.alpha,
                       p.gamma, p.t_max, p.t_min, p.eta, p.exploit, p.exploit_decay, goal, 1000.0, rows, cols,
                       limits, tol, first[m], last_bad[m], ok[m], bands[m], order[m], runs[m], keep_runs)
        e0 += u.shape[1]
    conv = {m: np.where(ok[m], last_bad[m] + 2.0, np.nan) for m in methods}  # 1-based episode after the last miss
    final = {m: tables[m][:, rows, cols].copy() for m in methods}
    settings = {**params, "layers": layers, "episodes": episodes, "seeds": seeds, "tol": tol, "seed": seed,
                "draws": "common random numbers: one uniform per move per seed, shared by every method"}
    return MigrationResult(limits=limits, convergence=conv, first_goal=first, final_q=final, bands=bands,
                           q=runs if keep_runs else None, settings=settings)


# -- statistics: paired over seeds -------------------------------------------------------------------------------

def _pct(x: float) -> str:
    return f"{100 * x:.1f}%"


def paired_rows(result: MigrationResult) -> list[dict[str, Any]]:
    """Per pair of methods and Q: a sign test of "a converges earlier than b" on the same seeds, the median
    paired difference b - a (episodes) with its 95% interval, and the detectable share at power 0.8."""
    out = []
    for a, b, alternative in PAIRS:
        if a not in result.convergence or b not in result.convergence:
            continue
        ca, cb = result.censored(a), result.censored(b)
        for j, node in enumerate(TRACKED):
            st = sign_test(ca[:, j], cb[:, j], alternative=alternative)
            with np.errstate(invalid="ignore"):
                d = cb[:, j] - ca[:, j]  # both censored: NaN, dropped
            out.append({"a": a, "b": b, "node": node, "alternative": alternative, "sign": st,
                        "diff": median_ci(d)})
    return out


def paired_table(result: MigrationResult) -> str:
    """Markdown: the paired comparisons of :func:`paired_rows`, one row per pair and Q."""
    lines = [f"Paired over {result.seeds} seeds (common random numbers). Sign test on the convergence episode, ties "
             "dropped; one-sided where the paper claims a direction (SSAQ earlier), two-sided otherwise. "
             "'Detectable' is the share of untied seeds where A is earlier that the test finds with power 0.8.", "",
             "| A vs B | Q | A earlier / equal / later | B - A, median [95% CI] (episodes) | A earlier among untied "
             "[95% CI] | p | detectable |", "|---|---|---|---|---|---:|---:|"]
    for r in paired_rows(result):
        st, d = r["sign"], r["diff"]
        n = st.n
        lines.append(f"| {LABELS[r['a']]} vs {LABELS[r['b']]} | Q_{r['node']} | {_pct(st.less / n)} / "
                     f"{_pct(st.equal / n)} / {_pct(st.greater / n)} | {d.mean:.0f} [{d.lo:.0f}, {d.hi:.0f}] | "
                     f"{_pct(st.share.mean)} [{_pct(st.share.lo)}, {_pct(st.share.hi)}] | {st.p:.2g} | "
                     f"{_pct(st.mde)} |")
    return "\n".join(lines)


def _level_claim(result: MigrationResult) -> dict[str, Any]:
    c = result.censored("ssaq")
    cells, effects, ps, mdes, inside = [], [], [], [], []
    for j, node in enumerate(TRACKED):
        paper = PAPER_SSAQ[node]
        med = median_ci(c[:, j])
        st = sign_test(np.full(c.shape[0], float(paper)), c[:, j], alternative="two-sided")
        lo, hi = (1 - LEVEL_TOL) * paper, (1 + LEVEL_TOL) * paper
        inside.append(lo <= med.lo and med.hi <= hi)
        cells.append(f"Q_{node} {med.mean:.0f} [{med.lo:.0f}, {med.hi:.0f}]")
        effects.append(f"Q_{node} {med.mean - paper:+.0f} [{med.lo - paper:+.0f}, {med.hi - paper:+.0f}]")
        ps.append(st.p)
        mdes.append(st.mde)
    verdict = "holds" if all(inside) else "partly" if any(inside) else "no"
    return {
        "text": "SSAQ converges in 214, 168 and 122 episodes for Q_3, Q_7, Q_15",
        "ours": f"SSAQ median [95% CI]: {', '.join(cells)} ({c.shape[0]} seeds)",
        "effect": "median - paper (episodes): " + ", ".join(effects),
        "p": f"{max(ps):.2g} (sign test: median = paper's count, largest over Q)",
        "mde": f"{_pct(max(mdes))} of seeds beyond the paper's count (vs 50%)",
        "verdict": verdict,
        "criterion": f"holds if every Q's median with its 95% CI lies within the paper's count +-{LEVEL_TOL:.0%}; "
                     "partly if some Q's does; no if none",
    }


def _order_claim(result: MigrationResult) -> dict[str, Any]:
    c = result.censored("ssaq")
    gaps = [(3, 7), (7, 15)]
    idx = {k: j for j, k in enumerate(TRACKED)}
    paper_gap = {(hi, lo): PAPER_SSAQ[hi] - PAPER_SSAQ[lo] for hi, lo in gaps}
    cells, effects, ps, mdes, size_ok = [], [], [], [], []
    for hi, lo in gaps:
        st = sign_test(c[:, idx[lo]], c[:, idx[hi]], alternative="less")  # Q_lo converges before Q_hi
        with np.errstate(invalid="ignore"):
            gap = median_ci(c[:, idx[hi]] - c[:, idx[lo]])
        pg = paper_gap[(hi, lo)]
        size_ok.append(gap.hi >= (1 - GAP_TOL) * pg and gap.lo <= (1 + GAP_TOL) * pg)
        cells.append(f"Q_{lo} before Q_{hi} on {_pct(st.less / st.n)} of seeds (same {_pct(st.equal / st.n)})")
        effects.append(f"Q_{hi} - Q_{lo} {gap.mean:.0f} [{gap.lo:.0f}, {gap.hi:.0f}] episodes (paper {pg})")
        ps.append(st.p)
        mdes.append(st.mde)
    order = all(p < ALPHA for p in ps)
    verdict = ("holds" if all(size_ok) else "partly") if order else "no"
    strict = float(np.mean((c[:, idx[15]] < c[:, idx[7]]) & (c[:, idx[7]] < c[:, idx[3]])))
    return {
        "text": "Q_15 converges first, then Q_7, then Q_3",
        "ours": f"SSAQ: {'; '.join(cells)}; strict order on {_pct(strict)} of seeds",
        "effect": "median gap [95% CI]: " + "; ".join(effects),
        "p": f"{max(ps):.2g} (sign test, one-sided, largest over the two gaps)",
        "mde": f"{_pct(max(mdes))} of untied seeds in order",
        "verdict": verdict,
        "criterion": f"holds if both orders are significant (p < {ALPHA}) and each median gap's 95% CI reaches the "
                     f"paper's 46 episodes +-{GAP_TOL:.0%}; partly if the order is significant but the gaps are "
                     "not that size (here they are structural: values climb one layer per backup); no otherwise",
    }


def _faster_claim(result: MigrationResult) -> dict[str, Any]:
    rows = [r for r in paired_rows(result) if r["a"] == "ssaq"]
    others = list(dict.fromkeys(r["b"] for r in rows))
    wins, effects, ps, mdes, ours = [], [], [], [], []
    for b in others:
        rb = [r for r in rows if r["b"] == b]
        worst = max(r["sign"].p for r in rb)
        wins.append(worst < ALPHA)
        q3 = next(r for r in rb if r["node"] == TRACKED[0])
        st, d = q3["sign"], q3["diff"]
        ours.append(f"vs {LABELS[b]} (Q_3): SSAQ earlier on {_pct(st.less / st.n)}, equal {_pct(st.equal / st.n)}, "
                    f"later {_pct(st.greater / st.n)} of seeds")
        effects.append(f"vs {LABELS[b]}: earlier among untied {_pct(st.share.mean)} [{_pct(st.share.lo)}, "
                       f"{_pct(st.share.hi)}], {LABELS[b]} - SSAQ median {d.mean:.0f} [{d.lo:.0f}, {d.hi:.0f}] "
                       "episodes")
        ps.append(f"{LABELS[b]} {worst:.2g}")
        mdes.append(f"{LABELS[b]} {_pct(max(r['sign'].mde for r in rb))}")
    verdict = "holds" if all(wins) else "partly" if any(wins) else "no"
    return {
        "text": "SSAQ converges faster than the Greedy and Dgreedy policies",
        "ours": "; ".join(ours) + f" ({result.seeds} seeds, common random numbers)",
        "effect": "; ".join(effects),
        "p": "; ".join(ps) + " (sign test, one-sided, largest over Q)",
        "mde": "earlier among untied seeds: " + "; ".join(mdes),
        "verdict": verdict,
        "criterion": f"holds if SSAQ converges earlier than each policy on significantly more seeds than later "
                     f"(paired sign test, p < {ALPHA} at every Q); partly if against one of them; no if neither",
    }


def paper_claims(result: MigrationResult) -> list[dict[str, Any]]:
    """The paper's Figure 9 claims tested on ``result`` with paired statistics: text, ours, effect, p, mde,
    verdict (holds / partly / no) and the criterion that decided it."""
    claims: list[dict[str, Any]] = []
    if "ssaq" in result.convergence:
        claims.append(_level_claim(result))
        claims.append(_order_claim(result))
        if any(b in result.convergence for b in ("greedy", "dgreedy")):
            claims.append(_faster_claim(result))
    return claims


# -- figure and tables --------------------------------------------------------------------------------------------

def plot_migration(result: MigrationResult, path: str | Path, max_episode: int | None = None) -> list[Path]:
    """Figure 9: Q_3, Q_7, Q_15 per episode, median line and interquartile band over seeds per method.

    ``path`` is a ``.png`` file or a folder (then ``figure9_migration.png`` inside it); returns the files written.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if not result.bands:
        raise ValueError("this result has no quartile bands (a subset of seeds): plot the full run")
    fig = Figure(figsize=(13, 3.8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(TRACKED))
    for j, (ax, node) in enumerate(zip(axes, TRACKED, strict=True)):
        for m, band in result.bands.items():
            q25, med, q75 = band[:, :max_episode, j]
            x = np.arange(1, med.size + 1)
            (line,) = ax.plot(x, med, label=LABELS.get(m, m), lw=1.2)
            ax.fill_between(x, q25, q75, color=line.get_color(), alpha=0.2, lw=0)
        ax.axhline(result.limits[j], color="k", ls="--", lw=0.8, label="limit")
        ax.set(title=f"({'abc'[j]}) Q_{node}, {result.seeds} seeds", xlabel="episode", ylabel=f"Q_{node}")
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
    """``python -m confront.experiments.migration``: run the comparison, print the tables, draw Figure 9."""
    import argparse

    ap = argparse.ArgumentParser(description=main.__doc__)
    ap.add_argument("--seeds", type=int, default=1000)
    ap.add_argument("--episodes", type=int, default=4000)
    ap.add_argument("--layers", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0, help="first seed")
    ap.add_argument("--plot", default="figure9.png")
    args = ap.parse_args(argv)
    if args.seeds < 1:
        ap.error(f"--seeds must be at least 1, got {args.seeds}")
    res = run_migration(seeds=args.seeds, episodes=args.episodes, layers=args.layers, seed=args.seed)
    print(format_summary(res))
    print(f"limits Q3, Q7, Q15: {', '.join(f'{x:.2f}' for x in res.limits)}")
    print(convergence_table(res))
    print(paired_table(res))
    for c in paper_claims(res):
        print(f"[{c['verdict']}] {c['text']}: {c['effect']}; p {c['p']}")
    print(f"plot: {plot_migration(res, args.plot)[0]}")


if __name__ == "__main__":
    main()
