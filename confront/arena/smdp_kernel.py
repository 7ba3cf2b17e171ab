"""The compiled SMDP step of :class:`confront.arena.smdp.TeamBattleEnv`: the learning tanks' moves
(``prepare_actions``), the gun/radar controller (``controller_turn``) and T turns of battles with rewards and
observations (``smdp_turns``).

``smdp_turns`` takes the arena's bundles (:mod:`confront.arena.state`'s robots, battles, bullets, radar, scores;
:mod:`confront.arena.kernels`' settings and scratch), the scripted robots' :class:`~confront.arena.bots.BotState`,
the technique robots' :class:`~confront.arena.tech.TechState` and five of its own: :class:`Tanks` (the learning
tanks' step), :class:`Senses` (what the robots know), :class:`Outputs` (what the step writes), :class:`Views`
(which observations, of what size) and :class:`Brains` (the learning tanks' technique brains: tank.py's skills).

A module of its own so that the Python side of the env (smdp.py) can change without recompiling the kernel;
its numba cache is stamped with all kernel modules' sources (kernel_cache.py), as it holds their code.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from . import kernels as K
from .bots.controller import bots_step
from .kernel_cache import install
from .observe import float_mod, perceive_row, remember_scans, reward_eq35_scalar, robot_observation, target_of
from .rules import java_atan2, java_hypot
from .tank import KNOWLEDGE_FEATURES, LEAD_GF, M_H, M_TURN, M_V, lead_point, tank_view_row
from .tech import TechState, _decide, guess_aim, knowledge_row, tech_battle_step

__all__ = ["Tanks", "Senses", "Outputs", "Views", "Brains", "prepare_actions", "relative_angle", "controller_turn",
           "smdp_turns"]

C_OVERSHOOT, C_TOL, C_PNEAR, C_PMID, C_PFAR, C_NEAR, C_FAR, C_FIRE, C_REWARD = range(9)


class Tanks(NamedTuple):
    """The learning tanks' step: who learns (R,), each robot's move (B, R, 5: distance, body turn, 1 = turn
    relative to the target, lead, 1 = the body surfs), fire power (B, R) and chosen target (B, R) (-1: by rule),
    the controller's settings (C_*), the target rule, Eq. 35's guard and the sensing mode (observe.SENSING)."""

    learner: np.ndarray
    move: np.ndarray
    power: np.ndarray
    chosen: np.ndarray
    ctrl: np.ndarray
    rule: int
    guard: float
    sensing: int


class Senses(NamedTuple):
    """What the robots know: each robot at each robot's last scan (B, MEMORY_ROWS, R, R; tank.py), the team messages
    (x, y, energy of every robot one turn ago, (B, 3, R)) and whether a message came yet (B,)."""

    memory: np.ndarray
    mates: np.ndarray
    mates_ok: np.ndarray


class Outputs(NamedTuple):
    """What a step writes: the per-turn scratch (4, B, R), rewards (B, R, T), the paper's observations (target,
    discrete state (B, R), features (B, R, F)), the tank views (B, R, view F) and their enemy slots (B, R, K)."""

    buf: np.ndarray
    rewards: np.ndarray
    target: np.ndarray
    disc: np.ndarray
    feats: np.ndarray
    tank_view: np.ndarray
    slots: np.ndarray


class Views(NamedTuple):
    """Which observations a step computes and their sizes: the paper's distance scale, the field, the tank view's
    enemy and mate slots (0: no tank view), the robots whose tank view / paper observation is computed (R,), and
    the battles stepped together (TeamBattleEnv.battle_group)."""

    max_distance: float
    width: float
    height: float
    k_slots: int
    m_slots: int
    view_mask: np.ndarray
    paper_mask: np.ndarray
    group: int


class Brains(NamedTuple):
    """The learning tanks' technique brains (tank.py's skills; tech.py's SurfGF decision code, run for the tank each
    turn, its commands proposed): their :class:`~confront.arena.tech.TechState` (a robot has a brain when its gun
    is >= 0), the commands they proposed this turn (B, R, 5) and whether the tank view ends with the knowledge
    block."""

    state: TechState
    cmd: np.ndarray
    knowledge: bool


@njit(cache=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def prepare_actions(actions: np.ndarray, space: np.ndarray, rb: np.ndarray, bb: np.ndarray, tables: np.ndarray,
                    n_act: np.ndarray, slots: np.ndarray, move: np.ndarray, power: np.ndarray, chosen: np.ndarray,
                    active: np.ndarray) -> bool:
    """Learning tanks' move (distance, body turn), fire power and chosen target robot for the step (from
    their action table and the enemy slots of their last view), and ``active`` (a learning tank alive in a
    battle not done). Returns True, changing nothing, if an action is out of range."""
    nb, n = actions.shape
    for b in range(nb):
        for i in range(n):
            if space[i] >= 0 and not 0 <= actions[b, i] < n_act[space[i]]:
                return True
    for b in range(nb):
        for i in range(n):
            sp = space[i]
            a = actions[b, i] if sp >= 0 else 0
            row = tables[max(sp, 0), a]
            move[b, i, 0] = row[0]
            move[b, i, 1] = row[1]
            move[b, i, 2] = row[4]
            move[b, i, 3] = row[5]
            move[b, i, 4] = row[6]
            power[b, i] = row[2]
            k = int(row[3])
            chosen[b, i] = slots[b, i, k] if sp >= 0 and 0 <= k < slots.shape[2] else -1
            active[b, i] = sp >= 0 and rb[b, K.ALIVE, i] and not bb[b, K.DONE]
    return False


@njit(cache=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def relative_angle(a: float) -> float:
    """Angle wrapped to [-pi, pi) (Utils.normalRelativeAngle, as control._rel)."""
    return float_mod(a + np.pi, 2 * np.pi) - np.pi


@njit(cache=True, forceinline=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def controller_turn(rf: np.ndarray, b: int, i: int, tgt: int, tx: float, ty: float, ctrl: np.ndarray,
                    power: float, cmd: np.ndarray) -> None:
    """Gun turn, radar turn and fire power of a living learning tank (control.aim's rule) toward its
    target ``tgt`` known at (tx, ty).

    The radar turns to the target plus an overshoot, the gun to the target; the tank fires when the gun
    is within the tolerance, the gun is cold and it has energy; power by distance band, or ``power`` > 0;
    never with ``power`` < 0 (hold fire).
    Without a target the radar spins a full turn and the gun keeps its command.
    """
    bearing = java_atan2(tx - rf[b, K.X, i], ty - rf[b, K.Y, i])  # 0 = north, clockwise (Math.atan2's bits)
    controller_aim(rf, b, i, tgt, tx, ty, bearing, ctrl, power, cmd)


@njit(cache=True, forceinline=True, _nrt=False)  # no allocation: no reference counting of the arrays it is passed
def controller_aim(rf: np.ndarray, b: int, i: int, tgt: int, tx: float, ty: float, gun_bearing: float,
                   ctrl: np.ndarray, power: float, cmd: np.ndarray) -> None:
    """:func:`controller_turn` with the gun turned to the absolute angle ``gun_bearing`` (the radar and the power
    band still by the target's point)."""
    if tgt < 0:
        cmd[b, i, 3] = 2 * np.pi
        cmd[b, i, 4] = 0.0
        return
    dx = tx - rf[b, K.X, i]
    dy = ty - rf[b, K.Y, i]
    bearing = java_atan2(dx, dy)  # absolute angle to the target, 0 = north, clockwise (Math.atan2's bits)
    dist = java_hypot(dx, dy)
    gun_turn = relative_angle(gun_bearing - rf[b, K.GH, i])
    radar_turn = relative_angle(bearing - rf[b, K.RH, i])
    radar_turn = radar_turn + np.sign(radar_turn) * ctrl[C_OVERSHOOT]
    cmd[b, i, 2] = gun_turn
    cmd[b, i, 3] = radar_turn
    fire = abs(gun_turn) <= ctrl[C_TOL] and rf[b, K.HEAT, i] == 0 and rf[b, K.E, i] > 0 and ctrl[C_FIRE] > 0
    if not fire or power < 0:
        cmd[b, i, 4] = 0.0
    elif power > 0:
        cmd[b, i, 4] = power
    elif dist < ctrl[C_NEAR]:
        cmd[b, i, 4] = ctrl[C_PNEAR]
    elif dist < ctrl[C_FAR]:
        cmd[b, i, 4] = ctrl[C_PMID]
    else:
        cmd[b, i, 4] = ctrl[C_PFAR]


@njit(cache=True, nogil=True)
def smdp_turns(b0, b1, t0, t1, robots, battles, bullets, radar, scores, cmd, settings, scratch, bots, has_bots, tech,
               has_tech, tanks, senses, out, views, brains):
    """Turns t0..t1-1 of an SMDP step for battles b0..b1-1 not done: learning tanks' commands (move at
    t = 0, then kept; gun/radar controller every turn, at the chosen target when it is known, with a lead
    per the action table's lead column), scripted bots, technique robots (``has_tech``), one Robocode turn,
    rewards (Eq. 35, or the change of the team's score margin with ``ctrl[C_REWARD]``). Then the observations of
    those battles' robots into target, disc, feats (and the tank view into ``view``, ``slots`` when ``k_slots`` > 0,
    of the robots in ``view_mask`` (R,); the others' rows zero, their slots -1; the paper's observations of the
    robots in ``paper_mask`` (R,), the others' target -1, state and features 0). Returns the turn index where it
    stopped (t1, or earlier when all its battles are done). Battles are independent: ranges can
    run in parallel threads. Each robot picks its target and aims from its own picture
    (observe.perceive_row); after each turn the robots' scans go into ``memory``. The battles are stepped in
    groups of ``group`` (TeamBattleEnv.battle_group); the results do not depend on it. Learning tanks with a
    technique brain (``brains``) run it every turn they live, before their commands (tank.py's skills)."""
    n = robots.f.shape[2]
    return _smdp_core(b0, b1, t0, t1, robots, battles, bullets, radar, scores, cmd, settings, scratch, bots, has_bots,
                      tech, has_tech, tanks, senses, out, views, brains, np.empty(n), np.empty(n), np.empty(n),
                      np.empty(n, dtype=np.bool_), np.zeros((b1 - b0, n)), np.zeros(n), np.zeros(out.feats.shape[2]),
                      np.zeros(out.tank_view.shape[2]), np.empty(n),
                      np.empty(-(-(b1 - b0) // views.group), dtype=np.int64))


@njit(cache=True, nogil=True, _nrt=False)
def _smdp_turn(b0, b1, t, force, robots, battles, bullets, radar, scores, cmd, settings, scratch, bots, has_bots, tech,
               has_tech, tanks, senses, out, views, brains, vx, vy, ve, va, before, gain):
    """Turn t of an SMDP step for battles b0..b1-1: the learning tanks' commands (battles done: buf[3] zero),
    then, unless every battle is done (and not ``force``), the scripted bots, the technique robots (of the battles
    not done: a round's end waits for the step's end, when its battle starts the next round), one Robocode turn,
    scan memory and rewards.
    Returns False when it stopped because every battle was done."""
    rf, rb, ri = robots
    bi, bb = battles.i, battles.b
    kf, ki = bullets
    scanned, scan_time, scan_order = radar
    score = scores.score
    learner, move, power, chosen, ctrl, rule, guard, sensing = tanks
    memory, mates, mates_ok = senses
    buf, rewards = out.buf, out.rewards
    width, height = views.width, views.height
    n = rf.shape[2]
    margin = ctrl[C_REWARD] > 0
    any_live = False
    for b in range(b0, b1):
        if bb[b, K.DONE]:
            buf[3, b, :] = 0.0
            continue
        any_live = True
        for i in range(n):
            if margin and not learner[i]:  # a scripted robot's target and energies feed only Eq. 35 rewards
                for c in range(4):
                    cmd[b, i, c] = np.nan
                cmd[b, i, 4] = 0.0
                continue
            perceive_row(rf[b, K.X], rf[b, K.Y], rf[b, K.E], rb[b, K.ALIVE], ri[b, K.TEAM], i, memory[b],
                         scan_time[b], sensing, vx, vy, ve, va)
            tg = target_of(vx, vy, ve, va, ri[b, K.TEAM], i, rule)
            c = chosen[b, i]
            if c >= 0 and va[c]:
                tg = c
            buf[0, b, i] = tg
            buf[1, b, i] = rf[b, K.E, i]
            buf[2, b, i] = rf[b, K.E, tg] if tg >= 0 else 0.0
            buf[3, b, i] = 1.0 if rb[b, K.ALIVE, i] and tg >= 0 else 0.0
            if learner[i]:
                bs = brains.state
                brain = bs.guns[i] >= 0 and rb[b, K.ALIVE, i]
                if brain:  # the technique brain's turn (TechBrain.decide): its commands proposed, not sent
                    bc = brains.cmd[b, i]
                    for c in range(4):
                        bc[c] = np.nan
                    bc[4] = 0.0
                    _decide(b, i, bs.guns[i], bs.moves[i], bs.mem[b, i], bs.stat[b, i], bs.rng, bs.mates[i], rf, rb,
                            ri, bi, kf, ki, scanned, scan_order, bc, width, height, bs.hit_p, bs.hit_h)
                if brain and move[b, i, 4] > 0:  # surfing: the body follows the brain every turn of the step
                    cmd[b, i, 0] = brains.cmd[b, i, 0]
                    cmd[b, i, 1] = brains.cmd[b, i, 1]
                else:  # moves are written once at the start of the SMDP step (set* semantics), then kept
                    cmd[b, i, 0] = move[b, i, 0] if t == 0 else np.nan
                    cmd[b, i, 1] = move[b, i, 1] if t == 0 else np.nan
                    if t == 0 and move[b, i, 2] > 0 and tg >= 0:  # turn relative to the target's bearing
                        bearing = java_atan2(vx[tg] - rf[b, K.X, i], vy[tg] - rf[b, K.Y, i])
                        cmd[b, i, 1] = relative_angle(bearing + move[b, i, 1] - rf[b, K.H, i])
                cmd[b, i, 2] = np.nan
                cmd[b, i, 3] = np.nan
                cmd[b, i, 4] = 0.0
                if rb[b, K.ALIVE, i]:
                    tx, ty = (vx[tg], vy[tg]) if tg >= 0 else (0.0, 0.0)
                    aim_power = power[b, i] if power[b, i] > 0 else 2.0
                    gun = guess_aim(bs.mem[b, i], tg, aim_power) if brain and move[b, i, 3] == LEAD_GF \
                        and tg >= 0 else np.nan
                    if tg >= 0 and move[b, i, 3] > 0 and sensing == 1 and np.isnan(gun):
                        rate = memory[b, M_TURN, i, tg] if move[b, i, 3] > 1 else 0.0  # gf without an aim: circular
                        tx, ty = lead_point(rf[b, K.X, i], rf[b, K.Y, i], tx, ty, memory[b, M_H, i, tg],
                                            memory[b, M_V, i, tg], rate,
                                            float(bi[b, K.TIME] - scan_time[b, i, tg]), aim_power, width, height)
                    if np.isnan(gun):
                        controller_turn(rf, b, i, tg, tx, ty, ctrl, power[b, i], cmd)
                    else:
                        controller_aim(rf, b, i, tg, vx[tg], vy[tg], gun, ctrl, power[b, i], cmd)
            else:
                for c in range(4):
                    cmd[b, i, c] = np.nan
                cmd[b, i, 4] = 0.0
    if not any_live and not force:
        return False
    if has_bots:
        bots_step(b0, b1, bots, robots, radar, cmd, width, height)
    if has_tech:
        for b in range(b0, b1):
            if not bb[b, K.DONE]:
                tech_battle_step(b, tech.guns, tech.moves, tech.mem, tech.stat, tech.rng, tech.mates, rf, rb, ri, bi,
                                 kf, ki, scanned, scan_order, cmd, width, height, tech.hit_p, tech.hit_h)
    if views.k_slots > 0 or margin:  # the tank view's team messages and the score margin before this turn
        for b in range(b0, b1):
            mates_ok[b] = True  # what each robot broadcasts to its team-mates this turn (read next turn)
            for i in range(n):
                mates[b, 0, i] = rf[b, K.X, i]
                mates[b, 1, i] = rf[b, K.Y, i]
                mates[b, 2, i] = rf[b, K.E, i]
                if margin:
                    before[b - b0, i] = score[b, i].sum()
    # one Robocode turn of these battles (what Arena.step runs)
    K.step_range(b0, b1, robots, battles, bullets, radar, scores, cmd, settings, scratch)
    for b in range(b0, b1):
        remember_scans(scanned[b], rf[b, K.X], rf[b, K.Y], rf[b, K.E], rf[b, K.H], rf[b, K.V],
                       float(bi[b, K.TIME]), memory[b])
        if margin:
            for j in range(n):  # each robot's score change this turn
                gain[j] = score[b, j].sum() - before[b - b0, j]
            for i in range(n):
                if not learner[i]:
                    continue
                m = 0.0
                for j in range(n):
                    m += gain[j] if ri[b, K.TEAM, j] == ri[b, K.TEAM, i] else -gain[j]
                rewards[b, i, t] = m
            continue
        for i in range(n):
            if buf[3, b, i] > 0:
                tg = int(buf[0, b, i])
                rewards[b, i, t] = reward_eq35_scalar(buf[1, b, i], rf[b, K.E, i], buf[2, b, i],
                                                      rf[b, K.E, tg], guard)
    return True


@njit(cache=True, nogil=True, _nrt=False)
def _smdp_core(b0, b1, t0, t1, robots, battles, bullets, radar, scores, cmd, settings, scratch, bots, has_bots, tech,
               has_tech, tanks, senses, out, views, brains, vx, vy, ve, va, before, gain, row, vrow, dist, stops):
    """:func:`smdp_turns` with its scratch arrays given (vx, vy, ve, va, gain, dist (R,), before (b1 - b0, R),
    row (F,), vrow (view F,) and stops (groups,)): no allocation, so no reference counting of the many views it
    passes on."""
    rf, rb, ri = robots
    bi, scan_time = battles.i, radar.scan_time
    rule, sensing = tanks.rule, tanks.sensing
    memory, mates, mates_ok = senses
    target, disc, feats, view, slots = out.target, out.disc, out.feats, out.tank_view, out.slots
    max_distance, width, height, k_slots, m_slots, view_mask, paper_mask, group = views
    n = rf.shape[2]
    # battles in groups of ``group`` (their arrays stay in cache over the step's turns), each group turn by turn; a
    # group whose battles are all done stops, and once the step's last turn is known (the first turn at which every
    # battle was done) it is given the turns it missed, as the turn-by-turn order over all battles would have: the
    # results do not depend on the group size
    t_end = t0
    for g in range(stops.shape[0]):
        g0 = b0 + g * group
        g1 = min(b1, g0 + group)
        stops[g] = t1
        for t in range(t0, t1):
            if not _smdp_turn(g0, g1, t, False, robots, battles, bullets, radar, scores, cmd, settings, scratch, bots,
                              has_bots, tech, has_tech, tanks, senses, out, views, brains, vx, vy, ve, va,
                              before[g0 - b0:g1 - b0], gain):
                stops[g] = t
                break
        t_end = max(t_end, stops[g])
    for g in range(stops.shape[0]):
        g0 = b0 + g * group
        g1 = min(b1, g0 + group)
        for t in range(stops[g], t_end):
            _smdp_turn(g0, g1, t, True, robots, battles, bullets, radar, scores, cmd, settings, scratch, bots, has_bots,
                       tech, has_tech, tanks, senses, out, views, brains, vx, vy, ve, va, before[g0 - b0:g1 - b0],
                       gain)
    # the paper's observations (observe.observe_kernel) of the robots in paper_mask; the others: target -1,
    # state 0, features 0
    for b in range(b0, b1):
        for i in range(n):
            if not paper_mask[i]:
                target[b, i] = -1
                disc[b, i] = 0
                feats[b, i, :] = 0.0
                continue
            perceive_row(rf[b, K.X], rf[b, K.Y], rf[b, K.E], rb[b, K.ALIVE], ri[b, K.TEAM], i, memory[b],
                         scan_time[b], sensing, vx, vy, ve, va)
            tg = target_of(vx, vy, ve, va, ri[b, K.TEAM], i, rule)
            target[b, i] = tg
            disc[b, i] = robot_observation(vx, vy, rf[b, K.H], ve, i, tg, max_distance, width, height, row)
            for q in range(row.shape[0]):
                feats[b, i, q] = row[q]
    if k_slots > 0:  # the tank views of the robots in view_mask (the others' rows zero, no slots)
        for b in range(b0, b1):
            tb = float(bi[b, K.TIME])
            for i in range(n):
                if view_mask[i]:
                    tank_view_row(rf[b, K.X], rf[b, K.Y], rf[b, K.H], rf[b, K.V], rf[b, K.E], rf[b, K.HEAT],
                                  rb[b, K.ALIVE], ri[b, K.TEAM], i, memory[b], scan_time[b], tb, width, height,
                                  k_slots, m_slots, mates[b], mates_ok[b], vrow, slots[b, i], dist)
                    bs = brains.state
                    if brains.knowledge and bs.guns[i] >= 0:  # the brain's knowledge block at the view's end
                        knowledge_row(bs.mem[b, i], bs.stat[b, i], rf[b, K.X, i], rf[b, K.Y, i], tb, vrow,
                                      vrow.shape[0] - KNOWLEDGE_FEATURES)
                    for q in range(vrow.shape[0]):
                        view[b, i, q] = vrow[q]
                else:
                    view[b, i, :] = 0.0
                    slots[b, i, :] = -1
    return t_end


install(globals())
