"""What a learning tank knows and chooses beyond the paper's model: the *tank view* and the *tank actions*.

Angles follow Robocode: radians, 0 = north (+y), clockwise; x right, y up; distances in px, time in turns.

Tank view (float32, ``n_features(K, M) = 11 + 9 K + 5 M`` (+ 8 with ``knowledge``); 62 with K = 4 enemy slots,
M = 3 mate slots),
everything a real robot can know (its own getters, its radar's ScannedRobotEvents, team messages):

| index | feature | scale |
|---|---|---|
| 0-3 | distance to the left, bottom, right, top wall: x/W, y/H, (W-x)/W, (H-y)/H | [0, 1] |
| 4-5 | sin, cos of the own heading | [-1, 1] |
| 6 | own velocity / 8 | [-1, 1] |
| 7 | own energy / 100 | [0, ~2] |
| 8 | gun heat / 3 (3.0 at a round's start) | [0, 1] |
| 9 | enemies alive / enemies at the start | [0, 1] |
| 10 | team-mates alive / team-mates at the start (0 without team-mates) | [0, 1] |
| per enemy slot k (9 each): | the k-th nearest enemy known from a scan this round, nearest first | |
| +0 | 1 when the slot holds an enemy (all nine 0 otherwise) | {0, 1} |
| +1, +2 | sin, cos of its bearing from the own heading, from its last scanned position | [-1, 1] |
| +3 | distance to that position / field diagonal | [0, 1] |
| +4 | its lateral velocity at the scan, v sin(h_e - bearing) / 8 (+ = clockwise around us) | [-1, 1] |
| +5 | its advancing velocity, v cos(h_e - bearing) / 8 (+ = away from us) | [-1, 1] |
| +6 | its energy at the scan / 100 | [0, ~2] |
| +7 | age of the scan, min(turns since, 50) / 50 | [0, 1] |
| +8 | its energy drop between its last two scans, clip(drop, 0, 3) / 3 (it fired a bullet of that power) | [0, 1] |
| per mate slot m (5 each): | the m-th nearest living team-mate, as its last message said (one turn ago) | |
| +0 | 1 when the slot holds a team-mate | {0, 1} |
| +1, +2 | sin, cos of its bearing from the own heading | [-1, 1] |
| +3 | distance / field diagonal | [0, 1] |
| +4 | its energy / 100 | [0, ~2] |
| knowledge (8, with ``knowledge``): | what the tank's technique brain (below) knows, as of its last turn | |
| +0-3 | rolling hit rates of the brain's virtual guns: head-on, linear, circular, GuessFactor (battle) | [0, 1] |
| +4 | enemy waves in the air (the enemy's detected shots at us, 1v1): min(n, 4) / 4 | [0, 1] |
| +5 | turns until the nearest of them reaches us, min(t, 50) / 50 (1 without one) | [0, 1] |
| +6 | share of the visits in the GuessFactor bin of its last aim this round (0 before one): how peaked | [0, 1] |
| +7 | share of the surfing danger (where its bullets hit us, battle memory) in its peak bin | [0, 1] |

A team-mate is known from its team messages, which arrive the turn after they are sent: its x, y and energy
one turn ago, and none in a round's first turn. Nothing names an opponent. The slot map ``slots`` (B, R, K)
keeps which robot fills each enemy slot, so the action's target slot can be resolved to a robot.

Tank actions: five heads, one joint integer ``(((d * n_turns + t) * n_fire + f) * K + k) * n_leads + l``
(``np.ravel_multi_index`` over ``TankSpace.dims``): a move distance
(px, + ahead) and a body turn set once at the start of the T-turn step (``turn_mode="target"``: the turn
that puts the body at that angle (rad, + clockwise) to the target's bearing, so 0 faces it and +-90 deg
circles it; ``"body"`` or no known target: a turn by that angle), a fire power
(0 = hold fire), the enemy slot to target, and the gun's lead (none: at the last scanned position; linear;
circular: with the turn rate between scans; gf: the brain's GuessFactor aim, below). The fixed gun/radar controller
(paper §6.1) then aims at that target every turn (``lead_point``) and fires with the chosen power when the gun is on
target and cold.

Skills (opt-in; all off: the tank of before, bit for bit). A tank with any of them carries a *technique brain*:
the decision code of the technique robot SurfGF (:mod:`confront.arena.tech`, Java ``confront.tech.TechBrain``), run
for the tank every turn on the tank's own events, its commands proposed, not sent. Its memory is a technique
robot's: per round (enemy waves, gun waves) and per battle of ``rounds_per_battle`` rounds (GuessFactor visit
counts, where enemy bullets hit us, virtual-gun hit rates), cleared when a new battle starts. The tank's radar
controller drives the radar (the brain's radar command is dropped; the brain sees the scans the tank's radar
makes).

| option | what | encoding |
|---|---|---|
| ``leads`` with ``"gf"`` | the gun turns to the brain's GuessFactor angle for the target (its bin's factor x the \
escape angle of the step's bullet power, 2 when none) when the brain aimed at that target this turn; else circular \
| a lead head value |
| ``surf = True`` | during the step the body follows the brain's movement every turn (wave surfing in 1v1, minimum \
risk with more enemies); the turn head is ignored | an extra last entry of the distance head (distance 0) |
| ``knowledge = True`` | the knowledge block above at the end of the tank view | 8 more features |

Scan memory rows (``memory`` (B, MEMORY_ROWS, R, R), ``[b, :, i, j]`` = robot j at robot i's last scan of
it): x, y, energy, heading, velocity, energy drop since the previous scan, 1 when scanned this round, its
turn rate between the last two scans (rad/turn, within +-10 deg), the scan's time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numba import njit

from .kernel_cache import install
from .rules import java_atan2, java_hypot

__all__ = ["TankSpace", "MEMORY_ROWS", "n_features", "tank_view_row", "tank_view_kernel", "lead_point",
           "action_table", "FEATURE_NAMES", "KNOWLEDGE_FEATURES", "LEADS"]

MEMORY_ROWS = 9  # x, y, energy, heading, velocity, energy drop, scanned this round, turn rate, scan time
M_X, M_Y, M_E, M_H, M_V, M_DROP, M_SEEN, M_TURN, M_TIME = range(MEMORY_ROWS)
OWN_FEATURES = 11
ENEMY_FEATURES = 9
MATE_FEATURES = 5
MAX_AGE = 50.0  # turns: older scans read as 1
WALL_MARGIN = 18.0  # half a robot: a tank's centre never gets closer to a wall (Robocode's 36 px body)
LEADS = {"none": 0, "linear": 1, "circular": 2, "gf": 3}
# the technique robots (confront.arena.tech) a tank's skills may run as its brain: wave surfers, with the GuessFactor
# gun, or with it and the anti-surfer gun beside it (the one that hits more aims)
BRAINS = ("SurfGF", "SurfAS")
LEAD_GF = LEADS["gf"]
KNOWLEDGE_FEATURES = 8  # the knowledge block (tech.knowledge_row)
KNOWLEDGE_NAMES = ("vg_head", "vg_linear", "vg_circular", "vg_gf", "waves", "wave_impact", "gf_peak", "surf_peak")


def n_features(k: int, m: int, knowledge: bool = False) -> int:
    """Length of the tank view with k enemy slots and m mate slots (and the knowledge block)."""
    return OWN_FEATURES + ENEMY_FEATURES * k + MATE_FEATURES * m + (KNOWLEDGE_FEATURES if knowledge else 0)


def feature_names(k: int, m: int, knowledge: bool = False) -> list[str]:
    """Names of the tank view's entries, in order."""
    names = ["wall_left", "wall_bottom", "wall_right", "wall_top", "sin_heading", "cos_heading", "velocity",
             "energy", "gun_heat", "enemies_alive", "mates_alive"]
    for s in range(k):
        names += [f"enemy{s}_{n}" for n in ("present", "sin_bearing", "cos_bearing", "distance", "lateral",
                                             "advancing", "energy", "age", "drop")]
    for s in range(m):
        names += [f"mate{s}_{n}" for n in ("present", "sin_bearing", "cos_bearing", "distance", "energy")]
    return names + [f"know_{n}" for n in KNOWLEDGE_NAMES] if knowledge else names


