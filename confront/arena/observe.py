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

Sensing (``sensing="scanned"``, the default): like a Robocode robot (and the exported PolicyBot), each robot
knows an enemy only from its radar: the position and energy of its last scan this round, forgotten when
that enemy dies (RobotDeathEvent). Before its first scan of a round a robot knows no enemy (target -1).
Targets, state, features and the gun/radar controller all use this picture; ``sensing="true"`` reads
the true state instead. The memory is ``(B, 3, R, R)``: ``memory[b, :, i, j]`` = x, y, energy of robot j
at robot i's last scan of it, valid where ``seen[b, i, j] >= 0`` (the arena's ``scan_time``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numba import njit, vectorize

from .kernel_cache import install
from .rules import java_atan2, java_atan2_ufunc, java_hypot, java_hypot_ufunc
from .tank import M_DROP, M_E, M_H, M_SEEN, M_TIME, M_TURN, M_V, MEMORY_ROWS

N_REL_BINS = 4
N_HEADING_BINS = 4
N_DIST_BINS = 20
N_STATES = N_REL_BINS * N_HEADING_BINS * N_DIST_BINS  # 320, paper §6.1
TWO_PI = 2.0 * np.pi

TargetRule = Literal["nearest", "weakest"]
Sensing = Literal["scanned", "true"]
SENSING: dict[str, int] = {"true": 0, "scanned": 1}


@dataclass(frozen=True)
class ObservationConfig:
    """How observations are built: target rule, distance range, optional position features."""

    target: TargetRule = "nearest"
    max_distance: float | None = None  # None = field diagonal
    include_position: bool = False
    reward_guard: float = 1.0  # floor of Eq. 35's denominator
    sensing: Sensing = "scanned"  # enemies as last scanned (a real robot's knowledge) or their true state

    def __post_init__(self) -> None:
        if self.target not in ("nearest", "weakest"):
            raise ValueError(f"observation.target must be 'nearest' or 'weakest', got {self.target!r}")
        if self.sensing not in SENSING:
            raise ValueError(f"observation.sensing must be 'scanned' or 'true', got {self.sensing!r}")
        if self.max_distance is not None and not self.max_distance > 0:
            raise ValueError(f"observation.max_distance must be > 0, got {self.max_distance!r}")
        if not self.reward_guard > 0:
            raise ValueError(f"observation.reward_guard must be > 0, got {self.reward_guard!r}")

    @property
    def n_features(self) -> int:
        """Length of the feature vector."""
        return 9 if self.include_position else 7


def kernel_array(a: np.ndarray, dtype: type) -> np.ndarray:
    """``a`` as a writable C-contiguous array of ``dtype`` (a copy only when needed): numba compiles a kernel
    once per array type (layout, dtype, read-only flag), so every Python entry point passes this one."""
    a = np.ascontiguousarray(a, dtype=dtype)
    return a if a.flags.writeable else a.copy()


