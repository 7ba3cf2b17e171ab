"""The classic-technique robots in the simulator: twins of the Java robots ``confront.tech.*``.

Each robot (:data:`TECH_ROBOTS`) is one gun and one movement of
``confront/engine/java/confront/tech/TechBot.java``; the kernels below follow that file line by line
(same arithmetic in the same order, Java's atan2 / hypot, StrictMath's sin / cos, java.util.Random), so a battle
replays the engine's turn by turn. The Java robot is an AdvancedRobot whose handlers only record and whose
``run()`` loop makes one decision per turn; here each decision reads the turn's events from the arena state:

- ScannedRobotEvent: ``scanned[b, i, j]`` in the robot's scan order (``scan_order``), bearing and distance as
  the engine computes them; RobotDeathEvent: ``alive[b, j]`` false.
- HitByBulletEvent / BulletHitEvent: the bullets that hit this turn (state HIT_VICTIM, frame 0), with their
  power and heading, in the bullet list's order.

Memory: per robot and round ``mem`` (enemy slots, enemy waves, gun waves, directions), and per robot and
battle ``stat`` (GuessFactor visit counts, where enemy bullets hit us, virtual-gun hit rates) and ``rng``
(java.util.Random, seeded from the first round's start position as the Java robot seeds it): a Java robot
keeps these in static fields, which live for one battle of ``rounds_per_battle`` rounds (35, RoboRumble's
battle); they are cleared when a new battle starts.

Usage: ``bots = TechBots(arena, ["SurfGF", None])`` (None = driven by someone else, e.g. a
:class:`confront.arena.bots.ScriptedBots`), then every turn ``bots.commands(cmd)``.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from typing import NamedTuple, Protocol

import numpy as np
from numba import njit

from . import kernels as K
from .bots import teammate_masks
from .core import Arena
from .kernel_cache import install
from .rules import java_atan2, java_hypot, java_next_double, java_seed, normal_relative_angle
from .scenarios import Scenario
from .strictmath import strict_cos, strict_sin
from .tank import KNOWLEDGE_FEATURES

__all__ = ["TECH_ROBOTS", "TechBots", "TechState", "tech_kind", "tech_battle", "tech_battle_step", "poses_per_turn",
           "knowledge_row", "guess_aim"]

G_HEAD, G_LINEAR, G_CIRCULAR, G_GF, G_VIRTUAL, G_AS = range(6)
MV_ORBIT, MV_STOPGO, MV_RAM, MV_SURF, MV_RISK = range(5)
# name: (gun, movement), as the Java subclasses pick them (confront.engine.tech_robots lists the same names)
TECH_ROBOTS: dict[str, tuple[int, int]] = {
    "RamHeadOn": (G_HEAD, MV_RAM),
    "StopGoCircular": (G_CIRCULAR, MV_STOPGO),
    "OrbitLinear": (G_LINEAR, MV_ORBIT),
    "OrbitCircular": (G_CIRCULAR, MV_ORBIT),
    "OrbitVG": (G_VIRTUAL, MV_ORBIT),
    "OrbitGF": (G_GF, MV_ORBIT),
    "SurfCircular": (G_CIRCULAR, MV_SURF),
    "SurfGF": (G_GF, MV_SURF),
    "SurfVG": (G_VIRTUAL, MV_SURF),
    "SurfAS": (G_AS, MV_SURF),
    "RiskGF": (G_GF, MV_RISK),
}

BINS, MID = 31, 15
SEGMENTS = 5 * 3 * 3 * 3
MAXE, MAXW, MAXG, NGUNS = 10, 16, 64, 4
HALF_PI = math.pi / 2
TWO_PI = 2 * math.pi
DEG = math.pi / 180
STICK, MARGIN, SPIN = 140.0, 25.0, 10000.0

# per-round memory (mem[b, i, :]): scalars, then enemy slots, enemy waves, gun waves
T_NE, T_MOVEDIR, T_GUNDIR, T_DESTX, T_DESTY, T_DESTT, T_PREVX, T_PREVY, T_PREVH, T_PREVV, T_GNEXT, T_STARTED = range(12)
T_AIMSLOT, T_AIMGF, T_AIMPEAK = range(12, 15)  # the decision's GuessFactor aim (TechBrain.aimSlot, ...)
T_ROBOT = 15  # slot -> robot index
T_SLOT = T_ROBOT + MAXE  # robot index -> slot (-1 none); room for 16 robots
MAX_ROBOTS = 16
E0 = T_SLOT + MAX_ROBOTS
EX, EY, EH, EV, EE, ED, EB, PEX, PEY, PEH, PEV, PEE, ESCAN, EPREV, EALIVE, EMATE = range(16)
E_SIZE = 16
W0 = E0 + MAXE * E_SIZE
WX, WY, WT, WS, WA, WD, WON = range(7)
W_SIZE = 7
G0 = W0 + MAXW * W_SIZE
GX, GY, GT, GS, GA, GD, GM, GSEG, GTGT, GON, GAIM = range(11)
G_SIZE = GAIM + NGUNS + 1  # the aims of the NGUNS guns, then the anti-surfer aim
M_SIZE = G0 + MAXG * G_SIZE
# per-battle memory (stat[b, i, :]): GuessFactor visit counts, surfing hit statistics, virtual-gun hit rates
S_GF = 0
S_SURF = S_GF + SEGMENTS * BINS
S_VG = S_SURF + BINS
S_AS = S_VG + NGUNS  # anti-surfer visit counts: distance segment x bin, rolling (AS_DECAY per visit)
S_ASR = S_AS + 5 * BINS  # the anti-surfer aim's rolling hit rate (beside S_VG's)
S_SIZE = S_ASR + 1
AS_DECAY = 0.7  # the anti-surfer counts fade by this at each visit of their segment
AS_MARGIN = 0.03  # G_AS aims by the anti-surfer counts while their hit rate beats the GuessFactor aim's by this
MAX_HITS = 8
MAX_IMPACT = 50.0  # turns: the knowledge block's wave time to impact saturates there
assert KNOWLEDGE_FEATURES == NGUNS + 4


def tech_kind(name: str) -> tuple[int, int]:
    """(gun, movement) of a technique robot's name."""
    if name not in TECH_ROBOTS:
        raise ValueError(f"unknown technique robot {name!r}; known: {', '.join(TECH_ROBOTS)}")
    return TECH_ROBOTS[name]