FEATURE_NAMES = feature_names(4, 3)


@dataclass(frozen=True)
class TankSpace:
    """The tank actions' values and the tank view's slots."""

    distances: tuple[float, ...] = (-150.0, -50.0, 0.0, 50.0, 150.0)  # px, + ahead
    turns_deg: tuple[float, ...] = (-90.0, -45.0, 0.0, 45.0, 90.0)  # + clockwise, see turn_mode
    turn_mode: Literal["target", "body"] = "target"  # the body ends at this angle to the target's bearing,
    # or turns by it (also "target" mode without a known target)
    fire_powers: tuple[float, ...] = (0.0, 1.0, 2.0, 3.0)  # 0 = hold fire
    enemy_slots: int = 4  # K
    mate_slots: int = 3  # M
    leads: tuple[str, ...] = ("none", "circular")  # the lead head's choices, of LEADS
    surf: bool = False  # the distance head's extra last entry: the body follows the brain's movement (skills)
    knowledge: bool = False  # the knowledge block at the end of the view (skills)
    brain: str = "SurfGF"  # the technique robot of BRAINS whose decisions the skills follow

    def __post_init__(self) -> None:
        for name in ("distances", "turns_deg", "fire_powers"):
            v = getattr(self, name)
            if not v or not all(isinstance(x, int | float) and math.isfinite(x) for x in v):
                raise ValueError(f"tank.{name} must be a non-empty list of finite numbers, got {v!r}")
        if any(not (p == 0 or 0.1 <= p <= 3.0) for p in self.fire_powers):
            raise ValueError(f"tank.fire_powers must be 0 (hold) or in [0.1, 3], got {self.fire_powers!r}")
        if any(abs(d) > 1000 for d in self.distances) or any(abs(t) > 360 for t in self.turns_deg):
            raise ValueError("tank.distances must be within +-1000 px and tank.turns_deg within +-360")
        if not isinstance(self.enemy_slots, int) or not 1 <= self.enemy_slots <= 16:
            raise ValueError(f"tank.enemy_slots must be an integer in 1..16, got {self.enemy_slots!r}")
        if not isinstance(self.mate_slots, int) or not 0 <= self.mate_slots <= 16:
            raise ValueError(f"tank.mate_slots must be an integer in 0..16, got {self.mate_slots!r}")
        if self.turn_mode not in ("target", "body"):
            raise ValueError(f"tank.turn_mode must be 'target' or 'body', got {self.turn_mode!r}")
        if not self.leads or any(v not in LEADS for v in self.leads):
            raise ValueError(f"tank.leads must be a non-empty list of {', '.join(LEADS)}, got {self.leads!r}")
        for name in ("surf", "knowledge"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"tank.{name} must be true or false, got {getattr(self, name)!r}")
        if self.brain not in BRAINS:
            raise ValueError(f"tank.brain must be one of {', '.join(BRAINS)}, got {self.brain!r}")

    @property
    def skills(self) -> bool:
        """True when the tank carries a technique brain (a gf lead, surf or knowledge)."""
        return self.surf or self.knowledge or "gf" in self.leads

    @property
    def dims(self) -> tuple[int, int, int, int, int]:
        """Sizes of the five action heads: distance (+ surf), turn, fire, target slot, lead."""
        return (len(self.distances) + int(self.surf), len(self.turns_deg), len(self.fire_powers), self.enemy_slots,
                len(self.leads))

    @property
    def n_actions(self) -> int:
        """Joint actions."""
        return int(np.prod(self.dims))

    @property
    def n_features(self) -> int:
        """Tank view length."""
        return n_features(self.enemy_slots, self.mate_slots, self.knowledge)


