"""Observations and reward of the paper's RL model (paper §6.1), as pure functions over (B, R) arrays.

Angles follow Robocode: radians, 0 = north (+y), clockwise; x right, y up.

Discrete state (4 x 4 x 20 = 320 states), ``index = (rel_bin * 4 + heading_bin) * 20 + dist_bin``:

- ``rel_bin``: direction of the target relative to the own body heading, 4 bins of 90 degrees centred on
  ahead (0: [-45, 45) deg), right (1: [45, 135)), behind (2: [135, 225)), left (3: [225, 315)).
- ``heading_bin``: own absolute heading in 4 quadrants over 0-360 deg: [0, 90), [90, 180), [180, 270),
  [270, 360).
- ``dist_bin``: centre distance to the target in 20 equal bins over [0, max_distance) with
  ``max_distance`` = the field diagonal by default (1000 px on 800x600, bin width 50 px): bin k holds
  ``k * max_distance / 20 <= d < (k + 1) * max_distance / 20``; farther distances fall in bin 19.

Continuous features (``features()``, float32, in this order):
``sin(rel), cos(rel), sin(heading), cos(heading), distance / max_distance, own energy / 100,
target energy / 100`` and, with ``include_position``, ``x / width, y / height``.

The target is the nearest living enemy by default (``target="nearest"``) or the living enemy with the
least energy (``target="weakest"``, ties to the nearest). A robot with no living enemy has target -1;
its relative angle and distance are then 0 and 0 (discrete: ahead, bin 0) and target energy is 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

N_REL_BINS = 4
N_HEADING_BINS = 4
N_DIST_BINS = 20
N_STATES = N_REL_BINS * N_HEADING_BINS * N_DIST_BINS  # 320, paper §6.1
TWO_PI = 2.0 * np.pi

TargetRule = Literal["nearest", "weakest"]


@dataclass(frozen=True)
class ObservationConfig:
    """How observations are built: target rule, distance range, optional position features."""

    target: TargetRule = "nearest"
    max_distance: float | None = None  # None = field diagonal
    include_position: bool = False
    reward_guard: float = 1.0  # floor of Eq. 35's denominator

    def __post_init__(self) -> None:
        if self.target not in ("nearest", "weakest"):
            raise ValueError(f"observation.target must be 'nearest' or 'weakest', got {self.target!r}")
        if self.max_distance is not None and not self.max_distance > 0:
            raise ValueError(f"observation.max_distance must be > 0, got {self.max_distance!r}")
        if not self.reward_guard > 0:
            raise ValueError(f"observation.reward_guard must be > 0, got {self.reward_guard!r}")

    @property
    def n_features(self) -> int:
        """Length of the feature vector."""
        return 9 if self.include_position else 7


def normal_absolute_angle(a: np.ndarray) -> np.ndarray:
    """Angle in [0, 2*pi)."""
    # Robocode Utils.normalAbsoluteAngle
    r = np.mod(a, TWO_PI)
    return np.where(r >= TWO_PI, 0.0, r)


def absolute_bearing(x: np.ndarray, y: np.ndarray, tx: np.ndarray, ty: np.ndarray) -> np.ndarray:
    """Absolute bearing from (x, y) to (tx, ty), in [0, 2*pi), 0 = north, clockwise."""
    # Robocode heading convention: x += sin(h), y += cos(h), so bearing = atan2(dx, dy)
    return normal_absolute_angle(np.arctan2(tx - x, ty - y))


def select_targets(
    x: np.ndarray,
    y: np.ndarray,
    energy: np.ndarray,
    alive: np.ndarray,
    team: np.ndarray,
    rule: TargetRule = "nearest",
) -> np.ndarray:
    """Target index of each robot, (B, R) int64: its nearest (or weakest) living enemy, -1 if none.

    ``x, y, energy, alive`` are (B, R); ``team`` is (R,) or (B, R) team ids.
    """
    dx = x[:, None, :] - x[:, :, None]  # (B, R_self, R_other)
    dy = y[:, None, :] - y[:, :, None]
    dist2 = dx * dx + dy * dy
    team_b = np.broadcast_to(team, x.shape)
    enemy = (team_b[:, :, None] != team_b[:, None, :]) & alive[:, None, :]
    if rule == "nearest":
        key = np.where(enemy, dist2, np.inf)
    elif rule == "weakest":
        # least energy first; the distance term (< 1e-9) only breaks ties
        tie = dist2 / (1.0 + dist2.max(initial=0.0)) * 1e-9
        key = np.where(enemy, energy[:, None, :] + tie, np.inf)
    else:
        raise ValueError(f"target rule must be 'nearest' or 'weakest', got {rule!r}")
    tgt = np.argmin(key, axis=2)
    has = np.isfinite(np.take_along_axis(key, tgt[:, :, None], axis=2)[:, :, 0])
    return np.where(has, tgt, -1).astype(np.int64)


def gather_target(values: np.ndarray, target: np.ndarray, fill: float = 0.0) -> np.ndarray:
    """values[b, target[b, r]] as (B, R); ``fill`` where target is -1."""
    safe = np.maximum(target, 0)
    out = np.take_along_axis(values, safe, axis=1)
    return np.where(target >= 0, out, fill)


def relative_geometry(
    x: np.ndarray, y: np.ndarray, heading: np.ndarray, target: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(relative angle in [0, 2*pi), centre distance) from each robot to its target; (0, 0) without one."""
    tx = gather_target(x, target)
    ty = gather_target(y, target)
    has = target >= 0
    tx = np.where(has, tx, x)
    ty = np.where(has, ty, y)
    dist = np.hypot(tx - x, ty - y)
    rel = normal_absolute_angle(absolute_bearing(x, y, tx, ty) - heading)
    rel = np.where(has, rel, 0.0)
    return rel, dist