def java_seed_of_start(x: float, y: float) -> int:
    """``new Random(Double.doubleToLongBits(x) * 31 + Double.doubleToLongBits(y))``'s state (long arithmetic)."""
    bx = struct.unpack("<q", struct.pack("<d", x))[0]
    by = struct.unpack("<q", struct.pack("<d", y))[0]
    seed = (bx * 31 + by) & ((1 << 64) - 1)
    if seed >= 1 << 63:
        seed -= 1 << 64
    return int(java_seed(seed))


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _clamp(v, lo, hi):
    """Math.max(lo, Math.min(hi, v))."""
    return max(lo, min(hi, v))


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _escape(speed):
    """asin(8 / speed) as atan2(8, sqrt(speed^2 - 64)): the maximum escape angle."""
    return java_atan2(8.0, math.sqrt(speed * speed - 64.0))


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _bin(g):
    k = int(math.floor((g + 1.0) * MID + 0.5))
    return max(0, min(BINS - 1, k))


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _in_field(px, py, w, h):
    return px >= MARGIN and px <= w - MARGIN and py >= MARGIN and py <= h - MARGIN


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _smooth(px, py, a, d, w, h):
    """Wall smoothing: turn a by 0.05 rad steps until a point STICK ahead lies inside the field."""
    for _ in range(60):
        if _in_field(px + strict_sin(a) * STICK, py + strict_cos(a) * STICK, w, h):
            return a
        a += d * 0.05
    return a


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _orbit_angle(px, py, sx, sy, dist, d):
    attack = max(-0.5, min(0.5, (dist - 400.0) * 0.002))
    return java_atan2(px - sx, py - sy) + d * (HALF_PI + attack)


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _go_angle(cmd, a, dist, heading):
    """Head for angle a, backwards when that is the shorter turn (setTurnRightRadians, setAhead)."""
    turn = normal_relative_angle(a - heading)
    if abs(turn) > HALF_PI:
        cmd[1] = normal_relative_angle(turn + math.pi)
        cmd[0] = -dist
    else:
        cmd[1] = turn
        cmd[0] = dist


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _bullet_damage(p):
    return 4.0 * p + (2.0 * (p - 1.0) if p > 1.0 else 0.0)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _target(m):
    """The nearest alive non-team-mate enemy slot (-1 none)."""
    best = -1
    for k in range(int(m[T_NE])):
        e = E0 + k * E_SIZE
        if m[e + EALIVE] == 1.0 and m[e + EMATE] == 0.0 and (best < 0 or m[e + ED] < m[E0 + best * E_SIZE + ED]):
            best = k
    return best


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _detect_fire(m, t, now, hit_p, n_hit, my_dmg):
    """Energy drop between two consecutive scans, our hits and its hits on us removed: a wave (detectFire)."""
    e = E0 + t * E_SIZE
    if m[e + EPREV] != now - 1:
        return
    gained = 0.0
    for k in range(n_hit):
        gained += 3.0 * hit_p[k]
    fired = m[e + PEE] - m[e + EE] + gained - my_dmg
    if fired < 0.0999 or fired > 3.0001:
        return
    w = -1
    for k in range(MAXW):
        if m[W0 + k * W_SIZE + WON] == 0.0:
            w = k
            break
    if w < 0:
        return
    q = W0 + w * W_SIZE
    m[q + WON] = 1.0
    m[q + WX] = m[e + PEX]
    m[q + WY] = m[e + PEY]
    m[q + WT] = now - 1
    m[q + WS] = 20.0 - 3.0 * fired
    m[q + WA] = java_atan2(m[T_PREVX] - m[q + WX], m[T_PREVY] - m[q + WY])
    m[q + WD] = 1.0 if m[T_PREVV] * strict_sin(m[T_PREVH] - m[q + WA]) >= 0 else -1.0


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _learn_hits(m, st, x, y, now, hit_p, hit_h, n_hit):
    """Each bullet that hit us: the wave it rode gives the GuessFactor it used (learnHits)."""
    for hh in range(n_hit):
        speed = 20.0 - 3.0 * hit_p[hh]
        best = -1
        best_gap = 60.0
        for k in range(MAXW):
            q = W0 + k * W_SIZE
            if m[q + WON] == 1.0 and abs(m[q + WS] - speed) < 0.01:
                gap = abs(m[q + WS] * (now - m[q + WT]) - java_hypot(x - m[q + WX], y - m[q + WY]))
                if gap < best_gap:
                    best_gap = gap
                    best = k
        if best >= 0:
            q = W0 + best * W_SIZE
            g = normal_relative_angle(hit_h[hh] - m[q + WA]) / _escape(m[q + WS]) * m[q + WD]
            c = _bin(g)
            for k in range(BINS):
                st[S_SURF + k] += 1.0 / ((k - c) * (k - c) + 1)
            m[q + WON] = 0.0


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _expire_waves(m, x, y, now):
    for k in range(MAXW):
        q = W0 + k * W_SIZE
        if m[q + WON] == 1.0 and m[q + WS] * (now - m[q + WT]) > java_hypot(x - m[q + WX], y - m[q + WY]) + 50.0:
            m[q + WON] = 0.0


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _next_double(rng, b, i):
    s, d = java_next_double(rng[b, i])
    rng[b, i] = s
    return d


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _orbit(m, rng, b, i, cmd, t, x, y, heading, seen, w, h):
    e = E0 + t * E_SIZE
    if seen and _next_double(rng, b, i) < 0.05:
        m[T_MOVEDIR] = -m[T_MOVEDIR]
    a = _orbit_angle(x, y, m[e + EX], m[e + EY], m[e + ED], m[T_MOVEDIR])
    s = _smooth(x, y, a, m[T_MOVEDIR], w, h)
    if s != a and abs(normal_relative_angle(s - a)) > 1.2:
        m[T_MOVEDIR] = -m[T_MOVEDIR]
        s = _smooth(x, y, _orbit_angle(x, y, m[e + EX], m[e + EY], m[e + ED], m[T_MOVEDIR]), m[T_MOVEDIR], w, h)
    _go_angle(cmd, s, 100.0, heading)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _stop_go(m, rng, b, i, cmd, t, x, y, heading, now, w, h):
    e = E0 + t * E_SIZE
    fired = False
    for k in range(MAXW):
        q = W0 + k * W_SIZE
        if m[q + WON] == 1.0 and m[q + WT] == now - 1:
            fired = True
    a = _orbit_angle(x, y, m[e + EX], m[e + EY], m[e + ED], m[T_MOVEDIR])
    if fired:
        if _next_double(rng, b, i) < 0.3 or not _in_field(x + strict_sin(a) * 80.0, y + strict_cos(a) * 80.0, w, h):
            m[T_MOVEDIR] = -m[T_MOVEDIR]
            a = _orbit_angle(x, y, m[e + EX], m[e + EY], m[e + ED], m[T_MOVEDIR])
        _go_angle(cmd, _smooth(x, y, a, m[T_MOVEDIR], w, h), 40.0, heading)
    _expire_waves(m, x, y, now)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _danger(m, st, wv, x, y, heading, velocity, now, d, dist, w, h):
    """Precise prediction of our path orbiting in direction d (0: stopping) until wave wv passes us."""
    q = W0 + wv * W_SIZE
    px, py, ph, pv = x, y, heading, velocity
    for k in range(1, 120):
        if d != 0:
            goal = _smooth(px, py, _orbit_angle(px, py, m[q + WX], m[q + WY], dist, d), d, w, h)
            turn = normal_relative_angle(goal - ph)
            ahead = 1.0
            if strict_cos(turn) < 0:
                turn = normal_relative_angle(turn + math.pi)
                ahead = -1.0
            max_turn = (10.0 - 0.75 * abs(pv)) * DEG
            ph += max(-max_turn, min(max_turn, turn))
            pv = pv + 2.0 * ahead if pv * ahead < 0 else max(-8.0, min(8.0, pv + ahead))
        else:
            pv = max(0.0, pv - 2.0) if pv > 0 else min(0.0, pv + 2.0)
        px = max(18.0, min(w - 18.0, px + strict_sin(ph) * pv))
        py = max(18.0, min(h - 18.0, py + strict_cos(ph) * pv))
        if m[q + WS] * (now + k - m[q + WT]) > java_hypot(px - m[q + WX], py - m[q + WY]) - 18.0:
            break
    g = normal_relative_angle(java_atan2(px - m[q + WX], py - m[q + WY]) - m[q + WA]) / _escape(m[q + WS]) \
        * m[q + WD]
    c = _bin(g)
    dng = st[S_SURF + c]
    if c > 0:
        dng += 0.5 * st[S_SURF + c - 1]
    if c < BINS - 1:
        dng += 0.5 * st[S_SURF + c + 1]
    return dng


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _surf(m, st, cmd, t, x, y, heading, velocity, now, w, h):
    _expire_waves(m, x, y, now)
    e = E0 + t * E_SIZE
    wv = -1
    soonest = 0.0
    for k in range(MAXW):
        q = W0 + k * W_SIZE
        if m[q + WON] == 1.0:
            left = java_hypot(x - m[q + WX], y - m[q + WY]) - m[q + WS] * (now - m[q + WT])
            if left > m[q + WS] and (wv < 0 or left / m[q + WS] < soonest):
                wv = k
                soonest = left / m[q + WS]
    d = m[T_MOVEDIR]
    if wv < 0:
        _go_angle(cmd, _smooth(x, y, _orbit_angle(x, y, m[e + EX], m[e + EY], m[e + ED], d), d, w, h), 100.0,
                  heading)
        return
    here = _danger(m, st, wv, x, y, heading, velocity, now, d, m[e + ED], w, h)
    there = _danger(m, st, wv, x, y, heading, velocity, now, -d, m[e + ED], w, h)
    still = _danger(m, st, wv, x, y, heading, velocity, now, 0.0, m[e + ED], w, h)
    if there < here:
        m[T_MOVEDIR] = -d
        here = there
    if still < here:
        cmd[0] = 0.0
        return
    d = m[T_MOVEDIR]
    q = W0 + wv * W_SIZE
    _go_angle(cmd, _smooth(x, y, _orbit_angle(x, y, m[q + WX], m[q + WY], m[e + ED], d), d, w, h), 100.0, heading)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _risk_at(m, px, py, x, y):
    r = 0.0
    to_p = java_atan2(px - x, py - y)
    for k in range(int(m[T_NE])):
        e = E0 + k * E_SIZE
        if m[e + EALIVE] == 1.0:
            dx = m[e + EX] - px
            dy = m[e + EY] - py
            d2 = max(dx * dx + dy * dy, 1.0)
            along = 1.0 + abs(strict_cos(to_p - java_atan2(m[e + EX] - x, m[e + EY] - y)))
            r += (50.0 if m[e + EMATE] == 1.0 else min(m[e + EE], 100.0) + 20.0) * along / d2
    dx = px - x
    dy = py - y
    return r + 0.5 / max(dx * dx + dy * dy, 1.0)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _risk(m, rng, b, i, cmd, x, y, heading, now, w, h):
    """Minimum risk: every 12 turns or near the destination, the safest of ten random points around us."""
    if m[T_DESTX] < 0 or now - m[T_DESTT] >= 12 or java_hypot(m[T_DESTX] - x, m[T_DESTY] - y) < 20:
        best = 1.7976931348623157e308 if m[T_DESTX] < 0 else _risk_at(m, m[T_DESTX], m[T_DESTY], x, y)
        for _ in range(10):
            a = _next_double(rng, b, i) * TWO_PI
            d = 80.0 + 120.0 * _next_double(rng, b, i)
            px = x + strict_sin(a) * d
            py = y + strict_cos(a) * d
            if not _in_field(px, py, w - 15.0, h - 15.0) or px < 40 or py < 40:
                continue
            r = _risk_at(m, px, py, x, y)
            if r < best:
                best = r
                m[T_DESTX] = px
                m[T_DESTY] = py
        m[T_DESTT] = now
    if m[T_DESTX] >= 0:
        _go_angle(cmd, java_atan2(m[T_DESTX] - x, m[T_DESTY] - y), java_hypot(m[T_DESTX] - x, m[T_DESTY] - y),
                  heading)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _predicted(m, t, x, y, bs, turn_rate, w, h):
    """Where the enemy meets a bullet of speed bs, moving on with its heading turning by turn_rate a turn."""
    e = E0 + t * E_SIZE
    px, py, ph = m[e + EX], m[e + EY], m[e + EH]
    for k in range(1, 100):
        if k * bs >= java_hypot(px - x, py - y):
            break
        ph += turn_rate
        px = max(18.0, min(w - 18.0, px + strict_sin(ph) * m[e + EV]))
        py = max(18.0, min(h - 18.0, py + strict_cos(ph) * m[e + EV]))
    return java_atan2(px - x, py - y)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _segment(m, t, w, h):
    e = E0 + t * E_SIZE
    lat = abs(m[e + EV] * strict_sin(m[e + EH] - m[e + EB]))
    ds = min(4, int(m[e + ED] / 150))
    ls = 0 if lat < 2 else (1 if lat < 5.5 else 2)
    a = abs(m[e + EV]) - abs(m[e + PEV]) if m[e + EPREV] == m[e + ESCAN] - 1 else 0.0
    acc = 2 if a > 0 else (0 if a < 0 else 1)
    s = -1.0 if m[e + EV] < 0 else 1.0
    k = 0
    while k < 15 and _in_field(m[e + EX] + strict_sin(m[e + EH]) * 20 * (k + 1) * s,
                               m[e + EY] + strict_cos(m[e + EH]) * 20 * (k + 1) * s, w, h):
        k += 1
    wsg = 0 if k < 4 else (1 if k < 10 else 2)
    return ((ds * 3 + ls) * 3 + acc) * 3 + wsg


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _peak(st, base):
    """The fullest bin of the BINS counts at ``st[base:]`` (the first of equals; MID first)."""
    best = MID
    for k in range(BINS):
        if st[base + k] > st[base + best]:
            best = k
    return best


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _aim_and_fire(m, st, cmd, gun_kind, move_kind, t, x, y, now, energy, gun_heading, gun_heat, gun_rem, w, h):
    e = E0 + t * E_SIZE
    power = min(3.0, 1.2 + 300.0 / m[e + ED])
    if move_kind == MV_RAM and m[e + ED] < 150:
        power = 3.0
    if energy < 15:
        power = min(power, 1.0)
    power = min(power, m[e + EE] / 4 + 0.1)
    power = max(0.1, power)
    bs = 20.0 - 3.0 * power
    lat = m[e + EV] * strict_sin(m[e + EH] - m[e + EB])
    if lat > 0:
        m[T_GUNDIR] = 1.0
    elif lat < 0:
        m[T_GUNDIR] = -1.0
    consecutive = m[e + EPREV] == m[e + ESCAN] - 1
    turn_rate = normal_relative_angle(m[e + EH] - m[e + PEH]) if consecutive else 0.0
    mea = _escape(bs)
    seg = _segment(m, t, w, h)
    for k in range(MAXG):
        q = G0 + k * G_SIZE
        if m[q + GON] == 1.0 and m[q + GTGT] == t:
            d = java_hypot(m[e + EX] - m[q + GX], m[e + EY] - m[q + GY])
            if m[q + GS] * (now - m[q + GT]) > d - 18:
                actual = java_atan2(m[e + EX] - m[q + GX], m[e + EY] - m[q + GY])
                g = max(-1.0, min(1.0, normal_relative_angle(actual - m[q + GA]) / m[q + GM] * m[q + GD]))
                c = _bin(g)
                base = S_GF + int(m[q + GSEG]) * BINS
                st[base + c] += 1.0
                if c > 0:
                    st[base + c - 1] += 0.5
                if c < BINS - 1:
                    st[base + c + 1] += 0.5
                base = S_AS + int(m[q + GSEG]) // 27 * BINS
                for j in range(BINS):
                    st[base + j] *= AS_DECAY
                st[base + c] += 1.0
                if c > 0:
                    st[base + c - 1] += 0.5
                if c < BINS - 1:
                    st[base + c + 1] += 0.5
                width = java_atan2(18.0, d)
                for gq in range(NGUNS):
                    hit = 1.0 if abs(normal_relative_angle(m[q + GAIM + gq] - actual)) < width else 0.0
                    st[S_VG + gq] = (st[S_VG + gq] * 19 + hit) / 20
                hit = 1.0 if abs(normal_relative_angle(m[q + GAIM + NGUNS] - actual)) < width else 0.0
                st[S_ASR] = (st[S_ASR] * 19 + hit) / 20
                m[q + GON] = 0.0
    head = m[e + EB]
    linear = _predicted(m, t, x, y, bs, 0.0, w, h)
    circular = _predicted(m, t, x, y, bs, turn_rate, w, h)
    base = S_GF + seg * BINS
    best = _peak(st, base)
    guess = m[e + EB] + m[T_GUNDIR] * (best - MID) / float(MID) * mea
    as_base = S_AS + seg // 27 * BINS
    as_best = _peak(st, as_base)
    as_guess = m[e + EB] + m[T_GUNDIR] * (as_best - MID) / float(MID) * mea
    if gun_kind == G_AS and st[S_ASR] > st[S_VG + G_GF] + AS_MARGIN:  # the anti-surfer aim while it hits more
        base = as_base
        best = as_best
    total = 0.0
    for q in range(BINS):
        total += st[base + q]
    m[T_AIMSLOT] = t
    m[T_AIMGF] = m[T_GUNDIR] * (best - MID) / float(MID)
    m[T_AIMPEAK] = st[base + best] / total if total > 0 else 0.0
    k = int(m[T_GNEXT])
    m[T_GNEXT] = (k + 1) % MAXG
    q = G0 + k * G_SIZE
    m[q + GON] = 1.0
    m[q + GX] = x
    m[q + GY] = y
    m[q + GT] = now
    m[q + GS] = bs
    m[q + GA] = m[e + EB]
    m[q + GD] = m[T_GUNDIR]
    m[q + GM] = mea
    m[q + GSEG] = seg
    m[q + GTGT] = t
    m[q + GAIM] = head
    m[q + GAIM + 1] = linear
    m[q + GAIM + 2] = circular
    m[q + GAIM + 3] = guess
    m[q + GAIM + NGUNS] = as_guess
    gun = gun_kind
    if gun == G_VIRTUAL:
        gun = G_CIRCULAR
        for gq in range(NGUNS):
            if st[S_VG + gq] > st[S_VG + gun]:
                gun = gq
    elif gun == G_AS:
        gun = G_GF if base != as_base else NGUNS
    aim = m[q + GAIM + gun]
    if gun_heat == 0 and abs(gun_rem) < 0.05 and energy > power + 0.1:
        cmd[4] = power
    cmd[2] = normal_relative_angle(aim - gun_heading)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _decide(b, i, gun_kind, move_kind, m, st, rng, mates, rf, rb, ri, bi, kf, ki, scanned, scan_order, cmd, w, h,
            hit_p, hit_h):
    """One decision of robot i in battle b (TechBot.run's loop body, the turn's events first)."""
    n = rf.shape[2]
    x, y = rf[b, K.X, i], rf[b, K.Y, i]
    heading = rf[b, K.H, i]
    now = float(bi[b, K.TIME])
    if m[T_STARTED] == 0.0:  # run(): before the loop
        m[T_STARTED] = 1.0
        m[T_MOVEDIR] = 1.0
        m[T_GUNDIR] = 1.0
        m[T_DESTX] = -1.0
        m[T_DESTY] = -1.0
        for j in range(MAX_ROBOTS):
            m[T_SLOT + j] = -1.0
        cmd[3] = SPIN
    m[T_AIMSLOT] = -1.0
    # events: deaths, bullets, scans (the handlers only record)
    for k in range(int(m[T_NE])):
        j = int(m[T_ROBOT + k])
        if not rb[b, K.ALIVE, j]:
            m[E0 + k * E_SIZE + EALIVE] = 0.0
    n_hit = 0
    my_dmg = 0.0
    for q in range(bi[b, K.NB]):
        s = ki[b, K.KLIST, q]
        if ki[b, K.KSTATE, s] == K.B_HIT_VICTIM and ki[b, K.KFRAME, s] == 0:
            p = kf[b, K.KP, s]
            if ki[b, K.KVICTIM, s] == i and n_hit < MAX_HITS:
                hit_p[n_hit] = p
                hit_h[n_hit] = kf[b, K.KH, s]
                n_hit += 1
            if ki[b, K.KOWNER, s] == i:
                my_dmg += _bullet_damage(p)
    for q in range(n):
        j = scan_order[b, i, q]
        if not scanned[b, i, j]:
            continue
        s = int(m[T_SLOT + j])
        if s < 0:
            if m[T_NE] >= MAXE:
                continue
            s = int(m[T_NE])
            m[T_NE] = s + 1
            m[T_SLOT + j] = s
            m[T_ROBOT + s] = j
        e = E0 + s * E_SIZE
        m[e + PEX] = m[e + EX]
        m[e + PEY] = m[e + EY]
        m[e + PEH] = m[e + EH]
        m[e + PEV] = m[e + EV]
        m[e + PEE] = m[e + EE]
        m[e + EPREV] = m[e + ESCAN] if m[e + EALIVE] == 1.0 else -10.0
        dx = rf[b, K.X, j] - x
        dy = rf[b, K.Y, j] - y
        bearing = normal_relative_angle(java_atan2(dx, dy) - heading)  # ScannedRobotEvent's bearing and distance
        ab = heading + bearing
        m[e + EB] = ab
        m[e + ED] = java_hypot(dx, dy)
        m[e + EX] = x + strict_sin(ab) * m[e + ED]
        m[e + EY] = y + strict_cos(ab) * m[e + ED]
        m[e + EH] = rf[b, K.H, j]
        m[e + EV] = rf[b, K.V, j]
        m[e + EE] = rf[b, K.E, j]
        m[e + ESCAN] = now
        m[e + EALIVE] = 1.0
        m[e + EMATE] = 1.0 if (mates >> j) & 1 else 0.0
    # decide()
    others = 0
    for j in range(n):
        if j != i and rb[b, K.ALIVE, j]:
            others += 1
    duel = others <= 1 and move_kind != MV_RISK
    t = _target(m)
    e = E0 + t * E_SIZE
    seen = t >= 0 and m[e + ESCAN] == now
    if seen and duel and m[e + EMATE] == 0.0:
        _detect_fire(m, t, now, hit_p, n_hit, my_dmg)
    if n_hit > 0:
        _learn_hits(m, st, x, y, now, hit_p, hit_h, n_hit)
    if others <= 1:
        if seen:
            cmd[3] = normal_relative_angle(m[e + EB] - rf[b, K.RH, i]) * 2
        elif t < 0 or now - m[e + ESCAN] > 1:
            cmd[3] = SPIN
    elif rf[b, K.RADREM, i] < 1:
        cmd[3] = SPIN
    if t >= 0 and m[e + EALIVE] == 1.0:
        if not duel:
            _risk(m, rng, b, i, cmd, x, y, heading, now, w, h)
        elif move_kind == MV_RAM:
            cmd[1] = normal_relative_angle(m[e + EB] - heading)
            cmd[0] = m[e + ED] + 40
        elif move_kind == MV_SURF:
            _surf(m, st, cmd, t, x, y, heading, rf[b, K.V, i], now, w, h)
        elif move_kind == MV_STOPGO:
            _stop_go(m, rng, b, i, cmd, t, x, y, heading, now, w, h)
        else:
            _orbit(m, rng, b, i, cmd, t, x, y, heading, seen, w, h)
        if seen:
            _aim_and_fire(m, st, cmd, gun_kind, move_kind, t, x, y, now, rf[b, K.E, i], rf[b, K.GH, i],
                          rf[b, K.HEAT, i], rf[b, K.GUNREM, i], w, h)
    m[T_PREVX] = x
    m[T_PREVY] = y
    m[T_PREVH] = heading
    m[T_PREVV] = rf[b, K.V, i]


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def knowledge_row(m, st, x, y, now, out, off):
    """The tank view's knowledge block (confront.arena.tank) from a brain's memory ``m`` and battle memory ``st``
    at (x, y) at time ``now`` into ``out[off:off + 8]`` (TechBrain.knowledge)."""
    for q in range(NGUNS):
        out[off + q] = st[S_VG + q]
    n = 0
    soonest = MAX_IMPACT
    for k in range(MAXW):
        q = W0 + k * W_SIZE
        if m[q + WON] == 1.0:
            n += 1
            left = (java_hypot(x - m[q + WX], y - m[q + WY]) - m[q + WS] * (now - m[q + WT])) / m[q + WS]
            soonest = min(soonest, max(left, 0.0))
    out[off + 4] = min(n, 4) / 4.0
    out[off + 5] = soonest / MAX_IMPACT
    out[off + 6] = m[T_AIMPEAK]
    top = 0.0
    total = 0.0
    for k in range(BINS):
        top = max(top, st[S_SURF + k])
        total += st[S_SURF + k]
    out[off + 7] = top / total if total > 0 else 0.0


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def guess_aim(m, robot, power):
    """The gun's absolute angle of the brain's GuessFactor aim at ``robot`` this turn for a bullet of ``power``:
    its bin's factor x the escape angle from the robot's bearing; NaN when it did not aim at that robot
    (TechBrain.guessAim)."""
    s = int(m[T_AIMSLOT])
    if s < 0 or int(m[T_ROBOT + s]) != robot:
        return np.nan
    return m[E0 + s * E_SIZE + EB] + m[T_AIMGF] * _escape(20.0 - 3.0 * power)