def team_rows(team: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Team ids (R,) or (B, R) as a (B, R) kernel array of the arena's dtype (int32, as the SMDP kernel's)."""
    return np.array(np.broadcast_to(team, shape), dtype=np.int32, order="C")


@njit(cache=True)
def float_mod(a: float, m: float) -> float:
    """a mod m for m > 0 with the sign of m, computed exactly as Python's and NumPy's float % (fmod based)."""
    if 0.0 <= a < m:  # fmod leaves such values unchanged; skip the slow call
        return a
    r = np.fmod(a, m)
    if r < 0:
        r += m
    return r


install(globals())  # before the vectorized ufuncs below compile float_mod at import


@vectorize(["float64(float64)"], cache=True)
def normal_absolute_angle(a: float) -> float:
    """Angle in [0, 2*pi) (a NumPy ufunc; also callable on scalars in compiled code)."""
    # Robocode Utils.normalAbsoluteAngle
    r = float_mod(a, TWO_PI)
    return 0.0 if r >= TWO_PI else r


def absolute_bearing(x: np.ndarray, y: np.ndarray, tx: np.ndarray, ty: np.ndarray) -> np.ndarray:
    """Absolute bearing from (x, y) to (tx, ty), in [0, 2*pi), 0 = north, clockwise."""
    # Robocode heading convention: x += sin(h), y += cos(h), so bearing = atan2(dx, dy)
    return normal_absolute_angle(java_atan2_ufunc(tx - x, ty - y))


TARGET_RULES: dict[str, int] = {"nearest": 0, "weakest": 1}


@njit(cache=True, forceinline=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def target_of(x: np.ndarray, y: np.ndarray, energy: np.ndarray, alive: np.ndarray, team: np.ndarray,
              i: int, rule: int) -> int:
    """Target of robot i among the (R,) rows: nearest living enemy (rule 0), or least energy then nearest
    (rule 1); ties go to the lower index; -1 if no enemy is alive."""
    best, best_e, best_d = -1, np.inf, np.inf
    for j in range(x.shape[0]):
        if team[j] == team[i] or not alive[j]:
            continue
        dx, dy = x[j] - x[i], y[j] - y[i]
        d = dx * dx + dy * dy
        e = energy[j] if rule == 1 else 0.0
        if e < best_e or (e == best_e and d < best_d):
            best, best_e, best_d = j, e, d
    return best


@njit(cache=True)
def _targets_kernel(x, y, energy, alive, team, rule, out):  # noqa: ANN001 - numba kernel
    for b in range(x.shape[0]):
        for i in range(x.shape[1]):
            out[b, i] = target_of(x[b], y[b], energy[b], alive[b], team[b], i, rule)


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
    if rule not in TARGET_RULES:
        raise ValueError(f"target rule must be 'nearest' or 'weakest', got {rule!r}")
    out = np.empty(x.shape, dtype=np.int64)
    _targets_kernel(kernel_array(x, np.float64), kernel_array(y, np.float64), kernel_array(energy, np.float64),
                    kernel_array(alive, np.bool_), team_rows(team, x.shape), TARGET_RULES[rule], out)
    return out


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
    dist = java_hypot_ufunc(tx - x, ty - y)
    rel = normal_absolute_angle(absolute_bearing(x, y, tx, ty) - heading)
    rel = np.where(has, rel, 0.0)
    return rel, dist


@vectorize(["int64(float64, int64, boolean)"], cache=True)
def angle_bin(angle: float, n: int, centred: bool) -> int:
    """Sector of an angle among n equal sectors (ufunc); ``centred`` puts sector 0 around angle 0."""
    width = TWO_PI / n
    a = normal_absolute_angle(angle + (width / 2 if centred else 0.0))
    return min(int(a / width), n - 1)


@vectorize(["int64(float64, float64, int64)"], cache=True)
def distance_bin(dist: float, max_distance: float, n: int) -> int:
    """Equal-width bin of a distance over [0, max_distance) (ufunc); farther goes to the last bin."""
    return min(max(int(np.floor(dist * (n / max_distance))), 0), n - 1)


def angle_bins(angle: np.ndarray, n: int, centred: bool) -> np.ndarray:
    """Bin angles into n equal sectors; ``centred`` puts sector 0 around angle 0."""
    return angle_bin(angle, n, centred)


def distance_bins(dist: np.ndarray, max_distance: float, n: int = N_DIST_BINS) -> np.ndarray:
    """Equal-width distance bins over [0, max_distance); farther distances go to the last bin."""
    return distance_bin(dist, float(max_distance), n)


def state_index(rel_bin: np.ndarray, heading_bin: np.ndarray, dist_bin: np.ndarray) -> np.ndarray:
    """Paper's discrete state 0..319 = (rel_bin * 4 + heading_bin) * 20 + dist_bin."""
    return (rel_bin * N_HEADING_BINS + heading_bin) * N_DIST_BINS + dist_bin


state_index_scalar = njit(cache=True)(state_index)  # the same rule compiled for kernels


def field_diagonal(width: float, height: float) -> float:
    """Length of the battlefield diagonal."""
    return float(java_hypot(float(width), float(height)))


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
    """Per-turn reward of the paper's Eq. 35, denominator floored at ``guard`` (arrays or scalars)."""
    # Eq. 35: ((Em_t - Em_t-1) - (Ee_t - Ee_t-1)) * |Ee_t-1 - Ee_t| / max(|Em_t-1 - Ee_t-1|, guard)
    delta = (own_now - own_prev) - (enemy_now - enemy_prev)
    return delta * np.abs(enemy_prev - enemy_now) / np.maximum(np.abs(own_prev - enemy_prev), guard)


reward_eq35_scalar = njit(cache=True)(reward_eq35)  # the same rule compiled for the SMDP kernel


