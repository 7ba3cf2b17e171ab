"""Fuzzy learning rate (paper §3.2, Eq. 11-17, §6.3): reward in, RL learning rate out.

Five input terms LN, TN, ZO, TP, LP on seven input points and five output terms VS, LS, M, LL, VL on seven
output points; trapezoids at both ends, triangles inside (term k peaks at point k+1). The relation matrix is
built by max-min composition, the reward is fuzzified by the weighted average of Eq. 15, composed with the
relation by max-min (Eq. 16) and defuzzified by the weighted average of Eq. 17. The map is fixed, so it is
tabulated once on a dense grid and evaluated by linear interpolation.

The output domain is ascending (positive reward -> high rate, paper-notes §4); §6.3 lists the same seven
values in descending order. Reversing ``rules`` gives the opposite reading.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from confront.learning.base import check_int

__all__ = [
    "INPUT_TERMS",
    "OUTPUT_TERMS",
    "FuzzyLearningRate",
    "FuzzyParams",
    "memberships",
    "memberships_numpy",
    "paper_learning_rate",
    "plot_fuzzy",
]

INPUT_TERMS = ("LN", "TN", "ZO", "TP", "LP")
OUTPUT_TERMS = ("VS", "LS", "M", "LL", "VL")


@dataclass(frozen=True)
class FuzzyParams:
    """Domains, rules and table resolution of the fuzzy learning rate (defaults: paper §6.3).

    ``rules[k]`` is the output term (index into VS, LS, M, LL, VL) fired by input term k (LN, TN, ZO, TP, LP).
    """

    input_points: tuple[float, ...] = (-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0)
    output_points: tuple[float, ...] = (0.05, 0.20, 0.35, 0.50, 0.65, 0.80, 0.95)
    rules: tuple[int, ...] = (0, 1, 2, 3, 4)
    grid_size: int = 6001

    def __post_init__(self) -> None:
        for key in ("input_points", "output_points"):
            pts = np.asarray(getattr(self, key), dtype=np.float64)
            if pts.shape != (7,) or not np.all(np.isfinite(pts)) or not np.all(np.diff(pts) > 0):
                raise ValueError(f"bad value {key}={getattr(self, key)!r}: must be 7 strictly increasing numbers")
        if sorted(self.rules) != list(range(5)) or len(self.rules) != 5:
            raise ValueError(f"bad value rules={self.rules!r}: must be a permutation of 0..4 (one per input term)")
        check_int("grid_size", self.grid_size, 2, 10_000_000)


def _corners(points: np.ndarray) -> list[list[float]]:
    """skfuzzy corner lists of the five terms: trapezoid, three triangles, trapezoid."""
    p = [float(x) for x in points]
    return [[p[0], p[0], p[1], p[2]], [p[1], p[2], p[3]], [p[2], p[3], p[4]], [p[3], p[4], p[5]],
            [p[4], p[5], p[6], p[6]]]


def memberships(x: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Degrees of the five terms at ``x`` (clipped to the domain), with skfuzzy: ``(5, len(x))``."""
    import skfuzzy  # imported here: it pulls in scipy, which other learners do not need

    x = np.clip(np.atleast_1d(np.asarray(x, dtype=np.float64)), points[0], points[-1])
    rows = []
    for c in _corners(points):
        # Eq. 11 (end terms) and triangles: skfuzzy.trapmf / trimf
        rows.append(skfuzzy.trapmf(x, c) if len(c) == 4 else skfuzzy.trimf(x, c))
    return np.array(rows)