@njit(cache=True, _nrt=False, error_model="numpy")
def knowledge_kernel(on, mem, stat, x, y, time, off, feats):
    """The knowledge blocks of the robots with a brain (``on`` (R,)) of (B, R) battles into ``feats[..., off:]``."""
    for b in range(x.shape[0]):
        for i in range(x.shape[1]):
            if on[i]:
                knowledge_row(mem[b, i], stat[b, i], x[b, i], y[b, i], float(time[b]), feats[b, i], off)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def tech_battle_step(b, guns, moves, mem, stat, rng, mates, rf, rb, ri, bi, kf, ki, scanned, scan_order, cmd, w, h,
                     hit_p, hit_h):
    """One decision of every alive technique robot of battle b (a compiled turn loop calls it per battle). A robot
    that died decides nothing more: the Java robot's onDeath stops its decisions (its last wake handles the turn's
    events only)."""
    for i in range(rf.shape[2]):
        if guns[i] >= 0 and rb[b, K.ALIVE, i]:
            _decide(b, i, guns[i], moves[i], mem[b, i], stat[b, i], rng, mates[i], rf, rb, ri, bi, kf, ki, scanned,
                    scan_order, cmd[b, i], w, h, hit_p, hit_h)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy", nogil=True)
def tech_step(guns, moves, mem, stat, rng, mates, rf, rb, ri, bi, kf, ki, scanned, scan_order, cmd, w, h, hit_p,
              hit_h):
    """One decision of every alive technique robot in every battle (cmd rows: NaN = keep)."""
    for b in range(rf.shape[0]):
        tech_battle_step(b, guns, moves, mem, stat, rng, mates, rf, rb, ri, bi, kf, ki, scanned, scan_order, cmd, w,
                         h, hit_p, hit_h)


