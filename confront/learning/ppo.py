"""PPO with one policy shared by every tank and a team critic (MAPPO-style), CleanRL-style in one file.

The recommended learner (beyond the paper). Every learning tank of every battle is an agent of one shared
actor (parameter sharing, as the paper's §4.2); the critic sees the tank's own view and the mean view of
its team's living tanks (``team_critic``), so a team's value is learned from the whole team's observations.

Actions are factorised: one categorical head per action dimension (move distance, body turn, fire power,
target slot: :class:`confront.arena.tank.TankSpace`), the joint action is their mixed-radix index.

One update (Schulman et al. 2017; the 37 details of Huang et al. 2022 as in CleanRL's ppo.py):

    rollout of S steps over N agents  ->  GAE(gamma, lambda) advantages over each agent's stream
    (a stream ends where ``done``; steps where an agent was not ``active`` (dead) carry no loss)
    -> E epochs of M minibatches: clipped surrogate, clipped value loss, entropy bonus, grad-norm clip

With ``overlap`` the update of rollout k runs on a second thread while rollout k + 1 is
collected, acting with the weights from before that update (a behaviour policy one update behind, as in
asynchronous PPO): :meth:`start_update`, then :meth:`finish_update`. The update then uses decoupled PPO
(Hilton et al. 2022, "Batch size-invariance for policy optimization"): the ratio is clipped around the weights
the update starts from (the proximal policy), each sample weighted by pi_prox / pi_behaviour (truncated at
``IS_MAX``). Clipping around the behaviour policy instead clipped 38% of the samples and left the policy
near-uniform (docs/learning.md). The schedule does not depend on timing, so a run
is as deterministic as without it.

Arrays in, arrays out: :meth:`PPO.act` takes (N, F) float32 observations; :meth:`PPO.update` a
:class:`Rollout`. Parameters, optimiser moments and the sampling generator are data (:meth:`state_dict`),
so a checkpoint resumes exactly.
"""

from __future__ import annotations

import copy
import warnings
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from confront.learning.ppo_config import PPOConfig

IS_MAX = 2.0  # truncation of the behaviour -> proximal importance weight with ``overlap``
UPDATE_STATS = ("policy_loss", "value_loss", "entropy", "approx_kl", "clip_frac", "explained_variance")

__all__ = ["UPDATE_STATS", "entropy_coef", "learning_rate", "ActorCritic", "PPO", "Rollout", "Tanh",
           "team_mean", "greedy_joint"]


def entropy_coef(c: PPOConfig, updates: int) -> float:
    """The entropy bonus of update number ``updates`` (0-based): ent_coef, linearly to ent_coef_end over
    ent_anneal_updates updates, then ent_coef_end."""
    if c.ent_anneal_updates == 0:
        return c.ent_coef
    f = min(1.0, updates / c.ent_anneal_updates)
    return c.ent_coef + f * (c.ent_coef_end - c.ent_coef)


def learning_rate(c: PPOConfig, progress: float) -> float:
    """The Adam step at ``progress`` (the fraction of the run done, 0..1): lr, or with ``anneal_lr`` lr (1 -
    progress), 0 from the run's end on."""
    return c.lr * max(0.0, 1.0 - progress) if c.anneal_lr else c.lr


def _done(value: dict[str, float]) -> Future[dict[str, float]]:
    job: Future[dict[str, float]] = Future()
    job.set_result(value)
    return job


class _TanhFn(torch.autograd.Function):
    """tanh(x) = 2 sigmoid(2x) - 1 (within 2e-7 of torch.tanh, whose CPU kernel here is ~10x slower than
    sigmoid's: 22% of an update's time); the backward is tanh's, (1 - y^2) g."""

    @staticmethod
    def forward(ctx: torch.autograd.function.FunctionCtx, x: torch.Tensor) -> torch.Tensor:
        y = torch.sigmoid(2.0 * x).mul_(2.0).sub_(1.0)
        ctx.save_for_backward(y)
        return y

    @staticmethod
    def backward(ctx: torch.autograd.function.FunctionCtx, g: torch.Tensor) -> torch.Tensor:
        (y,) = ctx.saved_tensors  # type: ignore[attr-defined]
        return torch.ops.aten.tanh_backward(g, y)