def memberships_numpy(x: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The same degrees as :func:`memberships`, in plain NumPy (piecewise-linear interpolation)."""
    x = np.atleast_1d(np.asarray(x, dtype=np.float64))
    p = points
    return np.array([
        np.interp(x, [p[1], p[2]], [1.0, 0.0]),  # Eq. 11: 1 below r2, (r3 - r)/(r3 - r2) between, 0 above r3
        np.interp(x, [p[1], p[2], p[3]], [0.0, 1.0, 0.0]),
        np.interp(x, [p[2], p[3], p[4]], [0.0, 1.0, 0.0]),
        np.interp(x, [p[3], p[4], p[5]], [0.0, 1.0, 0.0]),
        np.interp(x, [p[4], p[5]], [0.0, 1.0]),
    ])


def _infer_numpy(r: np.ndarray, params: FuzzyParams) -> np.ndarray:
    """Eq. 12-17 in plain NumPy for a batch of rewards."""
    ip = np.asarray(params.input_points)
    op = np.asarray(params.output_points)
    idm = memberships_numpy(ip, ip)  # Eq. 12: ID_ij = mu_i(I_j), (5, 7)
    odm = memberships_numpy(op, op)[list(params.rules)]  # Eq. 13 with rule k -> output term rules[k]
    rel = np.minimum(idm[:, :, None], odm[:, None, :]).max(axis=0)  # Eq. 14: R_ij = max_k min(ID_ki, OD_kj)
    mu = memberships_numpy(np.clip(r, ip[0], ip[-1]), ip)  # (5, N)
    fi = (idm.T @ mu) / mu.sum(axis=0)  # Eq. 15: FI_j = sum_i ID_ij mu_i(r0) / sum_i mu_i(r0), (7, N)
    fo = np.minimum(rel[:, :, None], fi[:, None, :]).max(axis=0)  # Eq. 16: FO_j = max_k min(R_kj, FI_k)
    return (op @ fo) / fo.sum(axis=0)  # Eq. 17: alpha = sum_j FO_j O_j / sum_j FO_j


def _infer_skfuzzy(r: np.ndarray, params: FuzzyParams) -> np.ndarray:
    """Eq. 12-17 with skfuzzy's memberships and max-min composition."""
    import skfuzzy

    ip = np.asarray(params.input_points)
    op = np.asarray(params.output_points)
    idm = memberships(ip, ip)  # Eq. 12
    odm = memberships(op, op)[list(params.rules)]  # Eq. 13
    rel = skfuzzy.maxmin_composition(idm.T, odm)  # Eq. 14: (7 x 5) o (5 x 7)
    mu = memberships(r, ip)
    fi = (idm.T @ mu) / mu.sum(axis=0)  # Eq. 15
    fo = skfuzzy.maxmin_composition(fi.T, rel)  # Eq. 16: (N x 7) o (7 x 7)
    return (fo @ op) / fo.sum(axis=1)  # Eq. 17


class FuzzyLearningRate:
    """Reward -> learning rate, tabulated once; call it on a float (returns a float) or an array."""

    def __init__(self, params: FuzzyParams | None = None) -> None:
        self.params = params or FuzzyParams()
        lo, hi = self.params.input_points[0], self.params.input_points[-1]
        self.grid = np.linspace(lo, hi, self.params.grid_size)
        self.table = _infer_skfuzzy(self.grid, self.params)
        self._lo, self._hi = float(lo), float(hi)
        self._inv_step = (self.params.grid_size - 1) / (hi - lo)
        self._slope = np.diff(self.table)
        self._n = self.table.shape[0]
        self._table_list, self._slope_list = self.table.tolist(), self._slope.tolist()

    def __call__(self, reward: float | np.ndarray) -> float | np.ndarray:
        r = np.asarray(reward, dtype=np.float64)
        u = (np.clip(r, self._lo, self._hi) - self._lo) * self._inv_step  # rewards outside the domain clipped
        i = np.minimum(u.astype(np.intp), self.table.shape[0] - 2)
        out = self.table[i] + (u - i) * self._slope[i]  # linear interpolation on the uniform grid
        return float(out) if out.ndim == 0 else out

    def scalar(self, reward: float) -> float:
        """``self(reward)`` for one finite float, on Python floats (the same double, without NumPy's per-call
        cost; a test checks this)."""
        u = (min(max(reward, self._lo), self._hi) - self._lo) * self._inv_step
        i = min(int(u), self._n - 2)
        return self._table_list[i] + (u - i) * self._slope_list[i]

    def exact(self, reward: float | np.ndarray, backend: str = "skfuzzy") -> np.ndarray:
        """Untabulated inference (``skfuzzy`` or ``numpy``), for checking the table."""
        r = np.atleast_1d(np.asarray(reward, dtype=np.float64))
        if backend == "skfuzzy":
            return _infer_skfuzzy(r, self.params)
        if backend == "numpy":
            return _infer_numpy(r, self.params)
        raise ValueError(f"bad value backend={backend!r}: must be one of skfuzzy, numpy")


@lru_cache(maxsize=1)
def _paper() -> FuzzyLearningRate:
    return FuzzyLearningRate()


def paper_learning_rate(reward: float | np.ndarray) -> float | np.ndarray:
    """The fuzzy learning rate with the paper's settings (§6.3)."""
    return _paper()(reward)


def plot_fuzzy(path: str | Path, params: FuzzyParams | None = None) -> Path:
    """Draw Figure 13 (reward -> learning rate) with the input and output memberships; write a PNG."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from confront.files import figure_path

    figure_path(path)  # a bad name fails before the drawing
    flr = FuzzyLearningRate(params)
    p = flr.params
    ip, op = np.asarray(p.input_points), np.asarray(p.output_points)
    fig = Figure(figsize=(12, 3.6))
    FigureCanvasAgg(fig)
    ax_in, ax_out, ax_map = fig.subplots(1, 3)
    xi = np.linspace(ip[0], ip[-1], 601)
    for name, row in zip(INPUT_TERMS, memberships(xi, ip), strict=True):
        ax_in.plot(xi, row, label=name)
    ax_in.set(title="(a) reward memberships", xlabel="reward r", ylabel="degree")
    xo = np.linspace(op[0], op[-1], 601)
    for name, row in zip(OUTPUT_TERMS, memberships(xo, op), strict=True):
        ax_out.plot(xo, row, label=name)
    ax_out.set(title="(b) learning-rate memberships", xlabel="learning rate", ylabel="degree")
    for ax in (ax_in, ax_out):
        ax.legend(fontsize=7, loc="center right")
        ax.set_ylim(-0.05, 1.05)
    ax_map.plot(flr.grid, flr.table, color="k")
    ax_map.plot(ip, flr(ip), "o", color="C3", ms=4)
    ax_map.set(title="Figure 13: fuzzy learning rate", xlabel="reward r", ylabel="learning rate")
    ax_map.grid(alpha=0.3)
    fig.tight_layout()
    from confront.files import save_figure

    return save_figure(fig, path, dpi=120)
