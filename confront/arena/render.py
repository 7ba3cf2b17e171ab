"""RGB frames of a battle drawn with Pillow: field, tanks (body, gun, radar), bullets, energy bars, scores.

Robocode's coordinates have y up; images have y down, so ``screen_y = (height - y) * scale``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw

TEAM_COLOURS: tuple[tuple[int, int, int], ...] = (
    (66, 135, 245),
    (230, 70, 60),
    (60, 190, 90),
    (240, 190, 40),
    (170, 90, 220),
    (40, 200, 200),
    (240, 130, 40),
    (200, 200, 200),
)
FIELD_COLOUR = (24, 26, 32)
DEAD_COLOUR = (90, 90, 90)
BULLET_COLOUR = (255, 255, 255)
ROBOT_HALF = 18.0  # Robocode robots are 36x36


@dataclass(frozen=True)
class FrameData:
    """What one frame shows. Angles in radians (Robocode: 0 = north, clockwise)."""

    x: np.ndarray  # (R,)
    y: np.ndarray
    heading: np.ndarray
    gun_heading: np.ndarray
    radar_heading: np.ndarray
    energy: np.ndarray
    alive: np.ndarray  # (R,) bool
    team: np.ndarray  # (R,) int
    bullets: np.ndarray  # (K, 3): x, y, power
    scores: np.ndarray | None = None  # (R,) totals, shown per team
    text: str = ""


def _to_screen(x: float, y: float, height: float, scale: float) -> tuple[float, float]:
    # y up in Robocode, down in images
    return x * scale, (height - y) * scale


def _along(x: float, y: float, angle: float, length: float) -> tuple[float, float]:
    # Robocode heading: x += sin(h), y += cos(h)
    return x + length * np.sin(angle), y + length * np.cos(angle)


def _body_polygon(x: float, y: float, h: float) -> list[tuple[float, float]]:
    """Corners of the drawn body (32 long, 26 wide) rotated to heading h, in field coordinates."""
    c, s = np.cos(h), np.sin(h)
    pts = []
    for fwd, side in ((16, 13), (16, -13), (-16, -13), (-16, 13)):
        pts.append((x + fwd * s + side * c, y + fwd * c - side * s))
    return pts


def team_colour(team: int) -> tuple[int, int, int]:
    """Colour of a team id."""
    return TEAM_COLOURS[int(team) % len(TEAM_COLOURS)]


def draw_frame(frame: FrameData, width: float, height: float, scale: float = 0.5) -> np.ndarray:
    """One frame as a (H, W, 3) uint8 array."""
    if scale <= 0:
        raise ValueError(f"scale must be > 0, got {scale}")
    iw, ih = max(1, int(round(width * scale))), max(1, int(round(height * scale)))
    img = Image.new("RGB", (iw, ih), FIELD_COLOUR)
    d = ImageDraw.Draw(img)

    def scr(px: float, py: float) -> tuple[float, float]:
        return _to_screen(px, py, height, scale)

    for r in range(len(frame.x)):
        x, y = float(frame.x[r]), float(frame.y[r])
        alive = bool(frame.alive[r])
        col = team_colour(int(frame.team[r])) if alive else DEAD_COLOUR
        d.polygon([scr(*p) for p in _body_polygon(x, y, float(frame.heading[r]))], fill=col)
        if not alive:
            continue
        gx, gy = _along(x, y, float(frame.gun_heading[r]), 24.0)
        d.line([scr(x, y), scr(gx, gy)], fill=(235, 235, 235), width=max(1, int(round(4 * scale))))
        ra = float(frame.radar_heading[r])
        rx, ry = _along(x, y, ra, 12.0)
        left = _along(rx, ry, ra - np.pi / 2, 8.0)
        right = _along(rx, ry, ra + np.pi / 2, 8.0)
        d.line([scr(*left), scr(*right)], fill=(255, 255, 160), width=max(1, int(round(3 * scale))))
        frac = float(np.clip(frame.energy[r] / 100.0, 0.0, 1.0))
        bx0, by = scr(x - ROBOT_HALF, y + ROBOT_HALF + 8)
        bx1, _ = scr(x + ROBOT_HALF, y)
        bh = max(2.0, 4 * scale)
        d.rectangle([bx0, by, bx1, by + bh], fill=(70, 20, 20))
        d.rectangle([bx0, by, bx0 + (bx1 - bx0) * frac, by + bh], fill=(60, 220, 60))

    for bx, by, p in np.asarray(frame.bullets, dtype=float).reshape(-1, 3):
        cx, cy = scr(bx, by)
        rad = max(1.0, (1.5 + float(p)) * scale)
        d.ellipse([cx - rad, cy - rad, cx + rad, cy + rad], fill=BULLET_COLOUR)

    lines = [frame.text] if frame.text else []
    if frame.scores is not None:
        teams = np.asarray(frame.team)
        for t in np.unique(teams):
            lines.append(f"team {int(t)}: {float(np.sum(np.asarray(frame.scores)[teams == t])):.0f}")
    for i, line in enumerate(lines):
        d.text((4, 4 + 12 * i), line, fill=(230, 230, 230))
    return np.asarray(img, dtype=np.uint8)