def angle_bins(angle: np.ndarray, n: int, centred: bool) -> np.ndarray:
    """Bin an angle in [0, 2*pi) into n equal sectors; ``centred`` puts sector 0 around angle 0."""
    width = TWO_PI / n
    a = normal_absolute_angle(angle + (width / 2 if centred else 0.0))
    return np.minimum((a / width).astype(np.int64), n - 1)


def distance_bins(dist: np.ndarray, max_distance: float, n: int = N_DIST_BINS) -> np.ndarray:
    """Equal-width distance bins over [0, max_distance); farther distances go to the last bin."""
    b = np.floor(dist * (n / max_distance)).astype(np.int64)
    return np.clip(b, 0, n - 1)


def state_index(rel_bin: np.ndarray, heading_bin: np.ndarray, dist_bin: np.ndarray) -> np.ndarray:
    """Paper's discrete state 0..319 = (rel_bin * 4 + heading_bin) * 20 + dist_bin."""
    return (rel_bin * N_HEADING_BINS + heading_bin) * N_DIST_BINS + dist_bin


def field_diagonal(width: float, height: float) -> float:
    """Length of the battlefield diagonal."""
    return float(np.hypot(width, height))


def discrete_state(
    x: np.ndarray,
    y: np.ndarray,
    heading: np.ndarray,
    target: np.ndarray,
    max_distance: float,
) -> np.ndarray:
    """Discrete state index (B, R) in 0..319 (paper §6.1: 4 relative-angle x 4 heading x 20 distance bins)."""
    rel, dist = relative_geometry(x, y, heading, target)
    return state_index(
        angle_bins(rel, N_REL_BINS, centred=True),
        angle_bins(normal_absolute_angle(heading), N_HEADING_BINS, centred=False),
        distance_bins(dist, max_distance),
    )


def features(
    x: np.ndarray,
    y: np.ndarray,
    heading: np.ndarray,
    energy: np.ndarray,
    target: np.ndarray,
    max_distance: float,
    field: tuple[float, float] | None = None,
) -> np.ndarray:
    """Continuous features (B, R, F) float32; see the module docstring. ``field`` adds x/W, y/H."""
    rel, dist = relative_geometry(x, y, heading, target)
    cols = [
        np.sin(rel),
        np.cos(rel),
        np.sin(heading),
        np.cos(heading),
        np.minimum(dist / max_distance, 1.0),
        energy / 100.0,
        gather_target(energy, target) / 100.0,
    ]
    if field is not None:
        cols += [x / field[0], y / field[1]]
    return np.stack(cols, axis=-1).astype(np.float32)


def reward_eq35(
    own_prev: np.ndarray,
    own_now: np.ndarray,
    enemy_prev: np.ndarray,
    enemy_now: np.ndarray,
    guard: float = 1.0,
) -> np.ndarray:
    """Per-turn reward of the paper's Eq. 35, denominator floored at ``guard``."""
    # Eq. 35: ((Em_t - Em_t-1) - (Ee_t - Ee_t-1)) * |Ee_t-1 - Ee_t| / max(|Em_t-1 - Ee_t-1|, guard)
    delta = (own_now - own_prev) - (enemy_now - enemy_prev)
    return delta * np.abs(enemy_prev - enemy_now) / np.maximum(np.abs(own_prev - enemy_prev), guard)


def observe(
    x: np.ndarray,
    y: np.ndarray,
    heading: np.ndarray,
    energy: np.ndarray,
    alive: np.ndarray,
    team: np.ndarray,
    field: tuple[float, float],
    config: ObservationConfig,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(target (B, R), discrete state (B, R), features (B, R, F)) for every robot."""
    target = select_targets(x, y, energy, alive, team, config.target)
    dmax = config.max_distance or field_diagonal(*field)
    disc = discrete_state(x, y, heading, target, dmax)
    feats = features(x, y, heading, energy, target, dmax, field if config.include_position else None)
    return target, disc, feats
