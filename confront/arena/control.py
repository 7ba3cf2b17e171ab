"""The learning tanks' fixed gun/radar controller and the paper's four macro moves (paper 6.1).

Vectorised over ``(B, R)``. Each robot aims at the target it knows: with a scan ``memory`` (see
:mod:`confront.arena.observe`, ``sensing``) its nearest enemy among those it has scanned this round, at
that enemy's last scanned position, exactly as the exported PolicyBot does; without one the true
state. Per turn the controller turns the radar toward the target with an overshoot (a classic lock),
turns the gun toward it, and fires when the gun points at the target within ``aim_tolerance`` with a
power chosen from the distance. With no known target the radar spins and the gun keeps its command.

Moves (action ids): 0 forward, 1 backward, 2 clockwise, 3 anticlockwise. Each becomes commands
written once at the start of an SMDP step of T turns; the robot then executes them over the step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .core import Arena
from .observe import Sensing, TargetRule, perceive, remember_scans, select_targets
from .rules import java_atan2_ufunc, java_hypot_ufunc

Floats = np.ndarray | float  # an array, or one value (a scalar works wherever an array does)

__all__ = ["ControlConfig", "nearest_enemy", "move_commands", "gun_radar_commands", "aim", "remember",
           "known_targets", "N_MOVES", "MOVE_NAMES"]

MOVE_NAMES = ("forward", "backward", "clockwise", "anticlockwise")
N_MOVES = 4


@dataclass(frozen=True)
class ControlConfig:
    """Parameters of the macro moves and the fixed gun/radar controller."""

    move_distance: float = 100.0  # px per forward/backward move
    turn_angle: float = math.radians(45.0)  # body turn per clockwise/anticlockwise move
    turn_move_distance: float = 0.0  # px driven while turning (0 = turn on the spot)
    radar_overshoot: float = math.radians(20.0)  # extra radar turn past the target to keep the lock
    aim_tolerance: float = math.radians(3.0)  # fire when the gun is this close to the target bearing
    power_near: float = 3.0  # bullet power below near_distance
    power_mid: float = 2.0
    power_far: float = 1.0
    near_distance: float = 150.0
    far_distance: float = 400.0
    fire: bool = True

    def __post_init__(self) -> None:
        for k in ("power_near", "power_mid", "power_far"):
            v = getattr(self, k)
            if not 0.1 <= v <= 3.0:
                raise ValueError(f"{k} must be in [0.1, 3], got {v}")
        if self.near_distance > self.far_distance:
            raise ValueError(f"near_distance {self.near_distance} exceeds far_distance {self.far_distance}")


def nearest_enemy(arena: Arena) -> np.ndarray:
    """(B, R) index of each robot's nearest living enemy, -1 if none."""
    s = arena.state
    dx = s.x[:, None, :] - s.x[:, :, None]
    dy = s.y[:, None, :] - s.y[:, :, None]
    d2 = dx * dx + dy * dy
    enemy = (s.team[:, None, :] != s.team[:, :, None]) & s.alive[:, None, :]
    d2 = np.where(enemy, d2, np.inf)
    idx = np.argmin(d2, axis=2).astype(np.int64)
    return np.where(np.isfinite(np.min(d2, axis=2)), idx, -1)


def _rel(a: np.ndarray) -> np.ndarray:
    """Angle wrapped to [-pi, pi) (Utils.normalRelativeAngle)."""
    return (a + np.pi) % (2 * np.pi) - np.pi


def power_for_distance(dist: np.ndarray, cfg: ControlConfig) -> np.ndarray:
    """Bullet power by distance band: near, mid, far."""
    return np.where(dist < cfg.near_distance, cfg.power_near,
                    np.where(dist < cfg.far_distance, cfg.power_mid, cfg.power_far))