class Tanh(nn.Module):
    """nn.Tanh by :class:`_TanhFn` (no parameters: state dicts are nn.Tanh's)."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return _TanhFn.apply(x)


def _layer(n_in: int, n_out: int, gain: float) -> nn.Linear:
    """Orthogonal weights, zero bias (CleanRL's layer_init)."""
    layer = nn.Linear(n_in, n_out)
    nn.init.orthogonal_(layer.weight, gain)
    nn.init.zeros_(layer.bias)
    return layer


class ActorCritic(nn.Module):
    """Actor: F -> H -> H -> sum(dims) logits (tanh); critic: (F or 2F) -> Hc -> Hc -> 1 (tanh), Hc =
    ``critic_hidden`` or H."""

    pad_index: torch.Tensor  # buffers (register_buffer below)
    pad: torch.Tensor

    def __init__(self, n_features: int, dims: tuple[int, ...], hidden: int, team_critic: bool,
                 critic_hidden: int = 0) -> None:
        super().__init__()
        self.dims = tuple(int(d) for d in dims)
        g = float(np.sqrt(2))
        self.actor = nn.Sequential(_layer(n_features, hidden, g), Tanh(), _layer(hidden, hidden, g), Tanh(),
                                   _layer(hidden, sum(self.dims), 0.01))
        n_crit = 2 * n_features if team_critic else n_features
        hc = critic_hidden or hidden
        self.critic = nn.Sequential(_layer(n_crit, hc, g), Tanh(), _layer(hc, hc, g), Tanh(), _layer(hc, 1, 1.0))
        # the heads' logits laid out as (H, max d) through one gather; the padding is masked to -inf
        width = max(self.dims)
        starts = np.cumsum((0,) + self.dims[:-1])
        idx = np.array([[s + min(j, d - 1) for j in range(width)] for s, d in zip(starts, self.dims, strict=True)])
        self.register_buffer("pad_index", torch.from_numpy(idx.reshape(-1)), persistent=False)
        self.register_buffer("pad", torch.from_numpy(np.arange(width)[None, :] >= np.array(self.dims)[:, None]),
                             persistent=False)

    def log_probs(self, obs: torch.Tensor, precision: str = "fp32") -> torch.Tensor:
        """Per-head log-probabilities (N, H, max d), -inf beyond a head's d choices."""
        z = _mlp(self.actor, obs, precision).index_select(1, self.pad_index).view(len(obs), *self.pad.shape)
        return torch.log_softmax(z.masked_fill(self.pad, -torch.inf), dim=-1)

    def value(self, critic_in: torch.Tensor, precision: str = "fp32") -> torch.Tensor:
        """V (N,)."""
        return _mlp(self.critic, critic_in, precision).squeeze(-1)


def _bf16_fast() -> bool:
    """Whether this CPU multiplies bfloat16 natively (oneDNN's check)."""
    try:
        return bool(torch.ops.mkldnn._is_mkldnn_bf16_supported())
    except (AttributeError, RuntimeError):
        return False


def _mlp(seq: nn.Sequential, x: torch.Tensor, precision: str) -> torch.Tensor:
    """``seq(x)`` (Linear, Tanh, Linear, Tanh, Linear) at a ``precision`` of ``PPOConfig.precision``: the layers from
    the first (``bf16``) or the second (``bf16-hidden``) up to the output one under bfloat16 autocast."""
    if precision == "fp32":
        return seq(x)
    lo = 0 if precision == "bf16" else 2
    h = seq[:lo](x)
    with torch.autocast("cpu", dtype=torch.bfloat16):
        h = seq[lo:-1](h)
    return seq[-1](h.float())


def team_mean(obs: np.ndarray, group: np.ndarray, n_groups: int, alive: np.ndarray) -> np.ndarray:
    """(N, F) mean observation of each agent's team (its ``group``, sorted, each of 0..n_groups-1 present), over
    living agents (all if none lives)."""
    w = alive.astype(np.float64) + 1e-6
    starts = np.flatnonzero(np.r_[True, group[1:] != group[:-1]])
    sums = np.add.reduceat(obs * w[:, None], starts, axis=0)
    tot = np.add.reduceat(w, starts)
    return (sums / tot[:, None])[group].astype(np.float32)


def greedy_joint(logits: np.ndarray, dims: tuple[int, ...]) -> np.ndarray:
    """Joint action of per-head argmax (ties to the lower index) of (N, sum(dims)) logits."""
    out = np.zeros(logits.shape[0], dtype=np.int64)
    start = 0
    for d in dims:
        out = out * d + np.argmax(logits[:, start:start + d], axis=1)
        start += d
    return out


@dataclass
class Rollout:
    """S steps of N agents: obs (S, N, F), critic inputs (S, N, C), heads (S, N, H) ints, logp / value /
    reward (S, N), done / active (S, N) bools, and the value of the observation after the last step (N,)."""

    obs: np.ndarray
    critic: np.ndarray
    heads: np.ndarray
    logp: np.ndarray
    value: np.ndarray
    reward: np.ndarray
    done: np.ndarray
    active: np.ndarray
    last_value: np.ndarray


def gae(reward: np.ndarray, value: np.ndarray, done: np.ndarray, active: np.ndarray, last_value: np.ndarray,
        gamma: float, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """(advantages, returns) (S, N): A_t = delta_t + gamma lambda (1 - done_t) A_{t+1}, delta_t = r_t + gamma
    (1 - done_t) V_{t+1} - V_t; inactive steps are zero and cut the stream."""
    s = reward.shape[0]
    adv = np.zeros_like(reward)
    nxt_v, nxt_a = last_value, np.zeros_like(last_value)
    for t in range(s - 1, -1, -1):
        keep = (~done[t]).astype(np.float64)
        delta = reward[t] + gamma * keep * nxt_v - value[t]
        adv[t] = np.where(active[t], delta + gamma * lam * keep * nxt_a, 0.0)
        nxt_v = np.where(active[t], value[t], 0.0)
        nxt_a = adv[t]
    return adv, adv + value


class PPO:
    """The learner: :meth:`act` during rollouts, :meth:`update` after each, data-only :meth:`state_dict`."""

    kind = "ppo"

    def __init__(self, n_features: int, dims: tuple[int, ...], config: PPOConfig | None = None, seed: int = 0,
                 init_logits: np.ndarray | None = None) -> None:
        self.config = config or PPOConfig()
        # acting runs between simulator steps on one thread; the update of the sequential schedule has the cores
        # to itself (:meth:`_learn` widens to ``threads``); with ``overlap`` both run beside the env at ``threads``
        self._act_threads = self.config.threads if self.config.overlap else 1
        if self.config.precision != "fp32" and not _bf16_fast():
            warnings.warn(f"ppo.precision = {self.config.precision} on a CPU without bfloat16 instructions "
                          "(AVX512-BF16, AMX): the update runs, emulated and slower than fp32", stacklevel=2)
        torch.set_num_threads(self._act_threads)
        torch.manual_seed(seed)
        self.net = ActorCritic(n_features, dims, self.config.hidden, self.config.team_critic,
                               self.config.critic_hidden)
        if init_logits is not None:  # a prior over the choices: added to the output layer's (zero) biases
            if np.shape(init_logits) != (sum(dims),) or not np.all(np.isfinite(init_logits)):
                raise ValueError(f"init_logits must be {sum(dims)} finite numbers, got shape {np.shape(init_logits)}")
            out = self.net.actor[-1]
            assert isinstance(out, nn.Linear)
            with torch.no_grad():
                out.bias.add_(torch.from_numpy(np.asarray(init_logits, dtype=np.float32)))
        self.opt = torch.optim.Adam(self.net.parameters(), lr=self.config.lr, eps=1e-5)
        self.gen = torch.Generator().manual_seed(seed)  # minibatch order
        self.act_gen = torch.Generator().manual_seed(seed + 1)  # action sampling (its own stream: acting and
        # updating may run side by side)
        self.acting = copy.deepcopy(self.net) if self.config.overlap else self.net  # the behaviour policy
        self._worker = ThreadPoolExecutor(1, thread_name_prefix="ppo-update") if self.config.overlap else None
        self._job: Future[dict[str, float]] | None = None
        self.ema = copy.deepcopy(self.net.actor) if self.config.ema_decay > 0 else None  # the averaged actor
        self.dims = self.net.dims
        self.n_features = n_features
        self.updates = 0

    def close(self) -> None:
        """Stop the update thread of ``overlap`` (acting still works; updating does not)."""
        if self._worker is not None:
            self._worker.shutdown(wait=True)

    @property
    def n_actions(self) -> int:
        """Joint actions."""
        return int(np.prod(self.dims))

    def critic_input(self, obs: np.ndarray, group: np.ndarray, n_groups: int, alive: np.ndarray) -> np.ndarray:
        """What the critic sees: the own view, and with ``team_critic`` the team's mean view beside it."""
        if not self.config.team_critic:
            return obs
        return np.concatenate([obs, team_mean(obs, group, n_groups, alive)], axis=1)

    @torch.no_grad()
    def act(self, obs: np.ndarray, explore: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(joint actions (N,), heads (N, H), log-probabilities (N,)) for (N, F) observations; sampled per head
        (Gumbel-max over the ``act_gen`` stream), or greedy (per-head argmax, ties to the lower index) without
        ``explore``. The values of a rollout come apart, from :meth:`values` on its critic inputs."""
        lp = self.acting.log_probs(torch.from_numpy(np.ascontiguousarray(obs, dtype=np.float32)))
        if explore:
            u = torch.rand(lp.shape, generator=self.act_gen).clamp_(min=1e-20)
            h = (lp - (-u.log()).log()).argmax(dim=2)
        else:
            h = lp.argmax(dim=2)
        logp = lp.gather(2, h[:, :, None]).sum(dim=(1, 2))
        hn = h.numpy()
        return np.ravel_multi_index(tuple(hn.T), self.dims), hn, logp.numpy()

    @torch.no_grad()
    def log_prob(self, obs: np.ndarray, heads: np.ndarray) -> np.ndarray:
        """Log-probabilities (N,) of the actions with heads (N, H) at (N, F) observations under the acting
        policy (what :meth:`act` returns for its own draws; for actions sampled elsewhere, e.g. by TankBot)."""
        lp = self.acting.log_probs(torch.from_numpy(np.ascontiguousarray(obs, dtype=np.float32)))
        h = torch.from_numpy(np.ascontiguousarray(heads, dtype=np.int64))
        return lp.gather(2, h[:, :, None]).sum(dim=(1, 2)).numpy()

    @torch.no_grad()
    def values(self, critic_in: np.ndarray, threads: int | None = None) -> np.ndarray:
        """V of (N, C) critic inputs (on ``threads`` torch threads for this call, e.g. a whole rollout's)."""
        x = torch.from_numpy(np.ascontiguousarray(critic_in, dtype=np.float32))
        if threads is None or threads == self._act_threads:
            return self.acting.value(x).numpy()
        torch.set_num_threads(threads)
        try:
            return self.acting.value(x).numpy()
        finally:
            torch.set_num_threads(self._act_threads)

    def set_progress(self, progress: float) -> None:
        """Tell the learner the fraction of the run done (0..1); with ``anneal_lr`` the next updates step by
        :func:`learning_rate`."""
        for group in self.opt.param_groups:
            group["lr"] = learning_rate(self.config, progress)

    def start_update(self, ro: Rollout) -> None:
        """Begin :meth:`update` on ``ro``: on the worker thread with ``overlap`` (acting stays on the current
        weights until :meth:`finish_update`), else here and now."""
        if self._worker is None:
            torch.set_num_threads(self.config.threads)
            try:
                self._job = _done(self._learn(ro))
            finally:
                torch.set_num_threads(self._act_threads)
        else:
            self._job = self._worker.submit(self._learn, ro)

    def finish_update(self) -> dict[str, float]:
        """Wait for the update :meth:`start_update` began; acting then follows the new weights."""
        if self._job is None:
            raise RuntimeError("finish_update without start_update")
        job, self._job = self._job, None
        stats = job.result()
        self._sync_acting()
        return stats

    def _sync_acting(self) -> None:
        if self.acting is not self.net:
            self.acting.load_state_dict(self.net.state_dict())

    def update(self, ro: Rollout) -> dict[str, float]:
        """One PPO update on a rollout, waited for; returns the losses, entropy, KL and clip fraction (means)."""
        self.start_update(ro)
        return self.finish_update()

    def _learn(self, ro: Rollout) -> dict[str, float]:
        c = self.config
        adv, ret = gae(ro.reward, ro.value.astype(np.float64), ro.done, ro.active, ro.last_value.astype(np.float64),
                       c.gamma, c.gae_lambda)
        m = ro.active.reshape(-1)
        obs = torch.from_numpy(ro.obs.reshape(-1, ro.obs.shape[-1])[m])
        crit = torch.from_numpy(ro.critic.reshape(-1, ro.critic.shape[-1])[m])
        heads = torch.from_numpy(ro.heads.reshape(-1, ro.heads.shape[-1])[m])
        old_logp = torch.from_numpy(ro.logp.reshape(-1)[m].astype(np.float32))
        old_v = torch.from_numpy(ro.value.reshape(-1)[m].astype(np.float32))
        adv_t = torch.from_numpy(adv.reshape(-1)[m].astype(np.float32))
        ret_t = torch.from_numpy(ret.reshape(-1)[m].astype(np.float32))
        n = obs.shape[0]
        stats = {"policy_loss": 0.0, "value_loss": 0.0, "entropy": 0.0, "approx_kl": 0.0, "clip_frac": 0.0}
        if n == 0:
            return stats
        if self.acting is self.net:  # acted with these weights: they are the proximal policy, weights 1
            prox_logp, weight = old_logp, torch.ones(n)
        else:  # acted one update behind: clip around the current weights (decoupled PPO, Hilton et al. 2022)
            with torch.no_grad():
                prox_logp = self.net.log_probs(obs).gather(2, heads[:, :, None]).sum(dim=(1, 2))
            weight = (prox_logp - old_logp).exp().clamp(max=IS_MAX)  # behaviour -> proximal, truncated
        size = max(1, n // c.minibatches)
        count = 0
        ent_coef = entropy_coef(c, self.updates)
        for _ in range(c.epochs):
            perm = torch.randperm(n, generator=self.gen)
            for start in range(0, n, size):
                idx = perm[start:start + size]
                # index_select: 4-8x faster than advanced indexing here (same values)
                mb_obs, mb_heads, mb_crit, mb_prox, a, mb_w, mb_old_v, mb_ret = (
                    t.index_select(0, idx) for t in (obs, heads, crit, prox_logp, adv_t, weight, old_v, ret_t))
                lp = self.net.log_probs(mb_obs, c.precision)
                logp = lp.gather(2, mb_heads[:, :, None]).sum(dim=(1, 2))
                entropy = -(lp.exp() * lp.masked_fill(self.net.pad, 0.0)).sum(dim=(1, 2)).mean()
                ratio = (logp - mb_prox).exp()
                a = (a - a.mean()) / (a.std() + 1e-8) if len(idx) > 1 else a
                pg = (mb_w * torch.max(-a * ratio, -a * ratio.clamp(1 - c.clip, 1 + c.clip))).mean()
                v = self.net.value(mb_crit, c.precision)
                v_clip = mb_old_v + (v - mb_old_v).clamp(-c.clip, c.clip)
                vl = 0.5 * torch.max((v - mb_ret) ** 2, (v_clip - mb_ret) ** 2).mean()
                loss = pg - ent_coef * entropy + c.vf_coef * vl
                if self.updates < c.value_warmup_updates:  # the critic alone: the actor gets no gradient
                    loss = c.vf_coef * vl
                self.opt.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(self.net.parameters(), c.max_grad_norm)
                self.opt.step()
                with torch.no_grad():
                    lr = logp - mb_prox
                    stats["approx_kl"] += float(((lr.exp() - 1) - lr).mean())
                    stats["clip_frac"] += float(((ratio - 1).abs() > c.clip).float().mean())
                stats["policy_loss"] += float(pg.detach())
                stats["value_loss"] += float(vl.detach())
                stats["entropy"] += float(entropy.detach())
                count += 1
        self.updates += 1
        if self.ema is not None:  # Polyak averaging: ema <- d ema + (1 - d) actor
            with torch.no_grad():
                for pe, p in zip(self.ema.parameters(), self.net.actor.parameters(), strict=True):
                    pe.mul_(c.ema_decay).add_(p, alpha=1 - c.ema_decay)
        out = {k: v / count for k, v in stats.items()}
        out["explained_variance"] = float(1 - np.var(ret.reshape(-1)[m] - ro.value.reshape(-1)[m])
                                          / (np.var(ret.reshape(-1)[m]) + 1e-12))
        return out

    def adopt_average(self) -> None:
        """Make the averaged actor (``ema_decay``) the actor: the policy a finished run saves and plays."""
        if self.ema is not None:
            self.net.actor.load_state_dict(self.ema.state_dict())
            self._sync_acting()

    # -- data-only state ---------------------------------------------------------------------------------
    def actor_arrays(self) -> dict[str, np.ndarray]:
        """The actor's layers as w0, b0, w1, b1, w2, b2 (weights (out, in), float64): what export needs."""
        layers = [m for m in self.net.actor if isinstance(m, nn.Linear)]
        out: dict[str, np.ndarray] = {}
        for i, layer in enumerate(layers):
            out[f"w{i}"] = layer.weight.detach().numpy().astype(np.float64)
            out[f"b{i}"] = layer.bias.detach().numpy().astype(np.float64)
        return out

    def load_actor_arrays(self, d: dict[str, np.ndarray]) -> None:
        """Set the actor from :meth:`actor_arrays`' output."""
        layers = [m for m in self.net.actor if isinstance(m, nn.Linear)]
        with torch.no_grad():
            for i, layer in enumerate(layers):
                w, b = np.asarray(d[f"w{i}"]), np.asarray(d[f"b{i}"])
                if w.shape != tuple(layer.weight.shape) or b.shape != tuple(layer.bias.shape):
                    raise ValueError(f"actor layer {i}: got {w.shape}/{b.shape}, expected "
                                     f"{tuple(layer.weight.shape)}/{tuple(layer.bias.shape)}")
                layer.weight.copy_(torch.from_numpy(w.astype(np.float32)))
                layer.bias.copy_(torch.from_numpy(b.astype(np.float32)))
        self._sync_acting()

    def state_dict(self) -> dict[str, np.ndarray]:
        """Network, Adam moments, sampling generator and update count as arrays."""
        d = {f"net.{k}": v.detach().numpy().copy() for k, v in self.net.state_dict().items()}
        opt = self.opt.state_dict()
        for pid, st in opt["state"].items():
            for k, v in st.items():
                d[f"opt.{pid}.{k}"] = v.detach().numpy().copy() if torch.is_tensor(v) else np.asarray(v)
        d["gen"] = self.gen.get_state().numpy().copy()
        d["act_gen"] = self.act_gen.get_state().numpy().copy()
        d["updates"] = np.asarray(self.updates)
        if self.ema is not None:
            d.update({f"ema.{k}": v.detach().numpy().copy() for k, v in self.ema.state_dict().items()})
        return d

    def load_state_dict(self, d: dict[str, np.ndarray]) -> None:
        """Restore :meth:`state_dict`'s output (ValueError on a mismatch)."""
        try:
            self.net.load_state_dict({k[4:]: torch.from_numpy(np.array(v)) for k, v in d.items()
                                      if k.startswith("net.")})
        except RuntimeError as exc:
            raise ValueError(f"network does not fit: {str(exc).splitlines()[0]}") from None
        opt = self.opt.state_dict()
        state: dict[int, dict[str, torch.Tensor]] = {}
        for k, v in d.items():
            if k.startswith("opt."):
                _, pid, name = k.split(".", 2)
                state.setdefault(int(pid), {})[name] = torch.from_numpy(np.array(v))
        opt["state"] = state
        self.opt.load_state_dict(opt)
        self.gen.set_state(torch.from_numpy(np.asarray(d["gen"], dtype=np.uint8)))
        if "act_gen" in d:  # models saved before acting had its own stream keep the seed's
            self.act_gen.set_state(torch.from_numpy(np.asarray(d["act_gen"], dtype=np.uint8)))
        self.updates = int(d["updates"])
        if self.ema is not None:  # a model saved without the average starts it from its actor
            ema = {k[4:]: torch.from_numpy(np.array(v)) for k, v in d.items() if k.startswith("ema.")}
            self.ema.load_state_dict(ema or self.net.actor.state_dict())
        self._sync_acting()
