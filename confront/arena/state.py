"""Structure-of-arrays state of many independent battles (battle axis first).

``ArenaState`` holds a few packed arrays (one per dtype and shape kind, fields on axis 1) and a
named view for every field (:data:`FIELDS`). Shape kinds: ``B`` (battles), ``BR`` (battles x
robots), ``BRR`` (robot x robot), ``BRS`` (robot x 6 score parts), ``BRP`` (robot x 3 placements),
``BK`` (bullet slots).
The full list with meanings is in :mod:`confront.arena.core`'s docstring.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .scenarios import Scenario

__all__ = ["FIELDS", "GROUPS", "SINGLES", "ArenaState", "allocate", "bullet_capacity", "SCORE_PARTS", "N_SCORE",
           "Robots", "Battles", "Bullets", "Radar", "Scores"]

SCORE_PARTS = ("survival", "last_survivor", "bullet_damage", "bullet_kill_bonus", "ram_damage", "ram_kill_bonus")
N_SCORE = len(SCORE_PARTS)

# bullet states (BulletState): 0 = no bullet in this slot
B_NONE, B_FIRED, B_MOVING, B_HIT_VICTIM, B_HIT_BULLET, B_HIT_WALL, B_EXPLODED = 0, 1, 2, 3, 4, 5, 6

# Packed groups: every field is a view into one array per group, shape (B, n_fields, ...) so that the
# kernel takes few arguments and each battle's data is contiguous. Index constants are the positions.
RF_FIELDS: tuple[str, ...] = ("x", "y", "heading", "gun_heading", "radar_heading", "velocity", "energy", "gun_heat",
             "box_x", "box_y", "distance_remaining", "body_turn_remaining", "gun_turn_remaining",
             "radar_turn_remaining", "max_velocity", "max_turn_rate", "fire_assist",
             "ev_hit_wall_bearing", "ev_hit_robot_bearing", "ev_hit_by_bullet_bearing", "ev_hit_by_bullet_heading")
# every HitRobotEvent of the last turn in the engine's order (one per collision, RobotPeer.checkRobotCollision):
# the count, then per slot the other robot, the bearing, the at-fault flag (1.0 / 0.0) and the other's energy
# just after the hit; the single ev_hit_robot* fields keep the last one
HIT_ROBOT_SLOTS = 4
RF_FIELDS += ("ev_hit_robots",) + tuple(f"ev_hit_robot_{k}_{f}" for k in range(HIT_ROBOT_SLOTS)
                                        for f in ("robot", "bearing", "fault", "energy"))
# every HitByBulletEvent of the last turn in the engine's bullet order (one per bullet, BulletPeer.checkRobotCollision):
# the count (at most HIT_BY_BULLET_SLOTS; ev_hit_by_bullet counts them all), then per slot the event's bearing and the
# bullet's own heading; ev_hit_by_bullet_bearing / _heading keep the last one
HIT_BY_BULLET_SLOTS = 4
RF_FIELDS += ("ev_hit_by_bullets",) + tuple(f"ev_hit_by_bullet_{k}_{f}" for k in range(HIT_BY_BULLET_SLOTS)
                                            for f in ("bearing", "heading"))
RB_FIELDS = ("alive", "overdriving", "in_collision", "turned_radar_with_gun", "winner", "is_advanced",
             "is_leader", "is_droid", "adjust_gun_for_body", "adjust_radar_for_body", "adjust_radar_for_gun",
             "ev_hit_wall", "ev_at_fault", "ev_fired", "ev_died", "scan_request")
RI_FIELDS = ("team", "ev_hit_robot", "ev_hit_by_bullet", "ev_bullet_hit", "ev_bullet_missed")
BI_FIELDS = ("rng", "time", "round", "inactive_turns", "end_timer", "n_bullets")
BF_FIELDS = ("inactivity_energy",)
BB_FIELDS = ("decided", "done")
KF_FIELDS = ("b_x", "b_y", "b_last_x", "b_last_y", "b_heading", "b_power", "b_vx", "b_vy")
KI_FIELDS = ("b_owner", "b_victim", "b_state", "b_frame", "b_list", "b_has_line")

# group: (fields, shape kind, dtype)
GROUPS: dict[str, tuple[tuple[str, ...], str, type]] = {
    "rf": (RF_FIELDS, "BR", np.float64),
    "rb": (RB_FIELDS, "BR", np.bool_),
    "ri": (RI_FIELDS, "BR", np.int32),
    "bi": (BI_FIELDS, "B", np.int64),
    "bf": (BF_FIELDS, "B", np.float64),
    "bb": (BB_FIELDS, "B", np.bool_),
    "kf": (KF_FIELDS, "BK", np.float64),
    "ki": (KI_FIELDS, "BK", np.int32),
}
# single arrays: name -> (shape kind, dtype)
SINGLES: dict[str, tuple[str, type]] = {
    "scanned": ("BRR", np.bool_),
    "scan_time": ("BRR", np.int32),
    "scan_order": ("BRR", np.int32),
    "damage_ledger": ("BRR", np.float64),
    "score": ("BRS", np.float64),
    "score_total": ("BRS", np.float64),
    "placements": ("BRP", np.int32),
    "placements_total": ("BRP", np.int32),
}
DEFAULTS: dict[str, float] = {
    "max_velocity": 8.0, "max_turn_rate": math.radians(10.0), "fire_assist": math.nan, "is_advanced": True,
    "ev_hit_robot": -1, "box_x": math.nan, "box_y": math.nan, "scan_time": -1, "b_owner": -1, "b_victim": -1,
}
FIELDS: tuple[str, ...] = tuple(f for g in GROUPS.values() for f in g[0]) + tuple(SINGLES)


class Robots(NamedTuple):
    """The per-robot groups (B, fields, R), fields in RF_FIELDS / RB_FIELDS / RI_FIELDS order: the kernels' robots."""

    f: np.ndarray  # float64
    b: np.ndarray  # bool
    i: np.ndarray  # int32


