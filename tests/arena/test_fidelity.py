"""Replay the real engine's recorded traces (tests/fixtures/traces) in the simulator and compare.

Per turn: x, y, body/gun/radar headings, velocity, energy and gun heat within 1e-6; the events each
robot was told (wall and robot hits, bullet hits and misses, deaths, scans) on the same turns; the
final scores. The arena runs with the trace's seed and Robocode's random processing order.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from confront.arena.core import Arena
from confront.arena.scenarios import Scenario

TRACES = Path(__file__).resolve().parents[1] / "fixtures" / "traces"
FILES = sorted(TRACES.glob("*.jsonl"))
TOL = 1e-6
COLS = {"ahead": 0, "turn": 1, "gun": 2, "radar": 3, "fire": 4}
FLAGS = {"adjust_gun_for_robot_turn": "adjust_gun_for_body", "adjust_radar_for_robot_turn": "adjust_radar_for_body",
         "adjust_radar_for_gun_turn": "adjust_radar_for_gun"}
SCORE_KEYS = ("survival", "surv_bonus", "bullet_dmg", "bullet_bonus", "ram_dmg", "ram_bonus")


def load(path: Path) -> tuple[dict, list[dict], dict]:
    lines = [json.loads(x) for x in path.read_text().splitlines() if x.strip()]
    head = lines[0]
    turns = [x for x in lines[1:] if x["type"] in ("round_start", "turn")]
    end = next(x for x in lines[1:] if x["type"] in ("round_end", "stopped"))
    return head, turns, end


def make_arena(head: dict) -> Arena:
    robots = head["robots"]
    sc = Scenario(
        name=head["name"], teams=tuple(1 for _ in robots), width=float(head["width"]),
        height=float(head["height"]), gun_cooling_rate=head["gun_cooling_rate"],
        inactivity_time=head["inactivity_time"], max_turns=100000, turns_after_end=150,
        initial_positions=tuple((r["start"]["x"], r["start"]["y"], r["start"]["heading_deg"]) for r in robots),
    )
    arena = Arena(sc, 1, seed=head["seed"], order="engine")
    for r in robots:
        for key, value in r.get("flags", {}).items():
            if key in FLAGS:
                arena.state.arrays[FLAGS[key]][0, r["index"]] = bool(value)
            elif key == "max_velocity":
                arena.state.max_velocity[0, r["index"]] = value
            elif key == "max_turn_rate_deg":
                arena.state.max_turn_rate[0, r["index"]] = math.radians(value)
    return arena


def commands_for(arena: Arena, line: dict) -> np.ndarray:
    cmd = arena.idle_commands()
    for i, c in enumerate(line.get("commands", [])):
        for key, value in c.items():
            if key == "max_velocity":
                arena.state.max_velocity[0, i] = value
            else:
                cmd[0, i, COLS[key]] = value
    return cmd


def robot_table(line: dict) -> np.ndarray:
    keys = ("x", "y", "body_heading", "gun_heading", "radar_heading", "velocity", "energy", "gun_heat")
    return np.array([[r[k] for k in keys] for r in sorted(line["robots"], key=lambda r: r["index"])])


def sim_table(arena: Arena) -> np.ndarray:
    s = arena.state
    return np.stack([s.x[0], s.y[0], s.heading[0], s.gun_heading[0], s.radar_heading[0], s.velocity[0],
                     s.energy[0], s.gun_heat[0]], axis=1)


def angle_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs((a - b + np.pi) % (2 * np.pi) - np.pi)


def engine_events(line: dict, names: dict[str, int], n: int) -> dict[str, np.ndarray]:
    ev = {k: np.zeros(n, dtype=np.int64) for k in ("hit_wall", "hit_robot", "my_fault", "hit_by_bullet",
                                                   "bullet_hit", "bullet_missed", "death")}
    ev["scanned"] = np.zeros((n, n), dtype=bool)
    for e in line.get("events", []):
        i, t = e["robot"], e["type"]
        if t == "scanned_robot":
            ev["scanned"][i, names[e["name"]]] = True
        elif t == "hit_robot":
            ev["hit_robot"][i] = 1
            ev["my_fault"][i] |= int(bool(e["my_fault"]))
        elif t in ev:
            ev[t][i] += 1
    return ev


def sim_events(arena: Arena) -> dict[str, np.ndarray]:
    s = arena.state
    return {"hit_wall": s.ev_hit_wall[0].astype(np.int64), "hit_robot": (s.ev_hit_robot[0] >= 0).astype(np.int64),
            "my_fault": s.ev_at_fault[0].astype(np.int64), "hit_by_bullet": s.ev_hit_by_bullet[0].astype(np.int64),
            "bullet_hit": s.ev_bullet_hit[0].astype(np.int64), "bullet_missed": s.ev_bullet_missed[0].astype(np.int64),
            "death": s.ev_died[0].astype(np.int64), "scanned": s.scanned[0].copy()}


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_trace_replays_exactly(path: Path) -> None:
    head, turns, end = load(path)
    arena = make_arena(head)
    n = len(head["robots"])
    names = {r["name"]: r["index"] for r in head["robots"]}
    np.testing.assert_allclose(sim_table(arena), robot_table(turns[0]), atol=TOL, err_msg="turn 0")
    last_event_turn = head["max_turns"] - 5
    for line in turns[1:]:
        t = line["turn"]
        arena.step(commands_for(arena, line))
        assert arena.state.time[0] == t
        want, got = robot_table(line), sim_table(arena)
        lin = [0, 1, 5, 6, 7]
        bad = np.abs(want[:, lin] - got[:, lin]) > TOL
        bad_a = angle_diff(want[:, 2:5], got[:, 2:5]) > TOL
        assert not bad.any() and not bad_a.any(), f"{path.stem} turn {t}: engine\n{want}\nsim\n{got}"
        alive = np.array([r["state"] != "DEAD" for r in sorted(line["robots"], key=lambda r: r["index"])])
        np.testing.assert_array_equal(arena.state.alive[0], alive, err_msg=f"{path.stem} turn {t} alive")
        if t <= last_event_turn:
            we, ge = engine_events(line, names, n), sim_events(arena)
            for k in we:
                np.testing.assert_array_equal(ge[k], we[k], err_msg=f"{path.stem} turn {t} event {k}")
    for r in end["robots"]:
        i = r["index"]
        cur = [r["current"][k] for k in SCORE_KEYS]
        np.testing.assert_allclose(arena.state.score[0, i], cur, atol=TOL, err_msg=f"{path.stem} round score {i}")
        tot = [r["score"][k] for k in SCORE_KEYS]
        np.testing.assert_allclose(arena.state.score_total[0, i], tot, atol=TOL, err_msg=f"{path.stem} total {i}")
        places = [r["score"][k] for k in ("firsts", "seconds", "thirds")]
        assert arena.state.placements_total[0, i].tolist() == places, f"{path.stem} placements {i}"