def action_table(space: TankSpace) -> np.ndarray:
    """(n_actions, 7) rows of (distance, body turn, fire power (-1 = hold), target slot, 1 when the turn is
    relative to the target's bearing, the gun's lead (LEADS), 1 when the body surfs (distance 0)) per joint
    action."""
    d, t, f, k, lead = np.unravel_index(np.arange(space.n_actions), space.dims)
    power = np.asarray(space.fire_powers, dtype=np.float64)[f]
    surf = d >= len(space.distances)
    return np.stack([np.asarray(space.distances + (0.0,), dtype=np.float64)[d],
                     np.radians(np.asarray(space.turns_deg, dtype=np.float64))[t],
                     np.where(power > 0, power, -1.0), k.astype(np.float64),
                     np.full(d.size, 1.0 if space.turn_mode == "target" else 0.0),
                     np.array([float(LEADS[v]) for v in space.leads])[lead], surf.astype(np.float64)], axis=1)


@njit(cache=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def lead_point(x: float, y: float, mx: float, my: float, mh: float, mv: float, rate: float, age: float,
               power: float, width: float, height: float) -> tuple[float, float]:
    """Where to aim at an enemy last scanned at (mx, my) heading mh at velocity mv ``age`` turns ago, turning
    ``rate`` rad/turn (0 = linear lead): it keeps speed and turn rate while our bullet of ``power`` flies
    (speed 20 - 3 p, Rules.getBulletSpeed), on a circle (x += v/w (cos h0 - cos(h0 + w t)), y += v/w
    (sin(h0 + w t) - sin h0), Robocode's heading clockwise from north); clipped to where a robot's centre can
    be; 10 fixed-point iterations."""
    speed = 20.0 - 3.0 * power
    px, py, t = mx, my, 0.0
    sh, ch = np.sin(mh), np.cos(mh)
    linear = abs(rate) < 1e-9
    for _ in range(10):
        tau = age + t
        if linear:
            ox, oy = sh * mv * tau, ch * mv * tau
        else:
            a = mh + rate * tau
            ox = mv / rate * (ch - np.cos(a))
            oy = mv / rate * (np.sin(a) - sh)
        px = min(max(mx + ox, WALL_MARGIN), width - WALL_MARGIN)
        py = min(max(my + oy, WALL_MARGIN), height - WALL_MARGIN)
        t_new = java_hypot(px - x, py - y) / speed
        if t_new == t:  # a fixed point: every further iteration gives the same point
            break
        t = t_new
    return px, py


@njit(cache=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def tank_view_row(x: np.ndarray, y: np.ndarray, h: np.ndarray, v: np.ndarray, e: np.ndarray, heat: np.ndarray,
                  alive: np.ndarray, team: np.ndarray, i: int, memory: np.ndarray, seen: np.ndarray, time: float,
                  width: float, height: float, k_slots: int, m_slots: int, mates: np.ndarray, mates_ok: bool,
                  out: np.ndarray, slots: np.ndarray, dist: np.ndarray) -> None:
    """Robot i's tank view of one battle's (R,) robots into ``out`` (F,), its enemy slots into ``slots`` (K,);
    ``dist`` (R,) is scratch.

    An enemy is known while alive and scanned this round (``seen[i, j] >= 0``), at ``memory[:, i, j]``
    (MEMORY_ROWS, R, R); a living team-mate at ``mates[:, j]`` (3, R): x, y, energy one turn ago (a team
    message arrives the turn after it is sent), none when not ``mates_ok`` (a round's first turn). Slots are
    filled nearest first (ties: lower index)."""
    n = x.shape[0]
    diag = java_hypot(width, height)
    for q in range(out.shape[0]):
        out[q] = 0.0
    for q in range(k_slots):
        slots[q] = -1
    out[0] = x[i] / width
    out[1] = y[i] / height
    out[2] = (width - x[i]) / width
    out[3] = (height - y[i]) / height
    out[4] = np.sin(h[i])
    out[5] = np.cos(h[i])
    out[6] = v[i] / 8.0
    out[7] = e[i] / 100.0
    out[8] = heat[i] / 3.0
    n_en, n_en_alive, n_mate, n_mate_alive = 0, 0, 0, 0
    for j in range(n):
        if j == i:
            continue
        if team[j] == team[i]:
            n_mate += 1
            n_mate_alive += 1 if alive[j] else 0
        else:
            n_en += 1
            n_en_alive += 1 if alive[j] else 0
    out[9] = n_en_alive / n_en if n_en > 0 else 0.0
    out[10] = n_mate_alive / n_mate if n_mate > 0 else 0.0
    # enemies: selection by distance to the remembered position (k_slots smallest, ties to the lower index)
    # (each distance computed once; a chosen or ineligible robot's is inf)
    for j in range(n):
        if team[j] == team[i] or not alive[j] or seen[i, j] < 0:
            dist[j] = np.inf
        else:
            dist[j] = java_hypot(memory[M_X, i, j] - x[i], memory[M_Y, i, j] - y[i])
    for s in range(k_slots):
        best, best_d = -1, np.inf
        for j in range(n):
            if dist[j] < best_d:
                best, best_d = j, dist[j]
        if best < 0:
            break
        dist[best] = np.inf
        slots[s] = best
        o = OWN_FEATURES + ENEMY_FEATURES * s
        bearing = java_atan2(memory[M_X, i, best] - x[i], memory[M_Y, i, best] - y[i])
        rel = bearing - h[i]
        rel_h = memory[M_H, i, best] - bearing
        out[o] = 1.0
        out[o + 1] = np.sin(rel)
        out[o + 2] = np.cos(rel)
        out[o + 3] = min(best_d / diag, 1.0)
        out[o + 4] = memory[M_V, i, best] * np.sin(rel_h) / 8.0
        out[o + 5] = memory[M_V, i, best] * np.cos(rel_h) / 8.0
        out[o + 6] = memory[M_E, i, best] / 100.0
        out[o + 7] = min(time - seen[i, best], MAX_AGE) / MAX_AGE
        out[o + 8] = min(max(memory[M_DROP, i, best], 0.0), 3.0) / 3.0
    # team-mates: as their last team messages said
    m_used = m_slots if mates_ok else 0
    if m_used > 0:
        for j in range(n):
            if j == i or team[j] != team[i] or not alive[j]:
                dist[j] = np.inf
            else:
                dist[j] = java_hypot(mates[0, j] - x[i], mates[1, j] - y[i])
    for s in range(m_used):
        best, best_d = -1, np.inf
        for j in range(n):
            if dist[j] < best_d:
                best, best_d = j, dist[j]
        if best < 0:
            break
        dist[best] = np.inf
        o = OWN_FEATURES + ENEMY_FEATURES * k_slots + MATE_FEATURES * s
        rel = java_atan2(mates[0, best] - x[i], mates[1, best] - y[i]) - h[i]
        out[o] = 1.0
        out[o + 1] = np.sin(rel)
        out[o + 2] = np.cos(rel)
        out[o + 3] = min(best_d / diag, 1.0)
        out[o + 4] = mates[2, best] / 100.0


@njit(cache=True)
def tank_view_kernel(x: np.ndarray, y: np.ndarray, h: np.ndarray, v: np.ndarray, e: np.ndarray,
                     heat: np.ndarray, alive: np.ndarray, team: np.ndarray, memory: np.ndarray, seen: np.ndarray,
                     time: np.ndarray, width: float, height: float, k_slots: int, m_slots: int, mates: np.ndarray,
                     mates_ok: np.ndarray, feats: np.ndarray, slots: np.ndarray) -> None:
    """Tank views (B, R, F) and enemy slot maps (B, R, K) of every robot of (B, R) arrays; ``mates`` (B, 3, R)
    and ``mates_ok`` (B,) as in :func:`tank_view_row`."""
    row, dist = np.zeros(feats.shape[2]), np.empty(x.shape[1])
    for b in range(x.shape[0]):
        for i in range(x.shape[1]):
            tank_view_row(x[b], y[b], h[b], v[b], e[b], heat[b], alive[b], team[b], i, memory[b], seen[b],
                          float(time[b]), width, height, k_slots, m_slots, mates[b], mates_ok[b], row, slots[b, i],
                          dist)
            for q in range(row.shape[0]):
                feats[b, i, q] = row[q]


install(globals())