class Battles(NamedTuple):
    """The per-battle groups (B, fields), in BI_FIELDS (the java.util.Random state first) / BF_FIELDS / BB_FIELDS
    order."""

    i: np.ndarray  # int64
    f: np.ndarray  # float64
    b: np.ndarray  # bool


class Bullets(NamedTuple):
    """The bullet list (B, fields, K), in KF_FIELDS / KI_FIELDS order."""

    f: np.ndarray  # float64
    i: np.ndarray  # int32


class Radar(NamedTuple):
    """Robot x robot scan arrays (B, R, R): this turn's scans, the turn of each last scan, each scanner's list order."""

    scanned: np.ndarray
    scan_time: np.ndarray
    scan_order: np.ndarray


class Scores(NamedTuple):
    """This round's score parts and their totals (B, R, 6), placements (B, R, 3), the damage ledger (B, R, R)."""

    score: np.ndarray
    score_total: np.ndarray
    placements: np.ndarray
    placements_total: np.ndarray
    ledger: np.ndarray


def bullet_capacity(scenario: Scenario) -> int:
    """Bullet-list slots per battle: flying bullets, explosions and death explosions of all robots.

    A robot can have at most diag*cooling/17.6 + 1 bullets in flight (17.6 = min over power of
    speed x heat per shot), plus one bullet explosion (17 turns) per shot and one death explosion.
    """
    diag = math.hypot(scenario.width, scenario.height)
    flying = math.ceil(diag * scenario.gun_cooling_rate / 17.6) + 1
    exploding = math.ceil(17 * scenario.gun_cooling_rate) + 1
    return scenario.n_robots * (flying + exploding + 2) + 4


@dataclass
class ArenaState:
    """All arrays of a batch of battles: ``packed`` group arrays and named views into them.

    Attribute access (``state.x``) returns the named array, a view of shape ``(B, R)`` etc.
    """

    packed: dict[str, np.ndarray]
    arrays: dict[str, np.ndarray]

    def __getattr__(self, name: str) -> np.ndarray:
        try:
            return self.__dict__["arrays"][name]
        except KeyError:
            raise AttributeError(name) from None

    @property
    def n_battles(self) -> int:
        return int(self.arrays["x"].shape[0])

    @property
    def n_robots(self) -> int:
        return int(self.arrays["x"].shape[1])

    @property
    def n_bullet_slots(self) -> int:
        return int(self.arrays["b_x"].shape[1])

    def bundles(self) -> tuple[Robots, Battles, Bullets, Radar, Scores]:
        """The packed arrays as the kernels take them (views: the kernels write the state)."""
        p = self.packed
        return (Robots(p["rf"], p["rb"], p["ri"]), Battles(p["bi"], p["bf"], p["bb"]), Bullets(p["kf"], p["ki"]),
                Radar(p["scanned"], p["scan_time"], p["scan_order"]),
                Scores(p["score"], p["score_total"], p["placements"], p["placements_total"], p["damage_ledger"]))


def allocate(scenario: Scenario, n_battles: int) -> ArenaState:
    """Fresh arrays for ``n_battles`` battles of ``scenario`` (robot flags filled in)."""
    if n_battles < 1:
        raise ValueError(f"n_battles must be >= 1, got {n_battles}")
    b, r, k = n_battles, scenario.n_robots, bullet_capacity(scenario)
    tail = {"B": (), "BR": (r,), "BK": (k,), "BRR": (r, r), "BRS": (r, N_SCORE), "BRP": (r, 3)}
    packed: dict[str, np.ndarray] = {}
    arrays: dict[str, np.ndarray] = {}
    for gname, (names, kind, dt) in GROUPS.items():
        arr: np.ndarray = np.zeros((b, len(names)) + tail[kind], dtype=dt)
        packed[gname] = arr
        for i, name in enumerate(names):
            arrays[name] = arr[:, i]
    for name, (kind, dt) in SINGLES.items():
        arr = np.zeros((b,) + tail[kind], dtype=dt)
        packed[name] = arr
        arrays[name] = arr
    for name, v in DEFAULTS.items():
        arrays[name][...] = v
    arrays["scan_order"][...] = np.arange(r, dtype=np.int32)  # index order until a scanner's list is drawn
    teams = np.asarray(scenario.team_ids(), dtype=np.int32)
    arrays["team"][:] = teams
    arrays["is_advanced"][:] = scenario.advanced
    if scenario.team_leaders:
        for t, n in enumerate(scenario.teams):
            if n > 1:
                arrays["is_leader"][:, int(np.argmax(teams == t))] = True
    return ArenaState(packed, arrays)