class TechState(NamedTuple):
    """What :func:`tech_battle_step` reads and writes, as a compiled turn loop passes it: each robot's gun and
    movement (R,) (-1: not a technique robot), its memory per round (B, R, M_SIZE) and per battle (B, R, S_SIZE),
    its java.util.Random (B, R), team-mate bit masks (R,), and the bullets that hit it this turn (power, heading;
    (MAX_HITS,) scratch: one per thread)."""

    guns: np.ndarray
    moves: np.ndarray
    mem: np.ndarray
    stat: np.ndarray
    rng: np.ndarray
    mates: np.ndarray
    hit_p: np.ndarray
    hit_h: np.ndarray


def no_tech_state(n_robots: int) -> TechState:
    """A TechState of no technique robots (the same array types as :meth:`TechBots.kernel_state`'s)."""
    none = np.full(n_robots, -1, dtype=np.int64)
    return TechState(none, none.copy(), np.zeros((1, n_robots, 1)), np.zeros((1, n_robots, 1)),
                     np.zeros((1, n_robots), dtype=np.int64), np.zeros(n_robots, dtype=np.int64), np.zeros(MAX_HITS),
                     np.zeros(MAX_HITS))


class TechBots:
    """Technique robots for some robots of an Arena (all battles); battles of ``rounds_per_battle`` rounds."""

    def __init__(self, arena: Arena, names: Sequence[str | None], rounds_per_battle: int = 35,
                 mates: Sequence[int] | None = None) -> None:
        """``mates``: per robot, the robots its isTeammate accepts (bit j); by default as the engine names the
        robots of ``names`` (teammate_masks)."""
        if len(names) != arena.n_robots:
            raise ValueError(f"names has {len(names)} entries, the arena has {arena.n_robots} robots")
        if arena.n_robots > MAX_ROBOTS:
            raise ValueError(f"technique robots play at most {MAX_ROBOTS} robots, got {arena.n_robots}")
        if rounds_per_battle < 1:
            raise ValueError(f"rounds_per_battle must be >= 1, got {rounds_per_battle}")
        self.arena = arena
        self.names = list(names)
        self.rounds_per_battle = int(rounds_per_battle)
        kinds = [tech_kind(n) if n is not None else (-1, -1) for n in names]
        self.guns = np.array([k[0] for k in kinds], dtype=np.int64)
        self.moves = np.array([k[1] for k in kinds], dtype=np.int64)
        self._bots = np.flatnonzero(self.guns >= 0)
        nb, nr = arena.n_battles, arena.n_robots
        self.mem = np.zeros((nb, nr, M_SIZE))
        self.stat = np.zeros((nb, nr, S_SIZE))
        self.rng = np.zeros((nb, nr), dtype=np.int64)
        self.mates = np.array(teammate_masks(self.names, list(arena.state.team[0])) if mates is None else mates,
                              dtype=np.int64)
        self._round = np.zeros(nb, dtype=np.int64)
        self._hits = (np.zeros(MAX_HITS), np.zeros(MAX_HITS))
        s = arena.state
        for i in self._bots:  # setAdjustGunForRobotTurn, setAdjustRadarForRobotTurn, setAdjustRadarForGunTurn
            s.is_advanced[:, i] = True
            s.adjust_gun_for_body[:, i] = True
            s.adjust_radar_for_body[:, i] = True
            s.adjust_radar_for_gun[:, i] = True
        self.sync_rounds()

    def sync_rounds(self) -> None:
        """A new round: forget the round's memory; a new battle (its first round): forget the battle's too and
        seed the generator from the start position."""
        rnd = self.arena.state.round
        changed = np.flatnonzero(rnd != self._round)
        for b in changed:
            self.mem[b] = 0.0
            if (int(rnd[b]) - 1) % self.rounds_per_battle == 0:
                self._battle_start(int(b))
            self._round[b] = rnd[b]

    def new_battles(self, mask: np.ndarray) -> None:
        """The masked battles (B,) started a new battle (``Arena.new_battle``): forget all their memory now."""
        self._round[np.asarray(mask, dtype=bool)] = -1
        self.sync_rounds()

    def kernel_state(self) -> TechState:
        """The robots' arrays for a compiled turn loop (:func:`tech_battle_step`), with their own hit scratch (one
        per thread)."""
        return TechState(self.guns, self.moves, self.mem, self.stat, self.rng, self.mates, np.zeros(MAX_HITS),
                         np.zeros(MAX_HITS))

    def state_dict(self) -> dict[str, np.ndarray]:
        """The robots' memory (per round, per battle), generators and the round each battle's memory is of."""
        return {"mem": self.mem.copy(), "stat": self.stat.copy(), "rng": self.rng.copy(), "round": self._round.copy()}

    def load_state_dict(self, d: dict[str, np.ndarray]) -> None:
        """Restore what :meth:`state_dict` wrote."""
        for name, arr in (("mem", self.mem), ("stat", self.stat), ("rng", self.rng), ("round", self._round)):
            saved = d.get(name)
            if saved is None or np.shape(saved) != arr.shape:
                got = "missing" if saved is None else f"shape {np.shape(saved)}"
                raise ValueError(f"technique robots' {name} is {got}, expected shape {arr.shape}")
            arr[...] = saved

    def _battle_start(self, b: int) -> None:
        """Battle b's first round: forget the battle's memory, seed the generators from the start positions."""
        s = self.arena.state
        self.stat[b] = 0.0
        self.stat[b, :, S_SURF + MID] = 1.0  # before any hit: expect head-on aim
        for i in self._bots:
            self.rng[b, i] = java_seed_of_start(float(s.x[b, i]), float(s.y[b, i]))

    def commands(self, cmd: np.ndarray) -> np.ndarray:
        """Fill the technique robots' rows of ``cmd`` (B, R, 5) in place for the next turn."""
        self.sync_rounds()
        cmd[:, self._bots, :4] = np.nan
        cmd[:, self._bots, 4] = 0.0
        p = self.arena.state.packed
        sc = self.arena.scenario
        tech_step(self.guns, self.moves, self.mem, self.stat, self.rng, self.mates, p["rf"], p["rb"], p["ri"],
                  p["bi"], p["kf"], p["ki"], p["scanned"], p["scan_order"], cmd, float(sc.width), float(sc.height),
                  *self._hits)
        return cmd


