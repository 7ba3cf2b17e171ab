"""DMNN: the decision-making neural network (paper §4, Eq. 19-32, Algorithm 2).

A fully connected back-propagation network with the bipolar sigmoid of Eq. 19 on every hidden layer, one Q
output per action and a softmax layer with annealed temperature for the choice. Training moves Q(s_t, a_t)
toward the SMDP backup target by the TD error phi = alpha_RL (target - Q) (Eq. 32); each pattern's squared
error E_p = phi^2 / 2 (Eq. 21) is averaged over the batch (Eq. 22). "With AWM": momentum beta (Eq. 23) and the
adaptive rate 1 - exp(-E_p) per pattern (Eq. 24); "without AWM": plain back-propagation at a fixed rate.

The output layer is linear by default (Q is unbounded; the paper's bipolar output would cap it at +-a): choose
``output="bipolar"`` for Eq. 20 as printed. Targets are scaled into network units, Q = q_scale * y, and the TD
error is clipped to +-td_clip network units before Eq. 32 (0 disables it): the adaptive rate 1 - exp(-E) tends
to 1 for large errors and, with momentum 0.95, would otherwise take twenty-fold steps and diverge.
Parameter sharing (§4.2) is simply a batch whose rows are the tanks of a team: one network, one update.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from confront.learning.backups import BACKUPS, BOOTSTRAPS, bootstrap_values, smdp_target
from confront.learning.base import (
    Learner,
    LearnerParams,
    Transition,
    check_choice,
    check_int,
    check_range,
    require_keys,
)
from confront.learning.exploration import ExplorationParams, policy_probs, select_actions
from confront.learning.fuzzy import FuzzyLearningRate, FuzzyParams
from confront.learning.tabular import RATES

__all__ = [
    "DMNN",
    "DMNNParams",
    "backward",
    "bipolar",
    "bipolar_slope",
    "forward",
    "td_loss_and_grads",
]

OUTPUTS = ("linear", "bipolar")
OBSERVATIONS = ("features", "discrete")
DTYPES = ("float64", "float32")
OUTPUT_INITS = ("zero", "uniform")
UNITS = ("q", "network")  # Q in reward units, or the network's own output units y = Q / q_scale


def bipolar(x: np.ndarray, a: float, b: float) -> np.ndarray:
    """The paper's activation."""
    return a * np.tanh(0.5 * b * x)  # Eq. 19: f(x) = a (1 - e^{-bx}) / (1 + e^{-bx}) = a tanh(bx/2)


def bipolar_slope(y: np.ndarray, a: float, b: float) -> np.ndarray:
    """f'(x) written with the output y = f(x)."""
    return (0.5 * b / a) * (a * a - y * y)  # d/dx a tanh(bx/2) = (b / 2a)(a^2 - f^2) (Eq. 25's correct form)


def forward(
    weights: list[np.ndarray], biases: list[np.ndarray], x: np.ndarray, a: float, b: float, linear_out: bool
) -> list[np.ndarray]:
    """Activations of every layer, input first, output (N, A) last."""
    acts = [x]
    last = len(weights) - 1
    for i, (w, th) in enumerate(zip(weights, biases, strict=True)):
        net = acts[-1] @ w + th  # Eq. 19/20: net_j = sum_i y_i w_ji, plus the threshold theta_j
        acts.append(net if (i == last and linear_out) else bipolar(net, a, b))  # y_j = f(theta_j + net_j)
    return acts