def aim(x: Floats, y: Floats, gun_heading: Floats, radar_heading: Floats, gun_heat: Floats, energy: Floats,
        tx: Floats, ty: Floats, has: np.ndarray | bool | np.bool_,
        cfg: ControlConfig = ControlConfig()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(gun turn, radar turn, fire power) toward (tx, ty) where ``has``; elsewhere (NaN = keep, 2 pi, 0).

    Arrays of one shape (or scalars). The rule of PolicyModel.gunRadar and the compiled controller_turn."""
    dx, dy = tx - x, ty - y
    bearing = java_atan2_ufunc(dx, dy)  # absolute angle to the target, 0 = north, clockwise (Math.atan2's bits)
    dist = java_hypot_ufunc(dx, dy)
    gun = _rel(bearing - gun_heading)
    radar = _rel(bearing - radar_heading)
    radar = radar + np.sign(radar) * cfg.radar_overshoot  # overshoot past the target keeps the radar lock
    # Robocode fires only with a cold gun and energy left (Rules: gun heat 1 + p/5 after a shot)
    fire = has & (np.abs(gun) <= cfg.aim_tolerance) & (gun_heat == 0) & (energy > 0) & cfg.fire
    return (np.where(has, gun, np.nan), np.where(has, radar, 2 * np.pi),
            np.where(fire, power_for_distance(dist, cfg), 0.0))


def remember(memory: np.ndarray, arena: Arena) -> None:
    """Add this turn's radar scans of ``arena`` to ``memory`` (B, 3 or 9, R, R), see observe.remember_scans."""
    s = arena.state
    for b in range(arena.n_battles):
        remember_scans(s.scanned[b], s.x[b], s.y[b], s.energy[b], s.heading[b], s.velocity[b], float(s.time[b]),
                       memory[b])


def known_targets(view: tuple[np.ndarray, ...], team: np.ndarray, rule: TargetRule = "nearest") -> np.ndarray:
    """(B, R) target of each robot in its own picture ``view`` = (x, y, energy, alive), each (B, R, R)."""
    vx, vy, ve, va = view
    b, r = vx.shape[:2]
    team_b = np.repeat(np.broadcast_to(np.asarray(team), (b, r)), r, axis=0)
    fx, fy, fe, fa = (v.reshape(b * r, r) for v in (vx, vy, ve, va))
    t = select_targets(fx, fy, fe, fa, team_b, rule)
    return t.reshape(b, r, r)[:, np.arange(r), np.arange(r)]


def gun_radar_commands(arena: Arena, cmd: np.ndarray, cfg: ControlConfig = ControlConfig(),
                       target: np.ndarray | None = None, robots: np.ndarray | None = None,
                       memory: np.ndarray | None = None, sensing: Sensing = "scanned",
                       rule: TargetRule = "nearest") -> np.ndarray:
    """Fill gun turn, radar turn and fire power of ``cmd`` (B, R, 5) in place for ``robots`` (bool (R,)).

    With ``memory`` (B, 3, R, R, see :func:`remember`) each robot aims at its target (``target``, or by
    ``rule``) as it knows it (``sensing``); without it, at the true positions (``target`` or the nearest)."""
    s = arena.state
    view = perceive(s.x, s.y, s.energy, s.alive, s.team, memory, s.scan_time if memory is not None else None,
                    sensing if memory is not None else "true")
    tgt = known_targets(view, s.team, rule) if target is None else target
    has = tgt >= 0
    t = np.where(has, tgt, 0)[..., None]
    tx = np.take_along_axis(view[0], t, axis=2)[..., 0]
    ty = np.take_along_axis(view[1], t, axis=2)[..., 0]
    gun, radar, power = aim(s.x, s.y, s.gun_heading, s.radar_heading, s.gun_heat, s.energy, tx, ty, has, cfg)
    sel = s.alive & (np.ones_like(has) if robots is None else robots[None, :])
    cmd[..., 2] = np.where(sel & has, gun, cmd[..., 2])
    cmd[..., 3] = np.where(sel, radar, cmd[..., 3])
    cmd[..., 4] = np.where(sel, power, cmd[..., 4])
    return cmd


def move_commands(actions: np.ndarray, cfg: ControlConfig = ControlConfig()) -> tuple[np.ndarray, np.ndarray]:
    """(distance, body turn) arrays for action ids (0 forward, 1 backward, 2 clockwise, 3 anticlockwise)."""
    a = np.asarray(actions)
    if a.size and (a.min() < 0 or a.max() >= N_MOVES):
        raise ValueError(f"actions must be in 0..{N_MOVES - 1}, got values in [{a.min()}, {a.max()}]")
    dist = np.select([a == 0, a == 1], [cfg.move_distance, -cfg.move_distance], cfg.turn_move_distance)
    turn = np.select([a == 2, a == 3], [cfg.turn_angle, -cfg.turn_angle], 0.0)
    return dist.astype(np.float64), turn.astype(np.float64)


def set_adjustments(arena: Arena, robots: np.ndarray) -> None:
    """Independent gun and radar (setAdjustGunForRobotTurn, setAdjustRadarFor*Turn) for ``robots`` (R,)."""
    for name in ("adjust_gun_for_body", "adjust_radar_for_body", "adjust_radar_for_gun"):
        arena.state.arrays[name][:, robots] = True