def tech_battle(names: list[str], rounds: int, seed: int = 0, n_battles: int = 1, scenario: Scenario | None = None,
                rounds_per_battle: int = 35, turns_after_end: int = 150) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Technique robots and sample robots (one name per robot) over ``rounds`` rounds, as
    :func:`confront.arena.bots.bot_battle` plays sample robots: a free-for-all by default, the rounds spread over
    ``n_battles`` parallel battles (battle b seeded ``seed + b``; with one battle and the engine's seed, the
    engine's start positions and processing order). Each battle keeps its robots' battle memory for
    ``rounds_per_battle`` rounds. Returns the score parts (R, 6) and placements (R, 3) summed over the rounds, and
    the rounds' lengths in turns (battle 0's first)."""
    from .bots import BOT_NAMES, ScriptedBots
    from .scenarios import get_scenario

    if rounds < 1:
        raise ValueError(f"rounds must be >= 1, got {rounds}")
    for n in names:
        if n not in TECH_ROBOTS and n not in BOT_NAMES:
            raise ValueError(f"unknown robot {n!r}; known: {', '.join((*TECH_ROBOTS, *BOT_NAMES))}")
    n_battles = min(n_battles, rounds)
    base = scenario if scenario is not None else get_scenario("melee").replace(teams=tuple(1 for _ in names))
    if base.n_robots != len(names):
        raise ValueError(f"scenario {base.name} has {base.n_robots} robots, got {len(names)} names")
    arena = Arena(base.replace(turns_after_end=turns_after_end, max_turns=100000), n_battles, seed=seed)
    samples = ScriptedBots(arena, [n if n in BOT_NAMES else None for n in names])
    tech = TechBots(arena, [n if n in TECH_ROBOTS else None for n in names], rounds_per_battle)
    quota = np.full(n_battles, rounds // n_battles)
    quota[: rounds % n_battles] += 1
    played = np.zeros(n_battles, dtype=np.int64)
    cmd = arena.idle_commands()
    s = arena.state
    lengths: list[int] = []
    while (played < quota).any():
        samples.commands(cmd)
        tech.commands(cmd)
        arena.step(cmd)
        done = s.done.copy()
        if done.any():
            lengths += [int(t) for t in s.time[done]]
            played += done
            again = done & (played < quota)
            if again.any():
                arena.reset(again)
    return s.score_total.sum(axis=0), s.placements_total.sum(axis=0), lengths


class _Driver(Protocol):
    def commands(self, cmd: np.ndarray) -> np.ndarray: ...


def poses_per_turn(arena: Arena, drivers: Sequence[_Driver], lengths: Sequence[int]) -> list[np.ndarray]:
    """Battle 0's robots turn by turn, for comparison with a recorded engine battle of rounds of ``lengths`` turns:
    per round (T, R, 7) x, y, body / gun / radar heading, velocity, energy after each turn (a round that ends
    sooner stops there). ``drivers`` fill their robots' commands every turn (e.g. ScriptedBots, TechBots)."""
    cmd = arena.idle_commands()
    s = arena.state
    out = []
    for n in lengths:
        rows = []
        for _ in range(n):
            for d in drivers:
                d.commands(cmd)
            arena.step(cmd)
            rows.append(np.stack([s.x[0], s.y[0], s.heading[0], s.gun_heading[0], s.radar_heading[0],
                                  s.velocity[0], s.energy[0]], 1))
            if s.done[0]:
                arena.reset(s.done.copy())
                break
        out.append(np.array(rows))
    return out


install(globals())
