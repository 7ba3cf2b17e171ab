"""Compiled turn kernel: one Robocode turn for every battle of a batch (Battle.runTurn order).

Composes the pure rules of :mod:`confront.arena.rules` over the packed arrays of
:mod:`confront.arena.state`. ``step_range`` releases the GIL, so :class:`confront.arena.core.Arena`
runs chunks of battles on a thread pool; within a battle the engine's sequence is followed exactly.
Kernels are compiled without numba's reference counting (``_nrt=False``): they only index arrays.
``order_mode`` 0 = Robocode's random processing order drawn from the battle's java.util.Random
exactly as the engine consumes it; 1 = one shuffle of the movement order per turn (same rules);
2 = fixed index order (deterministic, for tests).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .kernel_cache import install
from .rules import (
    BULLET_RADIUS,
    GUN_TURN_RATE,
    RADAR_SCAN_RADIUS,
    RADAR_TURN_RATE,
    ROBOT_HALF,
    ROBOT_HIT_BONUS,
    ROBOT_HIT_DAMAGE,
    TWO_PI,
    box_contains,
    boxes_intersect,
    bullet_damage,
    bullet_hit_bonus,
    bullet_speed,
    clamp_power,
    distance_until_stop,
    float_bits,
    gun_heat,
    is_near,
    java_atan2,
    java_next,
    java_next_double,
    java_next_int,
    new_velocity,
    normal_absolute_angle,
    normal_near_absolute_angle,
    normal_relative_angle,
    segment_intersects_box,
    segment_intersects_rect,
    segments_intersect,
    sweep_hits_box_uv,
    turn_rate,
    wall_hit_damage,
)
from .state import (
    BB_FIELDS,
    BF_FIELDS,
    BI_FIELDS,
    HIT_BY_BULLET_SLOTS,
    HIT_ROBOT_SLOTS,
    KF_FIELDS,
    KI_FIELDS,
    RB_FIELDS,
    RF_FIELDS,
    RI_FIELDS,
)

# field positions inside the packed groups (compile-time constants for numba)
X, Y, H, GH, RH, V, E, HEAT, BX, BY, DIST, BODYREM, GUNREM, RADREM, MAXV, MAXTURN, ASSIST, \
    EVWALLB, EVROBB, EVBULB, EVBULH, EVROBN = range(len(RF_FIELDS) - 4 * HIT_ROBOT_SLOTS - 1 - 2 * HIT_BY_BULLET_SLOTS)
EVROB0 = EVROBN + 1  # slot k: robot at EVROB0 + 4k, then bearing, at fault, the other's energy
EVBULN = EVROB0 + 4 * HIT_ROBOT_SLOTS  # HitByBulletEvents of the turn (count)
EVBUL0 = EVBULN + 1  # slot k: bearing at EVBUL0 + 2k, the bullet's heading at EVBUL0 + 2k + 1
ALIVE, OVERDRIVE, INCOLL, TRWG, WINNER, ADV, LEADER, DROID, ADJGB, ADJRB, ADJRG, \
    EVWALL, EVFAULT, EVFIRED, EVDIED, SCANREQ = range(len(RB_FIELDS))
TEAM, EVROBOT, EVHITBY, EVBHIT, EVMISSED = range(len(RI_FIELDS))
RNG, TIME, ROUND, INACT, ENDT, NB = range(len(BI_FIELDS))
(INACT_E,) = range(len(BF_FIELDS))
DECIDED, DONE = range(len(BB_FIELDS))
KX, KY, KLX, KLY, KH, KP, KVX, KVY = range(len(KF_FIELDS))
KOWNER, KVICTIM, KSTATE, KFRAME, KLIST, KLINE = range(len(KI_FIELDS))
# score parts and placements
S_SURV, S_LAST, S_BDMG, S_BKILL, S_RAM, S_RKILL = range(6)
# bullet states (BulletState)
B_NONE, B_FIRED, B_MOVING, B_HIT_VICTIM, B_HIT_BULLET, B_HIT_WALL, B_EXPLODED = range(7)
BULLET_EXPLOSION = 17  # BulletPeer.EXPLOSION_LENGTH
ROBOT_EXPLOSION = 71  # ExplosionPeer.EXPLOSION_LENGTH
HALT_TURNS = 120  # robots halted when endTimer > 4 * TURNS_DISPLAYED_AFTER_ENDING (Battle.shutdownTurn)
# the float scratch ``last`` (B, 9, R): rows 0-2 this turn's gun and radar headings before turning and the scan flag;
# rows 3-5 and 6-8 (angle, sin, cos) of the radar's last sweep end and of the body heading last moved along (_sin_cos)
TRIG_RADAR, TRIG_BODY = 3, 6

# params vector
P_W, P_H, P_COOL, P_INACT, P_MAXT, P_AFTER, P_ORDER = range(7)


class Settings(NamedTuple):
    """An arena's fixed settings: the params vector (P_*), the scenario's initial positions (R, 3) if any."""

    params: np.ndarray
    fixed: np.ndarray
    has_fixed: bool


class Scratch(NamedTuple):
    """Per-battle work arrays of the turn: ints (B, 6, max(R, K) + 1): robot and bullet orders, dead robots, bullet
    list order, near flags; floats (B, 9, R): the ``last`` rows (TRIG_RADAR, TRIG_BODY)."""

    ints: np.ndarray
    floats: np.ndarray


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def shuffle_into(rng: int, perm: np.ndarray, n: int, mode: int) -> int:
    """perm[:n] = 0..n-1, shuffled like Collections.shuffle when mode == 0 (swap(i-1, nextInt(i)))."""
    for i in range(n):
        perm[i] = i
    if mode == 0:
        for i in range(n, 1, -1):
            rng, j = java_next_int(rng, i)
            t = perm[i - 1]
            perm[i - 1] = perm[j]
            perm[j] = t
    return rng


def _jump_tables(n: int) -> tuple[np.ndarray, np.ndarray]:
    """LCG jump-ahead: state after j steps = (A[j] * s + C[j]) mod 2^48 (java.util.Random's generator)."""
    mult, add, mask = 0x5DEECE66D, 0xB, (1 << 48) - 1
    a = np.zeros(n + 1, dtype=np.int64)
    c = np.zeros(n + 1, dtype=np.int64)
    aj, cj = 1, 0
    for j in range(n + 1):
        a[j], c[j] = aj, cj
        aj, cj = (aj * mult) & mask, (cj * mult + add) & mask
    return a, c


def _reject_thresholds(n: int) -> np.ndarray:
    """T[i]: nextInt(i) rejects a draw iff the generator state is >= T[i] (u = state >> 17 >= 2^31 - i, i not a
    power of two; Random.nextInt); 2^48 (never) for powers of two."""
    t = np.full(n + 2, 1 << 48, dtype=np.int64)
    for i in range(2, n + 2):
        if i & (i - 1):
            t[i] = ((1 << 31) - i) << 17
    return t


_JUMP_N = 4096
_JUMP_A, _JUMP_C = _jump_tables(_JUMP_N)
_REJECT = _reject_thresholds(_JUMP_N)
_MASK48 = (1 << 48) - 1


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _skip_exact(rng: int, n: int) -> int:
    """skip_shuffle one step at a time, with nextInt's rejection loop."""
    for i in range(n, 1, -1):
        rng, u = java_next(rng, 31)
        if (i & (i - 1)) != 0 and u >= (1 << 31) - i:  # nextInt's rejection is only possible up here
            r = u % i
            while u - r + i - 1 >= (1 << 31):
                rng, u = java_next(rng, 31)
                r = u % i
    return rng


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def skip_shuffle(rng: int, n: int, mode: int) -> int:
    """Advance the generator exactly as shuffle_into(mode=0) would, without building the permutation.

    Used where the engine's order cannot change the outcome (or is rebuilt lazily when it can). The n-1
    states are computed independently by jump-ahead and tested together (a loop without branches, which
    the compiler vectorises); the rare case where nextInt could reject a draw falls back to the
    step-by-step loop.
    """
    if mode != 0 or n < 2:
        return rng
    steps = n - 1
    if steps > _JUMP_N:
        return _skip_exact(rng, n)
    bad = False
    for j in range(1, steps + 1):  # draw j is nextInt(n + 1 - j)
        bad |= ((_JUMP_A[j] * rng + _JUMP_C[j]) & _MASK48) >= _REJECT[n + 1 - j]
    if bad:
        return _skip_exact(rng, n)
    return (_JUMP_A[steps] * rng + _JUMP_C[steps]) & _MASK48


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _reset_inactivity(bi, bf, b, loss):
    """Battle.resetInactiveTurnCount: every 10 energy lost in total restarts the inactivity counter."""
    if loss < 0.0:
        return
    bf[b, INACT_E] += loss
    while bf[b, INACT_E] >= 10.0:
        bf[b, INACT_E] -= 10.0
        bi[b, INACT] = 0


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _set_energy(rf, bi, bf, b, i, new_e, reset_inactive):
    """RobotPeer.setEnergy: below 0.01 becomes 0 and clears movement and body turn."""
    if reset_inactive and rf[b, E, i] != new_e:
        _reset_inactivity(bi, bf, b, rf[b, E, i] - new_e)
    rf[b, E, i] = new_e
    if new_e < 0.01:
        rf[b, E, i] = 0.0
        rf[b, DIST, i] = 0.0
        rf[b, BODYREM, i] = 0.0


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _add_list_entry(kf, ki, bi, b, state, owner, x, y, power, heading, victim):
    """Append an entry to the battle's bullet list (first free slot); returns slot or -1 if full."""
    k = kf.shape[2]
    n = bi[b, NB]
    if n >= k:
        return -1
    slot = -1
    for s in range(k):
        if ki[b, KSTATE, s] == B_NONE:
            slot = s
            break
    if slot < 0:
        return -1
    kf[b, KX, slot] = x
    kf[b, KY, slot] = y
    kf[b, KLX, slot] = x
    kf[b, KLY, slot] = y
    kf[b, KH, slot] = heading
    kf[b, KP, slot] = power
    sp = bullet_speed(power)
    kf[b, KVX, slot] = sp * math.sin(heading)  # the engine's per-turn step v*sin(h), v*cos(h): constant
    kf[b, KVY, slot] = sp * math.cos(heading)
    ki[b, KOWNER, slot] = owner
    ki[b, KVICTIM, slot] = victim
    ki[b, KSTATE, slot] = state
    ki[b, KFRAME, slot] = 0
    ki[b, KLINE, slot] = 0
    ki[b, KLIST, n] = slot
    bi[b, NB] = n + 1
    return slot


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _kill(rf, rb, ri, bi, bf, kf, ki, dead, b, i):
    """RobotPeer.kill: +10 to the inactivity ledger, leader's death costs team-mates 30, death explosion."""
    _reset_inactivity(bi, bf, b, 10.0)
    n = rf.shape[2]
    if rb[b, ALIVE, i]:
        rb[b, EVDIED, i] = True
        if rb[b, LEADER, i]:
            for j in range(n):
                if j != i and rb[b, ALIVE, j] and ri[b, TEAM, j] == ri[b, TEAM, i]:
                    _set_energy(rf, bi, bf, b, j, rf[b, E, j] - 30.0, True)
                    _add_list_entry(kf, ki, bi, b, np.int64(B_HIT_VICTIM), i, rf[b, X, j], rf[b, Y, j], 4.0, 0.0, j)
        cnt = dead[n]
        dead[cnt] = i
        dead[n] = cnt + 1
        _add_list_entry(kf, ki, bi, b, np.int64(B_EXPLODED), i, rf[b, X, i], rf[b, Y, i], 1.0, 0.0, i)
    _set_energy(rf, bi, bf, b, i, 0.0, True)
    rb[b, ALIVE, i] = False


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _team_ledger(ri, ledger, b, killer, victim):
    """Damage the killer's whole team did to the victim this round (RobotStatistics.scoreBulletKill)."""
    tot = 0.0
    for t in range(ri.shape[2]):
        if ri[b, TEAM, t] == ri[b, TEAM, killer]:
            tot += ledger[b, t, victim]
    return tot


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _remove_from_list(ki, bi, b, pos):
    """Remove list entry at position pos (ArrayList.remove keeps the order); frees its slot."""
    n = bi[b, NB]
    slot = ki[b, KLIST, pos]
    for p in range(pos, n - 1):
        ki[b, KLIST, p] = ki[b, KLIST, p + 1]
    bi[b, NB] = n - 1
    ki[b, KSTATE, slot] = B_NONE
    ki[b, KOWNER, slot] = -1


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _update_bullet(rf, rb, ri, bi, bf, kf, ki, ledger, score, dead, perm_r, perm_k, b, s, params, bb_decided, near):
    """BulletPeer.update for slot s: move, wall test, robot test (segment vs box), bullet-bullet test (the
    candidates from _mark_near's pairs in ``near``)."""
    mode = int(params[P_ORDER])
    n = rf.shape[2]
    # the engine draws a robot order and a bullet order for every entry, used or not; the orders
    # are only built when two or more candidates make them matter
    rng0 = bi[b, RNG]
    rng1 = skip_shuffle(rng0, n, mode)
    nbk = bi[b, NB]
    bi[b, RNG] = skip_shuffle(rng1, nbk, mode)
    st = ki[b, KSTATE, s]
    ki[b, KFRAME, s] += 1
    if st == B_EXPLODED:
        o = ki[b, KOWNER, s]
        kf[b, KX, s] = rf[b, X, o]
        kf[b, KY, s] = rf[b, Y, o]
        if ki[b, KFRAME, s] >= ROBOT_EXPLOSION:
            ki[b, KSTATE, s] = B_NONE
        return
    if st == B_FIRED or st == B_MOVING:
        # movement along the heading at 20 - 3p
        kf[b, KLX, s] = kf[b, KX, s]
        kf[b, KLY, s] = kf[b, KY, s]
        kf[b, KX, s] += kf[b, KVX, s]
        kf[b, KY, s] += kf[b, KVY, s]
        ki[b, KLINE, s] = 1
        x = kf[b, KX, s]
        y = kf[b, KY, s]
        lx = kf[b, KLX, s]
        ly = kf[b, KLY, s]
        owner = np.int64(ki[b, KOWNER, s])
        # wall test with radius 3 (BulletPeer.checkWallCollision)
        if x - BULLET_RADIUS <= 0 or y - BULLET_RADIUS <= 0 or x + BULLET_RADIUS >= params[P_W] \
                or y + BULLET_RADIUS >= params[P_H]:
            st = B_HIT_WALL
            ki[b, KFRAME, s] = 0
            if rb[b, ALIVE, owner] or rb[b, EVDIED, owner]:
                ri[b, EVMISSED, owner] += 1
        if st == B_FIRED or st == B_MOVING:
            cand = 0
            for j in range(n):
                # the segment is at most 19.7 long: boxes farther than 18 + 20 from its end cannot be hit
                if j != owner and rb[b, ALIVE, j] and abs(rf[b, BX, j] - x) < 38.0 and \
                        abs(rf[b, BY, j] - y) < 38.0 and \
                        segment_intersects_box(lx, ly, x, y, rf[b, BX, j], rf[b, BY, j]):
                    cand += 1
            if cand >= 2:
                shuffle_into(rng0, perm_r, n, mode)
            for q in range(n if cand > 0 else 0):
                j = perm_r[q] if cand >= 2 else q
                if j == owner or not rb[b, ALIVE, j]:
                    continue
                if not segment_intersects_box(lx, ly, x, y, rf[b, BX, j], rf[b, BY, j]):
                    continue
                st = B_HIT_VICTIM
                ki[b, KFRAME, s] = 0
                ki[b, KVICTIM, s] = j
                p = kf[b, KP, s]
                dmg = bullet_damage(p)
                sc = min(dmg, rf[b, E, j])  # damage score capped by the victim's energy
                _set_energy(rf, bi, bf, b, j, rf[b, E, j] - dmg, True)
                team_fire = ri[b, TEAM, owner] == ri[b, TEAM, j]
                if not team_fire:
                    ledger[b, owner, j] += sc
                    score[b, owner, S_BDMG] += sc
                if rf[b, E, j] <= 0.0 and rb[b, ALIVE, j]:
                    _kill(rf, rb, ri, bi, bf, kf, ki, dead, b, j)
                    if not team_fire:
                        score[b, owner, S_BKILL] += 0.2 * _team_ledger(ri, ledger, b, owner, j)
                # 3p back to the shooter (Rules.getBulletHitBonus), even if it died this turn; a robot dead
                # since an earlier turn has stopped (RobotPeer.updateEnergy: isExecFinishedAndDisabled). The engine
                # sets that flag on the dead robot's own thread, which the battle does not wait for
                # (Battle.wakeupSerial), so now and then the bonus still lands there: a race, not a rule
                if (rb[b, ALIVE, owner] or rb[b, EVDIED, owner]) and \
                        not (bb_decided and bi[b, ENDT] >= HALT_TURNS + 2):
                    _set_energy(rf, bi, bf, b, owner, rf[b, E, owner] + bullet_hit_bonus(p), True)
                ri[b, EVHITBY, j] += 1
                rf[b, EVBULB, j] = normal_relative_angle(kf[b, KH, s] + math.pi - rf[b, H, j])
                rf[b, EVBULH, j] = kf[b, KH, s]  # HitByBulletEvent.getHeading(): the bullet's own heading
                # one HitByBulletEvent per bullet, in the engine's bullet order (BulletPeer.checkRobotCollision)
                kb = int(rf[b, EVBULN, j])
                if kb < HIT_BY_BULLET_SLOTS:
                    rf[b, EVBUL0 + 2 * kb, j] = rf[b, EVBULB, j]
                    rf[b, EVBUL0 + 2 * kb + 1, j] = rf[b, EVBULH, j]
                    rf[b, EVBULN, j] = kb + 1
                if rb[b, ALIVE, owner] or rb[b, EVDIED, owner]:  # a stopped robot gets no events
                    ri[b, EVBHIT, owner] += 1
                if box_contains(rf[b, BX, j], rf[b, BY, j], lx, ly):
                    kf[b, KX, s] = lx
                    kf[b, KY, s] = ly
                break
        if st == B_FIRED or st == B_MOVING:
            cand = 0
            pairs = near[0]
            if pairs < 0:  # more pairs than _mark_near could list: look at every listed bullet
                for q in range(nbk):
                    if _bullets_meet(kf, ki, b, s, ki[b, KLIST, q], owner, lx, ly, x, y):
                        cand += 1
            for p in range(pairs):  # the bullets another owner's bullet is near to (each pair listed once)
                if near[1 + 2 * p] == s:
                    cand += _bullets_meet(kf, ki, b, s, near[2 + 2 * p], owner, lx, ly, x, y)
                elif near[2 + 2 * p] == s:
                    cand += _bullets_meet(kf, ki, b, s, near[1 + 2 * p], owner, lx, ly, x, y)
            if cand >= 2:
                shuffle_into(rng1, perm_k, nbk, mode)
            for q in range(nbk if cand > 0 else 0):
                s2 = ki[b, KLIST, perm_k[q] if cand >= 2 else q]
                if _bullets_meet(kf, ki, b, s, s2, owner, lx, ly, x, y):
                    st = B_HIT_BULLET
                    ki[b, KFRAME, s] = 0
                    kf[b, KX, s] = lx
                    kf[b, KY, s] = ly
                    ki[b, KSTATE, s2] = B_HIT_BULLET
                    ki[b, KFRAME, s2] = 0
                    kf[b, KX, s2] = kf[b, KLX, s2]
                    kf[b, KY, s2] = kf[b, KLY, s2]
                    break
    # BulletPeer.updateBulletState
    if st == B_FIRED:
        if ki[b, KFRAME, s] > 0:
            st = B_MOVING
    elif st == B_HIT_BULLET or st == B_HIT_VICTIM or st == B_HIT_WALL:
        if ki[b, KFRAME, s] >= BULLET_EXPLOSION:
            st = B_NONE
    ki[b, KSTATE, s] = st


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _bullets_meet(kf, ki, b, s, s2, owner, lx, ly, x, y):
    """Bullet s (owner, moving from (lx, ly) to (x, y) this turn) crosses listed bullet s2's line
    (BulletPeer.checkBulletCollision)."""
    # segments of at most 19.7 whose start points are 40 apart cannot cross, nor does the formula say so unless the
    # lines are nearly parallel (then its quotients are rounding noise: it may say that lines far apart meet)
    if (abs(kf[b, KLX, s2] - lx) >= 40.0 or abs(kf[b, KLY, s2] - ly) >= 40.0) and not _nearly_parallel(kf, b, s, s2):
        return False
    st2 = ki[b, KSTATE, s2]
    return s2 != s and (st2 == B_FIRED or st2 == B_MOVING) and ki[b, KLINE, s2] != 0 and \
        ki[b, KOWNER, s2] != owner and segments_intersect(lx, ly, x, y, kf[b, KLX, s2], kf[b, KLY, s2],
                                                         kf[b, KX, s2], kf[b, KY, s2])


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _nearly_parallel(kf, b, s, s2):
    """Bullets s and s2 fly within 1e-6 rad of parallel or antiparallel (their steps' cross product): then the
    quotients of BulletPeer.intersect (rules.segments_intersect) divide by rounding noise and may say that nearly
    collinear lines meet however far apart they are. At larger angles its results are the geometry's to within
    1e-5 px, far inside the near-pair filters' margins."""
    vx, vy, wx, wy = kf[b, KVX, s], kf[b, KVY, s], kf[b, KVX, s2], kf[b, KVY, s2]
    c = vx * wy - vy * wx
    return c * c <= 1e-12 * (vx * vx + vy * vy) * (wx * wx + wy * wy)


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _mark_near(kf, ki, b, nb, near):
    """The pairs of listed bullets of different owners that can meet this turn: near[0] pairs, the p-th in
    near[1 + 2p], near[2 + 2p] (near[0] = -1 when they do not fit: then every bullet looks at every other).

    _bullets_meet looks only at lines starting within 40 px of its bullet's start, or nearly parallel to its line
    (``_nearly_parallel``); every line of this turn starts at most 19.7 px (one step) from its bullet's point before
    the turn's bullet updates, so two bullets whose points are 60 px apart on an axis, and not nearly parallel, cannot
    meet: the candidates, hence the battle, are unchanged.
    """
    cap = (near.shape[0] - 1) // 2
    pairs = 0
    for p in range(nb):
        s = ki[b, KLIST, p]
        st = ki[b, KSTATE, s]
        if st != B_FIRED and st != B_MOVING:
            continue
        x = kf[b, KX, s]
        y = kf[b, KY, s]
        o = ki[b, KOWNER, s]
        for q in range(p + 1, nb):
            s2 = ki[b, KLIST, q]
            if (abs(kf[b, KX, s2] - x) < 60.0 and abs(kf[b, KY, s2] - y) < 60.0) or _nearly_parallel(kf, b, s, s2):
                st2 = ki[b, KSTATE, s2]
                if (st2 == B_FIRED or st2 == B_MOVING) and ki[b, KOWNER, s2] != o:
                    if pairs == cap:
                        near[0] = -1
                        return
                    near[1 + 2 * pairs] = s
                    near[2 + 2 * pairs] = s2
                    pairs += 1
    near[0] = pairs


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _turn_step(rem, rate):
    """This turn's share of a remaining turn: all of it, or ``rate`` toward it (RobotPeer.update*Heading)."""
    if rem > 0.0:
        return rem if rem < rate else rate
    return rem if rem > -rate else -rate


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _turn_body(rf, rb, b, i):
    """RobotPeer.updateHeading: at most min(maxTurnRate, 10 - 0.75|v|) deg; gun and radar follow."""
    rem = rf[b, BODYREM, i]
    if rem == 0.0:
        return
    step = _turn_step(rem, turn_rate(rf[b, V, i], rf[b, MAXTURN, i]))
    rf[b, H, i] += step
    rf[b, GH, i] += step
    rf[b, RH, i] += step
    if rb[b, ADJGB, i]:
        rf[b, GUNREM, i] -= step
    if rb[b, ADJRB, i]:
        rf[b, RADREM, i] -= step
    rem = 0.0 if step == rem else rem - step
    rf[b, BODYREM, i] = rem
    if rem == 0.0:
        rf[b, H, i] = normal_near_absolute_angle(rf[b, H, i])
    else:
        rf[b, H, i] = normal_absolute_angle(rf[b, H, i])


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _turn_gun(rf, rb, b, i):
    """RobotPeer.updateGunHeading: at most 20 deg; the radar follows (adjusted if adjustRadarForGun)."""
    rem = rf[b, GUNREM, i]
    if rem != 0.0:
        step = _turn_step(rem, GUN_TURN_RATE)
        rf[b, GH, i] += step
        rf[b, RH, i] += step
        if rb[b, ADJRG, i]:
            rf[b, RADREM, i] -= step
        rf[b, GUNREM, i] = 0.0 if step == rem else rem - step
    rf[b, GH, i] = normal_absolute_angle(rf[b, GH, i])


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _turn_radar(rf, b, i):
    """RobotPeer.updateRadarHeading: at most 45 deg."""
    rem = rf[b, RADREM, i]
    if rem != 0.0:
        step = _turn_step(rem, RADAR_TURN_RATE)
        rf[b, RH, i] += step
        rf[b, RADREM, i] = 0.0 if step == rem else rem - step
    rf[b, RH, i] = normal_absolute_angle(rf[b, RH, i])


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _sin_cos(a, cache, b, row, i):
    """sin(a), cos(a), taken from cache[b, row + 1 : row + 3, i] when cache[b, row, i] holds a bit for bit (a
    heading that did not turn, a radar sweep starting where the last one ended), else computed and kept there."""
    if float_bits(cache[b, row, i]) == float_bits(a):
        return cache[b, row + 1, i], cache[b, row + 2, i]
    sa = math.sin(a)
    ca = math.cos(a)
    cache[b, row, i] = a
    cache[b, row + 1, i] = sa
    cache[b, row + 2, i] = ca
    return sa, ca


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _move(rf, rb, b, i, last):
    """RobotPeer.updateMovement: getNewVelocity, overdrive flag, remaining distance, position, box."""
    d = rf[b, DIST, i]
    if math.isnan(d):
        d = 0.0
    v = new_velocity(rf[b, V, i], d, rf[b, MAXV, i])
    rf[b, V, i] = v
    if is_near(v, 0.0) and rb[b, OVERDRIVE, i]:
        d = 0.0
        rb[b, OVERDRIVE, i] = False
    if d * v >= 0.0 or math.isnan(d * v):
        rb[b, OVERDRIVE, i] = distance_until_stop(v) > abs(d)
    rf[b, DIST, i] = d - v
    if v != 0.0:
        sh, ch = _sin_cos(rf[b, H, i], last, b, TRIG_BODY, i)
        rf[b, X, i] += v * sh
        rf[b, Y, i] += v * ch
        rf[b, BX, i] = rf[b, X, i]
        rf[b, BY, i] = rf[b, Y, i]


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def wall_correction(x: float, y: float, h: float, w: float, hgt: float) -> tuple[bool, float, float, float]:
    """RobotPeer.checkWallCollision geometry: (hit, new x, new y, bearing of the wall)."""
    min_x = ROBOT_HALF
    min_y = ROBOT_HALF
    max_x = float(int(w)) - ROBOT_HALF
    max_y = float(int(hgt)) - ROBOT_HALF
    ax = 0.0
    ay = 0.0
    ang = 0.0
    hit = True
    if x < min_x:
        ax = min_x - x
        ang = normal_relative_angle(3 * math.pi / 2 - h)
    elif x > max_x:
        ax = max_x - x
        ang = normal_relative_angle(math.pi / 2 - h)
    elif y < min_y:
        ay = min_y - y
        ang = normal_relative_angle(math.pi - h)
    elif y > max_y:
        ay = max_y - y
        ang = normal_relative_angle(-h)
    else:
        hit = False
    if not hit:
        return False, x, y, 0.0
    if np.fmod(h, math.pi / 2) != 0.0:  # at an angle: correct the other axis along the heading
        t = math.tan(h)
        if ax == 0.0:
            ax = ay * t
        elif ay == 0.0:
            ay = ax / t
        elif abs(ax / t) > abs(ay):
            ay = ax / t
        elif abs(ay * t) > abs(ax):
            ax = ay * t
    x = min(max(x + ax, min_x), max_x)
    y = min(max(y + ay, min_y), max_y)
    return True, x, y, ang


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _perform_move(rf, rb, ri, bi, bf, kf, ki, ledger, score, dead, perm_r, last, b, i, zap, params):
    """RobotPeer.performMove for robot i."""
    n = rf.shape[2]
    mode = int(params[P_ORDER])
    rng0 = bi[b, RNG]
    bi[b, RNG] = skip_shuffle(rng0, n, mode)
    if not rb[b, ALIVE, i]:
        return
    rf[b, HEAT, i] = max(rf[b, HEAT, i] - params[P_COOL], 0.0)  # gun cooling per turn
    lh = rf[b, H, i]
    lg = rf[b, GH, i]
    lr = rf[b, RH, i]
    lx = rf[b, X, i]
    ly = rf[b, Y, i]
    last[b, 0, i] = lg
    last[b, 1, i] = lr
    if not rb[b, INCOLL, i]:
        _turn_body(rf, rb, b, i)
    _turn_gun(rf, rb, b, i)
    _turn_radar(rf, b, i)
    _move(rf, rb, b, i, last)
    hit, nx, ny, ang = wall_correction(rf[b, X, i], rf[b, Y, i], rf[b, H, i], params[P_W], params[P_H])
    if hit:
        rb[b, EVWALL, i] = True
        rf[b, EVWALLB, i] = ang
        rf[b, X, i] = nx
        rf[b, Y, i] = ny
        if rb[b, ADV, i]:  # wall damage only for AdvancedRobots, not counted for inactivity
            _set_energy(rf, bi, bf, b, i, rf[b, E, i] - wall_hit_damage(rf[b, V, i]), False)
        rf[b, BX, i] = nx
        rf[b, BY, i] = ny
        rf[b, DIST, i] = 0.0
        rf[b, V, i] = 0.0
    # robot collisions (RobotPeer.checkRobotCollision); the box is not recomputed after moving back
    rb[b, INCOLL, i] = False
    cand = 0
    for j in range(n):
        if j != i and rb[b, ALIVE, j] and boxes_intersect(rf[b, BX, i], rf[b, BY, i], rf[b, BX, j], rf[b, BY, j]):
            cand += 1
    if cand >= 2:  # the engine's robot order decides which collision comes first
        shuffle_into(rng0, perm_r, n, mode)
    for q in range(n if cand > 0 else 0):
        j = perm_r[q] if cand >= 2 else q
        if j == i or not rb[b, ALIVE, j]:
            continue
        if not boxes_intersect(rf[b, BX, i], rf[b, BY, i], rf[b, BX, j], rf[b, BY, j]):
            continue
        angle = java_atan2(rf[b, X, j] - rf[b, X, i], rf[b, Y, j] - rf[b, Y, i])  # Java's atan2
        v = rf[b, V, i]
        h = rf[b, H, i]
        bearing = normal_relative_angle(angle - h)
        if (v > 0 and -math.pi / 2 < bearing < math.pi / 2) or \
                (v < 0 and (bearing < -math.pi / 2 or bearing > math.pi / 2)):
            rb[b, INCOLL, i] = True
            rf[b, V, i] = 0.0
            rf[b, DIST, i] = 0.0
            rf[b, X, i] -= v * math.sin(h)
            rf[b, Y, i] -= v * math.cos(h)
            team_fire = ri[b, TEAM, i] == ri[b, TEAM, j]
            if not team_fire:
                ledger[b, i, j] += ROBOT_HIT_DAMAGE
                score[b, i, S_RAM] += ROBOT_HIT_BONUS
            _set_energy(rf, bi, bf, b, i, rf[b, E, i] - ROBOT_HIT_DAMAGE, True)
            _set_energy(rf, bi, bf, b, j, rf[b, E, j] - ROBOT_HIT_DAMAGE, True)
            if rf[b, E, j] == 0.0 and rb[b, ALIVE, j]:
                _kill(rf, rb, ri, bi, bf, kf, ki, dead, b, j)
                if not team_fire:
                    score[b, i, S_RKILL] += 0.3 * _team_ledger(ri, ledger, b, i, j)
            ri[b, EVROBOT, i] = j
            rf[b, EVROBB, i] = bearing
            rb[b, EVFAULT, i] = True
            ri[b, EVROBOT, j] = i
            rf[b, EVROBB, j] = normal_relative_angle(math.pi + angle - rf[b, H, j])
            _add_hit_robot(rf, b, i, j, bearing, True, rf[b, E, j])
            _add_hit_robot(rf, b, j, i, rf[b, EVROBB, j], False, rf[b, E, i])
    # the radar scans this turn if anything moved or turned
    if lh != rf[b, H, i] or lg != rf[b, GH, i] or lr != rf[b, RH, i] or lx != rf[b, X, i] or ly != rf[b, Y, i]:
        last[b, 2, i] = 1.0
    if zap != 0.0:  # inactivity drain (RobotPeer.zap)
        if rf[b, E, i] == 0.0:
            _kill(rf, rb, ri, bi, bf, kf, ki, dead, b, i)
            return
        rf[b, E, i] -= zap
        if rf[b, E, i] < 0.1:
            rf[b, E, i] = 0.0
            rf[b, DIST, i] = 0.0
            rf[b, BODYREM, i] = 0.0


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _add_hit_robot(rf, b, i, j, bearing, fault, energy):
    """One HitRobotEvent for robot i per collision, in the order they happen (RobotPeer.checkRobotCollision)."""
    k = int(rf[b, EVROBN, i])
    if k < HIT_ROBOT_SLOTS:
        rf[b, EVROB0 + 4 * k, i] = j
        rf[b, EVROB0 + 4 * k + 1, i] = bearing
        rf[b, EVROB0 + 4 * k + 2, i] = 1.0 if fault else 0.0
        rf[b, EVROB0 + 4 * k + 3, i] = energy
        rf[b, EVROBN, i] = k + 1


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _perform_scan(rf, rb, bi, scanned, scan_time, scan_order, perm_r, last, b, i, mode):
    """RobotPeer.performScan: radar pie from last to current radar heading, radius 1200.

    The engine hands each scanner its own random robot list (Battle.updateRobots:
    ``performScan(getRobotsAtRandom())``) and queues the ScannedRobotEvents in that order; where two scans'
    distances differ by under 1 px (ScannedRobotEvent.compareTo) that order decides which the robot handles
    first. ``scan_order[b, i]`` keeps it, written only when two or more robots were scanned (with one the order
    cannot matter; index order from the allocation on)."""
    n = rf.shape[2]
    rng0 = bi[b, RNG]
    bi[b, RNG] = skip_shuffle(rng0, n, mode)
    if not rb[b, ALIVE, i]:
        return
    rb[b, TRWG, i] = False
    if last[b, 2, i] == 0.0:
        return
    if not rb[b, DROID, i]:
        start = last[b, 1, i]
        ext = rf[b, RH, i] - start
        if ext < -math.pi:
            ext += TWO_PI
        elif ext > math.pi:
            ext -= TWO_PI
        ux, uy = _sin_cos(start, last, b, TRIG_RADAR, i)
        vx, vy = ux, uy  # sin/cos of start + 0.0: the same values
        if ext != 0.0:
            vx, vy = _sin_cos(start + ext, last, b, TRIG_RADAR, i)  # usually the next turn's start
        xi = rf[b, X, i] + ROBOT_HALF
        yi = rf[b, Y, i] + ROBOT_HALF
        for j in range(n):
            if j == i or not rb[b, ALIVE, j]:
                continue
            x0 = rf[b, BX, j] - xi
            y0 = rf[b, BY, j] - yi
            if ext >= 0.0:
                hit = sweep_hits_box_uv(x0, y0, ux, uy, vx, vy, ext != 0.0, RADAR_SCAN_RADIUS)
            else:
                hit = sweep_hits_box_uv(x0, y0, vx, vy, ux, uy, ext != 0.0, RADAR_SCAN_RADIUS)  # True here
                if not hit:
                    hit = segment_intersects_rect(0.0, 0.0, RADAR_SCAN_RADIUS * ux, RADAR_SCAN_RADIUS * uy,
                                                  x0, y0, 2 * ROBOT_HALF, 2 * ROBOT_HALF)
            if hit:
                scanned[b, i, j] = True
                scan_time[b, i, j] = bi[b, TIME]
        hits = 0
        for j in range(n):
            if scanned[b, i, j]:
                hits += 1
        if hits >= 2 and mode == 0:
            shuffle_into(rng0, perm_r, n, mode)
            for q in range(n):
                scan_order[b, i, q] = perm_r[q]
    rb[b, TRWG, i] = (last[b, 0, i] == last[b, 1, i]) and (rf[b, GH, i] == rf[b, RH, i])


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _clear_events(b, i, rb, ri, scanned, rf):
    """Forget robot i's events and scans of the last turn (each turn starts with none)."""
    rf[b, EVROBN, i] = 0.0
    rf[b, EVBULN, i] = 0.0
    rb[b, EVWALL, i] = False
    rb[b, EVFAULT, i] = False
    rb[b, EVFIRED, i] = False
    rb[b, EVDIED, i] = False
    ri[b, EVROBOT, i] = -1
    ri[b, EVHITBY, i] = 0
    ri[b, EVBHIT, i] = 0
    ri[b, EVMISSED, i] = 0
    for j in range(scanned.shape[2]):
        scanned[b, i, j] = False


@njit(cache=True, forceinline=True, _nrt=False, error_model="numpy")
def _step_battle(b, robots, battles, bullets, radar, scores, cmd, params, perm_r, perm_k, perm_d, dead, last, order,
                 near):
    """One Robocode turn of battle b (Battle.runTurn)."""
    rf, rb, ri = robots
    bi, bf, bb = battles
    kf, ki = bullets
    scanned, scan_time, scan_order = radar
    score, score_total, placements, placements_total, ledger = scores
    n = rf.shape[2]
    mode = int(params[P_ORDER])
    bi[b, TIME] += 1
    for i in range(n):
        _clear_events(b, i, rb, ri, scanned, rf)
    dead[n] = 0
    # robots are halted 120 turns after the decision (BaseBattle): the commands sent while being halted
    # are the last ones taken, and from then on a robot gains no energy (isExecFinishedAndDisabled)
    accept = not bb[b, DECIDED] or bi[b, ENDT] <= HALT_TURNS + 2
    accept_energy = not bb[b, DECIDED] or bi[b, ENDT] < HALT_TURNS + 2
    # 1. load commands (robot list order); a disabled robot cannot set move or body turn
    for i in range(n):
        last[b, 2, i] = 0.0
        if not rb[b, ALIVE, i] or not accept:
            continue
        if rb[b, SCANREQ, i]:  # scan() was called: the radar scans this turn even if nothing moves
            last[b, 2, i] = 1.0
            rb[b, SCANREQ, i] = False
        c = cmd[b, i, 0]
        if not math.isnan(c) and rf[b, E, i] > 0.0:
            rf[b, DIST, i] = c
        c = cmd[b, i, 1]
        if not math.isnan(c) and rf[b, E, i] > 0.0:
            rf[b, BODYREM, i] = c
        c = cmd[b, i, 2]
        if not math.isnan(c):
            rf[b, GUNREM, i] = c
        c = cmd[b, i, 3]
        if not math.isnan(c):
            rf[b, RADREM, i] = c
        p = cmd[b, i, 4]
        assist = rf[b, ASSIST, i]
        rf[b, ASSIST, i] = math.nan
        if p > 0.0 and rf[b, HEAT, i] == 0.0 and rf[b, E, i] > 0.0:
            p = clamp_power(p, rf[b, E, i])
            _set_energy(rf, bi, bf, b, i, rf[b, E, i] - p, True)
            rf[b, HEAT, i] += gun_heat(p)
            hd = rf[b, GH, i]
            if not rb[b, ADV, i] and rb[b, TRWG, i] and not math.isnan(assist):
                hd = assist  # fire assist of plain Robots firing from onScannedRobot
            if _add_list_entry(kf, ki, bi, b, np.int64(B_FIRED), i, rf[b, X, i], rf[b, Y, i], p, hd, np.int64(-1)) >= 0:
                rb[b, EVFIRED, i] = True
    # 2. bullets in random order
    nb = bi[b, NB]
    bi[b, RNG] = shuffle_into(bi[b, RNG], perm_d, nb, mode)
    for q in range(nb):
        order[q] = ki[b, KLIST, perm_d[q]]
    _mark_near(kf, ki, b, nb, near)
    for q in range(nb):
        s = order[q]
        _update_bullet(rf, rb, ri, bi, bf, kf, ki, ledger, score, dead, perm_r, perm_k, b, s, params,
                       bb[b, DECIDED], near)
        if ki[b, KSTATE, s] == B_NONE:
            for p in range(bi[b, NB]):
                if ki[b, KLIST, p] == s:
                    _remove_from_list(ki, bi, b, p)
                    break
    # 3. robots move, then scan
    zap = 0.1 if bi[b, INACT] > params[P_INACT] else 0.0
    bi[b, RNG] = shuffle_into(bi[b, RNG], perm_d, n, 0 if mode <= 1 else 2)
    for q in range(n):
        order[q] = perm_d[q]
    for q in range(n):
        _perform_move(rf, rb, ri, bi, bf, kf, ki, ledger, score, dead, perm_r, last, b, np.int64(order[q]), zap, params)
    bi[b, RNG] = shuffle_into(bi[b, RNG], perm_d, n, mode)  # the scanners' order: each draws its own list
    for q in range(n):
        order[q] = perm_d[q]
    for q in range(n):
        _perform_scan(rf, rb, bi, scanned, scan_time, scan_order, perm_r, last, b, np.int64(order[q]), mode)
    # 4. deaths: placements and +50 survival to every living robot of another team
    nd = np.int64(dead[n])
    bi[b, RNG] = skip_shuffle(bi[b, RNG], nd, mode)  # placements do not depend on this order
    for q in range(nd):
        d = dead[q]
        td = ri[b, TEAM, d]
        mates_alive = False
        for t in range(n):
            if ri[b, TEAM, t] == td and rb[b, ALIVE, t]:
                mates_alive = True
        if not mates_alive:
            # contestants (teams) other than the dead robot's with someone alive
            cnt = 0
            for t in range(n):
                if rb[b, ALIVE, t] and ri[b, TEAM, t] != td:
                    first = True
                    for u in range(t):
                        if ri[b, TEAM, u] == ri[b, TEAM, t] and rb[b, ALIVE, u]:
                            first = False
                            break
                    if first:
                        cnt += 1
            if cnt == 0:
                if not rb[b, WINNER, d]:
                    placements[b, d, 0] += 1
                    placements_total[b, d, 0] += 1
            elif cnt <= 2:  # 1 enemy left: a second, 2 left: a third
                placements[b, d, cnt] += 1
                placements_total[b, d, cnt] += 1
        bi[b, RNG] = skip_shuffle(bi[b, RNG], n, mode)
        for t in range(n):
            if rb[b, ALIVE, t] and ri[b, TEAM, t] != td:
                score[b, t, S_SURV] += 50.0
    # 5. round decided when at most one team has living robots
    team0 = -1
    one_left = True
    for t in range(n):
        if rb[b, ALIVE, t]:
            if team0 < 0:
                team0 = ri[b, TEAM, t]
            elif ri[b, TEAM, t] != team0:
                one_left = False
                break
    if one_left:
        if bi[b, ENDT] == 0:
            bb[b, DECIDED] = True
            bi[b, RNG] = skip_shuffle(bi[b, RNG], n, mode)  # the outcome does not depend on this order
            leader_firsts = False
            win_team = -1
            for i in range(n):
                if rb[b, ALIVE, i] and not rb[b, WINNER, i]:
                    size = 0
                    for t in range(n):
                        if ri[b, TEAM, t] == ri[b, TEAM, i]:
                            size += 1
                    score[b, i, S_LAST] += 10.0 * (n - 1 - (size - 1))  # 10 per enemy robot
                    if size == 1 or rb[b, LEADER, i]:
                        placements[b, i, 0] += 1
                        placements_total[b, i, 0] += 1
                    rb[b, WINNER, i] = True
                    if size > 1:
                        if rb[b, LEADER, i]:
                            leader_firsts = True
                        else:
                            win_team = ri[b, TEAM, i]
            if not leader_firsts and win_team >= 0:
                for t in range(n):
                    if ri[b, TEAM, t] == win_team and rb[b, LEADER, t]:
                        placements[b, t, 0] += 1
                        placements_total[b, t, 0] += 1
            for i in range(n):
                for k in range(6):
                    score_total[b, i, k] += score[b, i, k]
        bi[b, ENDT] += 1
        if bi[b, ENDT] > params[P_AFTER]:
            bb[b, DONE] = True
    bi[b, INACT] += 1
    if bi[b, TIME] >= params[P_MAXT] and not bb[b, DONE]:
        bb[b, DONE] = True
    if not accept_energy:  # halted robots have stopped: they are told nothing
        for i in range(n):
            rb[b, EVWALL, i] = False
            rb[b, EVFAULT, i] = False
            rb[b, EVDIED, i] = False
            rf[b, EVROBN, i] = 0.0
            rf[b, EVBULN, i] = 0.0
            ri[b, EVROBOT, i] = -1
            ri[b, EVHITBY, i] = 0
            ri[b, EVBHIT, i] = 0
            ri[b, EVMISSED, i] = 0
            for j in range(n):
                scanned[b, i, j] = False
    # 6. robots woken in random order
    bi[b, RNG] = skip_shuffle(bi[b, RNG], n, mode)


@njit(cache=True, inline="always", _nrt=False, error_model="numpy")
def step_battle_at(b, robots, battles, bullets, radar, scores, cmd, settings, scratch):
    """_step_battle with battle b's rows of the scratch arrays."""
    n = robots.f.shape[2]
    k = bullets.f.shape[2]
    ints = scratch.ints
    _step_battle(b, robots, battles, bullets, radar, scores, cmd, settings.params, ints[b, 0, :n], ints[b, 1, :k],
                 ints[b, 2], ints[b, 3, :n + 1], scratch.floats, ints[b, 4], ints[b, 5])


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy", nogil=True)
def step_range(b0, b1, robots, battles, bullets, radar, scores, cmd, settings, scratch):
    """Advance battles b0 .. b1-1 that are not done by one turn."""
    bb = battles.b
    for b in range(b0, b1):
        if bb[b, DONE]:
            continue
        step_battle_at(b, robots, battles, bullets, radar, scores, cmd, settings, scratch)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def reset_battle(b, robots, battles, bullets, radar, scores, settings):
    """Start a new round in battle b (RobotPeer.initializeRound): placement, energies, gun heat 3."""
    rf, rb, ri = robots
    bi, bf, bb = battles
    kf, ki = bullets
    scanned, scan_time = radar.scanned, radar.scan_time
    score, placements, ledger = scores.score, scores.placements, scores.ledger
    params, fixed, has_fixed = settings
    n = rf.shape[2]
    w = params[P_W]
    hgt = params[P_H]
    mode = int(params[P_ORDER])
    for i in range(n):
        placed = False
        if has_fixed:
            rf[b, X, i] = fixed[i, 0]
            rf[b, Y, i] = fixed[i, 1]
            rf[b, H, i] = fixed[i, 2]
            rf[b, BX, i] = fixed[i, 0]
            rf[b, BY, i] = fixed[i, 1]
            placed = _valid_spot(rf, b, i)
        if not placed:
            for _ in range(1000):
                rng = bi[b, RNG]
                rng, rx = java_next_double(rng)
                rng, ry = java_next_double(rng)
                rng, rh = java_next_double(rng)
                bi[b, RNG] = rng
                rf[b, X, i] = 2 * ROBOT_HALF + rx * (w - 4 * ROBOT_HALF)
                rf[b, Y, i] = 2 * ROBOT_HALF + ry * (hgt - 4 * ROBOT_HALF)
                rf[b, H, i] = TWO_PI * rh
                rf[b, BX, i] = rf[b, X, i]
                rf[b, BY, i] = rf[b, Y, i]
                if _valid_spot(rf, b, i):
                    break
        rf[b, GH, i] = rf[b, H, i]
        rf[b, RH, i] = rf[b, H, i]
        rb[b, ALIVE, i] = True
        rb[b, WINNER, i] = False
        rf[b, V, i] = 0.0
        e = 100.0
        if rb[b, LEADER, i]:
            e += 100.0
        if rb[b, DROID, i]:
            e += 20.0
        rf[b, E, i] = e
        rf[b, HEAT, i] = 3.0
        rf[b, DIST, i] = 0.0
        rf[b, BODYREM, i] = 0.0
        rf[b, GUNREM, i] = 0.0
        rf[b, RADREM, i] = 0.0
        rf[b, ASSIST, i] = math.nan
        rb[b, OVERDRIVE, i] = False
        rb[b, INCOLL, i] = False
        rb[b, TRWG, i] = False
        _clear_events(b, i, rb, ri, scanned, rf)
        for j in range(n):
            scan_time[b, i, j] = -1
            ledger[b, i, j] = 0.0
        for k in range(6):
            score[b, i, k] = 0.0
        for k in range(3):
            placements[b, i, k] = 0
    for s in range(kf.shape[2]):
        ki[b, KSTATE, s] = B_NONE
        ki[b, KOWNER, s] = -1
        ki[b, KLINE, s] = 0
    bi[b, NB] = 0
    bi[b, TIME] = 0
    bi[b, ROUND] += 1
    bi[b, INACT] = 0
    bi[b, ENDT] = 0
    bb[b, DECIDED] = False
    bb[b, DONE] = False
    # robots started in random order (Battle.initializeRound)
    bi[b, RNG] = skip_shuffle(bi[b, RNG], n, mode)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def reset_many(idx, robots, battles, bullets, radar, scores, settings):
    """reset_battle for every battle index in idx."""
    for q in range(idx.shape[0]):
        reset_battle(idx[q], robots, battles, bullets, radar, scores, settings)


@njit(cache=True, forceinline=False, _nrt=False, error_model="numpy")
def _valid_spot(rf, b, i):
    """No overlap with any other robot's current box (RobotPeer.validSpot; NaN boxes never overlap)."""
    for j in range(rf.shape[2]):
        if j != i and boxes_intersect(rf[b, BX, i], rf[b, BY, i], rf[b, BX, j], rf[b, BY, j]):
            return False
    return True


install(globals())