@njit(cache=True, forceinline=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def remember_scans(scanned: np.ndarray, x: np.ndarray, y: np.ndarray, e: np.ndarray, h: np.ndarray, v: np.ndarray,
                   time: float, memory: np.ndarray) -> None:
    """Store, for one battle, what each robot's radar saw this turn: memory[:, i, j] = (x, y, energy) of j
    where scanned[i, j] (the values of a ScannedRobotEvent: the scan comes after every robot moved). A memory
    of 9 rows (:mod:`confront.arena.tank`) also keeps heading, velocity, the energy drop since i's previous
    scan of j this round, the scanned flag, the turn rate since that scan (within the +-10 deg/turn of
    Rules.MAX_TURN_RATE) and the scan time."""
    n = x.shape[0]
    full = memory.shape[0] >= MEMORY_ROWS
    max_rate = np.pi / 18.0
    for i in range(n):
        for j in range(n):
            if scanned[i, j]:
                if full:
                    seen = memory[M_SEEN, i, j] > 0
                    memory[M_DROP, i, j] = memory[M_E, i, j] - e[j] if seen else 0.0
                    dt = time - memory[M_TIME, i, j]
                    dh = float_mod(h[j] - memory[M_H, i, j] + np.pi, 2 * np.pi) - np.pi
                    memory[M_TURN, i, j] = min(max(dh / dt, -max_rate), max_rate) if seen and dt > 0 else 0.0
                    memory[M_H, i, j] = h[j]
                    memory[M_V, i, j] = v[j]
                    memory[M_SEEN, i, j] = 1.0
                    memory[M_TIME, i, j] = time
                memory[0, i, j] = x[j]
                memory[1, i, j] = y[j]
                memory[2, i, j] = e[j]


@njit(cache=True, forceinline=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def perceive_row(x: np.ndarray, y: np.ndarray, e: np.ndarray, alive: np.ndarray, team: np.ndarray, i: int,
                 memory: np.ndarray, seen: np.ndarray, sensing: int, vx: np.ndarray, vy: np.ndarray,
                 ve: np.ndarray, va: np.ndarray) -> None:
    """Robot i's picture of one battle's (R,) robots into vx, vy, ve, va: itself and team-mates as they are;
    an enemy (sensing 1) at its last scanned position and energy, known while alive and scanned this round
    (PolicyBot's map of ScannedRobotEvents, emptied each round, entry removed on RobotDeathEvent);
    with sensing 0 every robot as it is. ``memory`` (3, R, R) and ``seen`` (R, R) are the battle's."""
    for j in range(x.shape[0]):
        if sensing == 0 or j == i or team[j] == team[i]:
            vx[j], vy[j], ve[j], va[j] = x[j], y[j], e[j], alive[j]
        else:
            vx[j], vy[j], ve[j] = memory[0, i, j], memory[1, i, j], memory[2, i, j]
            va[j] = alive[j] and seen[i, j] >= 0


@njit(cache=True)
def _perceive_kernel(x, y, e, alive, team, memory, seen, sensing, vx, vy, ve, va):  # noqa: ANN001 - numba kernel
    for b in range(x.shape[0]):
        for i in range(x.shape[1]):
            perceive_row(x[b], y[b], e[b], alive[b], team[b], i, memory[b], seen[b], sensing,
                         vx[b, i], vy[b, i], ve[b, i], va[b, i])


def perceive(x: np.ndarray, y: np.ndarray, energy: np.ndarray, alive: np.ndarray, team: np.ndarray,
             memory: np.ndarray | None, seen: np.ndarray | None,
             sensing: Sensing = "scanned") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, energy, alive) of every robot as each robot knows it, (B, R, R) each: ``[b, i, j]`` is robot
    j in robot i's picture (see :func:`perceive_row`). ``memory`` (B, 3, R, R) / ``seen`` (B, R, R) may be
    None only with ``sensing="true"``."""
    if sensing not in SENSING:
        raise ValueError(f"sensing must be 'scanned' or 'true', got {sensing!r}")
    b, r = x.shape
    if memory is None or seen is None:
        if sensing != "true":
            raise ValueError("sensing='scanned' needs the scan memory and the scan times")
        memory, seen = np.zeros((b, 3, r, r)), np.zeros((b, r, r), dtype=np.int32)
    out = tuple(np.empty((b, r, r)) for _ in range(3)) + (np.empty((b, r, r), dtype=np.bool_),)
    _perceive_kernel(kernel_array(x, np.float64), kernel_array(y, np.float64), kernel_array(energy, np.float64),
                     kernel_array(alive, np.bool_), team_rows(team, x.shape), kernel_array(memory, np.float64),
                     kernel_array(seen, np.int32), SENSING[sensing], *out)
    return out  # type: ignore[return-value]


@njit(cache=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def robot_observation(x: np.ndarray, y: np.ndarray, h: np.ndarray, e: np.ndarray, i: int, tgt: int,
                      max_distance: float, width: float, height: float, feat: np.ndarray) -> int:
    """Discrete state of robot i toward robot tgt (-1: none) from (R,) rows; writes its features in ``feat``
    (x/W, y/H too when ``feat`` has 9 entries). The same rules as discrete_state() and features()."""
    if tgt >= 0:
        dx, dy = x[tgt] - x[i], y[tgt] - y[i]
        dist = java_hypot(dx, dy)
        rel = normal_absolute_angle(normal_absolute_angle(java_atan2(dx, dy)) - h[i])
        te = e[tgt]
    else:
        dist, rel, te = 0.0, 0.0, 0.0
    feat[0] = np.sin(rel)
    feat[1] = np.cos(rel)
    feat[2] = np.sin(h[i])
    feat[3] = np.cos(h[i])
    feat[4] = min(dist / max_distance, 1.0)
    feat[5] = e[i] / 100.0
    feat[6] = te / 100.0
    if feat.shape[0] > 7:
        feat[7] = x[i] / width
        feat[8] = y[i] / height
    return int(state_index_scalar(angle_bin(rel, N_REL_BINS, True),
                                  angle_bin(normal_absolute_angle(h[i]), N_HEADING_BINS, False),
                                  distance_bin(dist, max_distance, N_DIST_BINS)))


@njit(cache=True)
def observe_kernel(x: np.ndarray, y: np.ndarray, h: np.ndarray, e: np.ndarray, alive: np.ndarray,
                   team: np.ndarray, memory: np.ndarray, seen: np.ndarray, sensing: int, rule: int,
                   max_distance: float, width: float, height: float,
                   target: np.ndarray, disc: np.ndarray, feats: np.ndarray) -> None:
    """Targets, discrete states and features of every robot of (B, R) arrays, each from its own picture
    (:func:`perceive_row`), into the outputs."""
    n = x.shape[1]
    row = np.zeros(feats.shape[2])
    vx, vy, ve, va = np.empty(n), np.empty(n), np.empty(n), np.empty(n, dtype=np.bool_)
    for b in range(x.shape[0]):
        for i in range(n):
            perceive_row(x[b], y[b], e[b], alive[b], team[b], i, memory[b], seen[b], sensing, vx, vy, ve, va)
            tg = target_of(vx, vy, ve, va, team[b], i, rule)
            target[b, i] = tg
            disc[b, i] = robot_observation(vx, vy, h[b], ve, i, tg, max_distance, width, height, row)
            for k in range(row.shape[0]):
                feats[b, i, k] = row[k]


def observe(
    x: np.ndarray,
    y: np.ndarray,
    heading: np.ndarray,
    energy: np.ndarray,
    alive: np.ndarray,
    team: np.ndarray,
    field: tuple[float, float],
    config: ObservationConfig,
    memory: np.ndarray | None = None,
    seen: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(target (B, R), discrete state (B, R), features (B, R, F)) for every robot (compiled).

    With the scan ``memory`` (B, 3, R, R) and ``seen`` (B, R, R) times, each robot sees enemies as
    ``config.sensing`` says; without them every robot sees the true state."""
    dmax = config.max_distance or field_diagonal(*field)
    b, r = x.shape
    target = np.empty(x.shape, dtype=np.int64)
    disc = np.empty(x.shape, dtype=np.int64)
    feats = np.empty(x.shape + (config.n_features,), dtype=np.float32)
    sensing = SENSING[config.sensing] if memory is not None and seen is not None else 0
    if memory is None or seen is None:
        memory, seen = np.zeros((b, 3, r, r)), np.zeros((b, r, r), dtype=np.int32)
    x, y, heading, energy, memory = (kernel_array(a, np.float64) for a in (x, y, heading, energy, memory))
    observe_kernel(x, y, heading, energy, kernel_array(alive, np.bool_), team_rows(team, x.shape), memory,
                   kernel_array(seen, np.int32), sensing, TARGET_RULES[config.target], float(dmax), float(field[0]),
                   float(field[1]), target, disc, feats)
    return target, disc, feats


install(globals())