def backward(
    weights: list[np.ndarray], acts: list[np.ndarray], d_out: np.ndarray, a: float, b: float, linear_out: bool
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Gradients of a loss w.r.t. weights and thresholds, given dLoss/d(output) ``d_out`` (N, A)."""
    n_layers = len(weights)
    gw: list[np.ndarray] = [np.empty(0)] * n_layers
    gb: list[np.ndarray] = [np.empty(0)] * n_layers
    delta = d_out if linear_out else d_out * bipolar_slope(acts[-1], a, b)  # Eq. 25/26: output delta
    for i in range(n_layers - 1, -1, -1):
        gw[i] = acts[i].T @ delta  # Eq. 23: dE/dw_kj = dE/dnet_k * y_j
        gb[i] = delta.sum(axis=0)
        if i:
            delta = (delta @ weights[i].T) * bipolar_slope(acts[i], a, b)  # Eq. 28-29: hidden deltas
    return gw, gb


def td_loss_and_grads(
    weights: list[np.ndarray],
    biases: list[np.ndarray],
    x: np.ndarray,
    actions: np.ndarray,
    labels: np.ndarray,
    a: float,
    b: float,
    linear_out: bool,
    pattern_rates: np.ndarray | None = None,
    acts: list[np.ndarray] | None = None,
) -> tuple[float, np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """E = mean_p rate_p (O_p - y_{p,a_p})^2 / 2 (Eq. 21-22; rate_p = 1 without AWM) and its gradients.

    Only the taken action's output has a label. ``acts`` reuses a forward pass of ``x``.
    Returns (E, per-pattern errors O - y, weight grads, bias grads).
    """
    if acts is None:
        acts = forward(weights, biases, x, a, b, linear_out)
    n = x.shape[0]
    rows = np.arange(n)
    err = labels - acts[-1][rows, actions]
    rates = np.ones(n) if pattern_rates is None else pattern_rates
    loss = float(np.mean(rates * 0.5 * err * err))  # Eq. 22: E = sum_p sum_k (O - y)^2 / (2 M_n)
    d_out = np.zeros_like(acts[-1])
    d_out[rows, actions] = -rates * err / n
    gw, gb = backward(weights, acts, d_out, a, b, linear_out)
    return loss, err, gw, gb


@dataclass(frozen=True)
class DMNNParams(LearnerParams):
    """Parameters of :class:`DMNN` (defaults: the paper's Table 2, with AWM)."""

    n_inputs: int = 8
    n_actions: int = 4
    observation: str = "features"
    hidden: tuple[int, ...] = (32,)
    a: float = 1.725
    b: float = 0.566
    output: str = "linear"
    q_scale: float = 10.0
    td_clip: float = 5.0
    rate_units: str = "network"
    output_init: str = "uniform"
    softmax_units: str = "q"
    gamma: float = 0.9
    alpha: float = 0.1
    rate: str = "fixed"
    backup: str = "paper"
    bootstrap: str = "expected"
    awm: bool = True
    momentum: float = 0.95
    nn_rate: float = 0.9
    exploration: str = "boltzmann"
    t_max: float = 0.1
    t_min: float = 0.01
    eta: float = 0.9
    exploit: float = 0.95
    exploit_decay: float = 0.99
    init_seed: int = 0
    dtype: str = "float64"

    def validate(self) -> None:
        check_choice("dtype", self.dtype, DTYPES)
        check_int("n_inputs", self.n_inputs, 1)
        check_int("n_actions", self.n_actions, 1)
        check_choice("observation", self.observation, OBSERVATIONS)
        if not isinstance(self.hidden, tuple) or not self.hidden:
            raise ValueError(f"bad value hidden={self.hidden!r}: must be a non-empty list of layer sizes")
        for i, h in enumerate(self.hidden):
            check_int(f"hidden[{i}]", h, 1, 1_000_000)
        check_range("a", self.a, 0.0, 1e6, lo_open=True)
        check_range("b", self.b, 0.0, 1e6, lo_open=True)
        check_choice("output", self.output, OUTPUTS)
        check_range("q_scale", self.q_scale, 0.0, 1e12, lo_open=True)
        check_range("td_clip", self.td_clip, 0.0, 1e12)
        check_choice("rate_units", self.rate_units, UNITS)
        check_choice("softmax_units", self.softmax_units, UNITS)
        check_choice("output_init", self.output_init, OUTPUT_INITS)
        check_range("gamma", self.gamma, 0.0, 1.0)
        check_range("alpha", self.alpha, 0.0, 1.0, lo_open=True)
        check_choice("rate", self.rate, RATES)
        check_choice("backup", self.backup, BACKUPS)
        check_choice("bootstrap", self.bootstrap, BOOTSTRAPS)
        if not isinstance(self.awm, bool | np.bool_):
            raise ValueError(f"bad value awm={self.awm!r}: must be true or false")
        check_range("momentum", self.momentum, 0.0, 1.0, hi_open=True)
        check_range("nn_rate", self.nn_rate, 0.0, 10.0, lo_open=True)
        check_int("init_seed", self.init_seed, 0)
        self.exploration_params()

    def exploration_params(self) -> ExplorationParams:
        """The exploration settings as their own dataclass."""
        return ExplorationParams(self.exploration, self.t_max, self.t_min, self.eta, self.exploit,
                                 self.exploit_decay)


class DMNN(Learner):
    """Batched DMNN learner; exploration schedules advance once per ``learn`` call."""

    def __init__(self, params: DMNNParams | None = None, rng: np.random.Generator | None = None,
                 fuzzy: FuzzyParams | None = None, kind: str = "dmnn") -> None:
        self.params = p = params or DMNNParams()
        self.kind = kind
        self.observation = p.observation
        self.n_actions = p.n_actions
        self._explore = p.exploration_params()
        self._fuzzy = FuzzyLearningRate(fuzzy) if p.rate == "fuzzy" else None
        self._linear = p.output == "linear"
        rng = rng if rng is not None else np.random.default_rng(p.init_seed)
        self.dtype = np.dtype(p.dtype)
        sizes = (p.n_inputs, *p.hidden, p.n_actions)
        self.weights = [(rng.uniform(-1.0, 1.0, (i, o)) / np.sqrt(i)).astype(self.dtype) for i, o in pairwise(sizes)]
        if p.output_init == "zero":  # Q(s, .) = 0 at the start, as the tables' q_init (whatever q_scale is)
            self.weights[-1][:] = 0.0
        self.biases = [np.zeros(o, dtype=self.dtype) for o in sizes[1:]]
        self.vel_w = [np.zeros_like(w) for w in self.weights]
        self.vel_b = [np.zeros_like(th) for th in self.biases]
        self.step = 0
        self._last = np.zeros(4)  # mean |TD error| (Q units), mean RL rate, mean NN rate, loss E

    def inputs(self, obs: np.ndarray) -> np.ndarray:
        """Network input rows: the features, or one-hot rows of discrete states."""
        n_in = self.params.n_inputs
        if self.observation == "discrete":
            s = np.asarray(obs).reshape(-1)
            if s.dtype.kind not in "iu" or (s.size and (s.min() < 0 or s.max() >= n_in)):
                raise ValueError(f"obs must be integer states in [0, {n_in}) for a discrete DMNN")
            x = np.zeros((s.size, n_in), dtype=self.dtype)
            x[np.arange(s.size), s] = 1.0
            return x
        x = np.asarray(obs, dtype=self.dtype)
        if x.ndim != 2 or x.shape[1] != n_in:
            raise ValueError(f"obs must have shape (N, {n_in}) for a features DMNN, got {x.shape}")
        return x

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        """Q(s, .) in reward units, (N, A)."""
        p = self.params
        y = forward(self.weights, self.biases, self.inputs(obs), p.a, p.b, self._linear)[-1]
        return p.q_scale * y.astype(np.float64)

    def act(self, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
        # Eq. 30-31: softmax layer over the Q outputs at the annealed temperature
        return select_actions(self._explore, self.softmax_input(self.q_values(obs)), self.step, rng, explore)

    def softmax_input(self, q: np.ndarray) -> np.ndarray:
        """What the softmax layer's temperature divides: Q, or the network outputs Q / q_scale."""
        return q / self.params.q_scale if self.params.softmax_units == "network" else q

    def learning_rate(self, rewards: np.ndarray) -> np.ndarray:
        """Per-transition RL rate: fixed alpha, or the fuzzy map of the SMDP step's summed reward."""
        if self._fuzzy is None:
            return np.full(rewards.shape[0], self.params.alpha)
        return np.asarray(self._fuzzy(rewards.sum(axis=1)))

    def targets(self, batch: Transition) -> np.ndarray:
        """Backup targets (reward units) from the current network."""
        q_next = self.q_values(batch.next_obs)
        expected = self.params.bootstrap == "expected"
        probs = policy_probs(self._explore, self.softmax_input(q_next), self.step) if expected else None
        v = bootstrap_values(q_next, probs, batch.done)
        return smdp_target(batch.rewards, v, self.params.gamma, self.params.backup)

    def learn(self, batch: Transition) -> dict[str, float]:
        p = self.params
        a = batch.action
        if a.size and (a.min() < 0 or a.max() >= self.n_actions):
            raise ValueError(f"action holds a value outside [0, {self.n_actions})")
        target = self.targets(batch) / p.q_scale
        x = self.inputs(batch.obs)
        acts = forward(self.weights, self.biases, x, p.a, p.b, self._linear)
        n = x.shape[0]
        rows = np.arange(n)
        td = target - acts[-1][rows, a]
        alpha = self.learning_rate(batch.rewards)
        clipped = np.clip(td, -p.td_clip, p.td_clip) if p.td_clip > 0 else td  # guard: see docs/learning.md
        phi = alpha * clipped  # Eq. 32: phi_t = Q_next - Q_cur = alpha [target - Q_cur]
        e_p = 0.5 * phi * phi  # Eq. 21: E_p = (O - y)^2 / 2 with the label O = Q_cur + phi
        if p.awm:
            e_rate = e_p * p.q_scale**2 if p.rate_units == "q" else e_p  # E_p of phi in Q units, or network units
            lam = 1.0 - np.exp(-e_rate)  # Eq. 24: adaptive rate 1 - exp(-E_p)
        else:
            lam = np.full(n, p.nn_rate)
        labels = acts[-1][rows, a] + phi  # Eq. 18: Q_cur* = (1 - alpha) Q_cur + alpha target
        # lambda_p dE_p/dw averaged over the batch (Eq. 22-23)
        _, _, gw, gb = td_loss_and_grads(self.weights, self.biases, x, a, labels, p.a, p.b, self._linear,
                                         pattern_rates=lam, acts=acts)
        beta = p.momentum if p.awm else 0.0
        vel_w = [beta * v - g for v, g in zip(self.vel_w, gw, strict=True)]  # Eq. 23: dw = beta dw - lambda dE/dw
        vel_b = [beta * v - g for v, g in zip(self.vel_b, gb, strict=True)]
        if not all(np.isfinite(v).all() for v in vel_w + vel_b):
            raise FloatingPointError("DMNN update is non-finite (weights left unchanged): lower td_clip or "
                                     "raise q_scale")
        self.vel_w, self.vel_b = vel_w, vel_b
        for i in range(len(self.weights)):
            self.weights[i] += vel_w[i]
            self.biases[i] += vel_b[i]
        self.step += 1
        self._last = np.array([np.abs(td).mean() * p.q_scale, alpha.mean(), lam.mean(), e_p.mean()])
        return {"td_error": float(self._last[0]), "learning_rate": float(self._last[1]),
                "nn_rate": float(self._last[2]), "loss": float(self._last[3])}

    def weights_norm(self) -> float:
        """Euclidean norm of all weights and thresholds."""
        return float(np.sqrt(sum((w * w).sum() for w in self.weights + self.biases)))

    def diagnostics(self) -> dict[str, float]:
        return {
            "temperature": self._explore.temperature(self.step),
            "exploit": self._explore.threshold(self.step),
            "learning_rate": float(self._last[1]),
            "nn_rate": float(self._last[2]),
            "td_error": float(self._last[0]),
            "loss": float(self._last[3]),
            "weights_norm": self.weights_norm(),
            "updates": float(self.step),
        }

    def state_dict(self) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {"step": np.array(self.step, dtype=np.int64), "last": self._last.copy()}
        for i in range(len(self.weights)):
            out[f"w{i}"] = self.weights[i].copy()
            out[f"b{i}"] = self.biases[i].copy()
            out[f"vw{i}"] = self.vel_w[i].copy()
            out[f"vb{i}"] = self.vel_b[i].copy()
        return out

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        expected: dict[str, tuple[int, ...]] = {"step": (), "last": (4,)}
        for i, (w, th) in enumerate(zip(self.weights, self.biases, strict=True)):
            expected.update({f"w{i}": w.shape, f"b{i}": th.shape, f"vw{i}": w.shape, f"vb{i}": th.shape})
        require_keys(state, expected)
        k = len(self.weights)
        self.weights = [np.array(state[f"w{i}"], dtype=self.dtype) for i in range(k)]
        self.biases = [np.array(state[f"b{i}"], dtype=self.dtype) for i in range(k)]
        self.vel_w = [np.array(state[f"vw{i}"], dtype=self.dtype) for i in range(k)]
        self.vel_b = [np.array(state[f"vb{i}"], dtype=self.dtype) for i in range(k)]
        self.step = int(state["step"])
        self._last = np.array(state["last"], dtype=np.float64)
