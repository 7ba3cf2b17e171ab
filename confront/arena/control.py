"""The learning tanks' fixed gun/radar controller and the paper's four macro moves (paper 6.1).

Vectorised over ``(B, R)``. The target of each robot is its nearest living enemy (true state; the
controller's radar keeps that robot scanned, so reading its true position matches what a Robocode
robot would know). Per turn the controller turns the radar toward the target with an overshoot
(a classic lock), turns the gun toward it, and fires when the gun points at the target within
``aim_tolerance`` with a power chosen from the distance.

Moves (action ids): 0 forward, 1 backward, 2 clockwise, 3 anticlockwise. Each becomes commands
written once at the start of an SMDP step of T turns; the robot then executes them over the step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .core import Arena

__all__ = ["ControlConfig", "nearest_enemy", "move_commands", "gun_radar_commands", "N_MOVES", "MOVE_NAMES"]

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


def gun_radar_commands(arena: Arena, cmd: np.ndarray, cfg: ControlConfig = ControlConfig(),
                       target: np.ndarray | None = None, robots: np.ndarray | None = None) -> np.ndarray:
    """Fill gun turn, radar turn and fire power of ``cmd`` (B, R, 5) in place for ``robots`` (bool (R,))."""
    s = arena.state
    tgt = nearest_enemy(arena) if target is None else target
    has = tgt >= 0
    t = np.where(has, tgt, 0)
    tx = np.take_along_axis(s.x, t, axis=1)
    ty = np.take_along_axis(s.y, t, axis=1)
    dx, dy = tx - s.x, ty - s.y
    bearing = np.arctan2(dx, dy)  # absolute angle to the target, 0 = north, clockwise
    dist = np.hypot(dx, dy)
    gun_turn = _rel(bearing - s.gun_heading)
    radar_turn = _rel(bearing - s.radar_heading)
    radar_turn = radar_turn + np.sign(radar_turn) * cfg.radar_overshoot
    fire = has & (np.abs(gun_turn) <= cfg.aim_tolerance) & (s.gun_heat == 0) & (s.energy > 0) & cfg.fire
    sel = s.alive & (np.ones_like(has) if robots is None else robots[None, :])
    cmd[..., 2] = np.where(sel & has, gun_turn, cmd[..., 2])
    cmd[..., 3] = np.where(sel, np.where(has, radar_turn, 2 * np.pi), cmd[..., 3])
    cmd[..., 4] = np.where(sel & fire, power_for_distance(dist, cfg), np.where(sel, 0.0, cmd[..., 4]))
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
