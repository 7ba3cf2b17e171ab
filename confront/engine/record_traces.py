"""Record turn-by-turn traces of short scripted battles in the real engine (fixtures for the simulator).

Usage: ``python -m confront.engine.record_traces OUT_DIR [NAME ...]``. Each battle is played by copies of
the project's ScriptBot (an AdvancedRobot that plays a command script) from fixed start positions with a
fixed seed; the control-API runner writes every turn; this module adds the scripts and per-turn commands
so each file describes itself (format: tests/fixtures/traces/README.md).
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from confront.engine.battle import BattleSpec
from confront.engine.install import ENGINE_VERSION
from confront.engine.runner import EngineOptions, run_battle

TRACE_FORMAT = "confront-trace"
TRACE_VERSION = 1
COMMANDS: tuple[str, ...] = ("ahead", "turn", "gun", "radar", "fire", "max_velocity")
FLAGS: tuple[str, ...] = (
    "adjust_gun_for_robot_turn", "adjust_radar_for_robot_turn", "adjust_radar_for_gun_turn",
    "max_velocity", "max_turn_rate_deg",
)
Command = tuple[int, str, float]


def deg(x: float) -> float:
    """Degrees to radians, the unit of turn commands in scripts."""
    return math.radians(x)


@dataclass(frozen=True)
class ScriptedRobot:
    """Start pose (x, y, heading in degrees) and script: (turn, command, value) taking effect in that turn."""

    x: float
    y: float
    heading_deg: float
    commands: tuple[Command, ...] = ()
    flags: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for turn, cmd, value in self.commands:
            if cmd not in COMMANDS:
                raise ValueError(f"unknown script command {cmd!r}; known: {COMMANDS}")
            if turn < 1 or not math.isfinite(value):
                raise ValueError(f"bad script line {(turn, cmd, value)}: turn must be >= 1, value finite")
        for name in self.flags:
            if name not in FLAGS:
                raise ValueError(f"unknown flag {name!r}; known: {FLAGS}")

    def script_text(self) -> str:
        """The script file ScriptBot reads."""
        lines = [f"flag {k} {float(v)!r}" for k, v in self.flags.items()]
        lines += [f"{t} {c} {float(v)!r}" for t, c, v in sorted(self.commands, key=lambda c: c[0])]
        return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class ScriptedBattle:
    """A named scripted battle of ScriptBots, one round, stopped at ``max_turns`` unless it ends earlier."""

    name: str
    description: str
    robots: tuple[ScriptedRobot, ...]
    max_turns: int
    width: int = 800
    height: int = 600
    gun_cooling_rate: float = 0.1
    seed: int = 1

    def spec(self) -> BattleSpec:
        """The engine battle."""
        return BattleSpec(
            ("confront.ScriptBot*",) * len(self.robots), rounds=1, width=self.width, height=self.height,
            gun_cooling_rate=self.gun_cooling_rate, name=self.name, max_turns=self.max_turns,
            initial_positions=tuple((r.x, r.y, r.heading_deg) for r in self.robots),
        )


def _every(start: int, stop: int, step: int, cmd: str, value: float) -> tuple[Command, ...]:
    return tuple((t, cmd, value) for t in range(start, stop, step))


def _bearing_deg(x0: float, y0: float, x1: float, y1: float) -> float:
    # Robocode heading: 0 = north, clockwise [robocode-facts.md section 1]
    return math.degrees(math.atan2(x1 - x0, y1 - y0)) % 360.0


BATTLES: tuple[ScriptedBattle, ...] = (
    ScriptedBattle(
        "straight_and_brake",
        "Straight runs: 'ahead 25' from rest (exact stopping rule), a long run at full speed, reversing "
        "while moving forward, a lowered max velocity, backing up.",
        (
            ScriptedRobot(100, 100, 0, ((1, "ahead", 25.0), (20, "ahead", 300.0), (45, "ahead", -60.0),
                                        (70, "max_velocity", 5.0), (70, "ahead", 120.0),
                                        (100, "max_velocity", 8.0), (100, "ahead", 37.5))),
            ScriptedRobot(600, 450, 180, ((1, "ahead", -150.0), (30, "ahead", 37.5), (60, "ahead", 3.0),
                                          (80, "ahead", 200.0), (84, "ahead", 0.0))),
        ),
        max_turns=130,
    ),
    ScriptedBattle(
        "turn_while_moving",
        "Body turns at speed (turn rate 10 - 0.75|v|), gun and radar turns with and without the adjust "
        "flags, stopping a turn midway.",
        (
            ScriptedRobot(400, 300, 0, ((1, "ahead", 600.0), (1, "turn", deg(360)), (30, "gun", deg(-90)),
                                        (30, "radar", deg(200)), (60, "turn", deg(-45)),
                                        (60, "ahead", -80.0), (90, "turn", 0.0), (95, "turn", deg(30)))),
            ScriptedRobot(150, 150, 45, ((1, "turn", deg(180)), (1, "gun", deg(-90)), (1, "radar", deg(270)),
                                         (1, "ahead", 200.0), (50, "turn", deg(-120)), (50, "gun", deg(45)),
                                         (50, "radar", deg(-360)), (50, "ahead", -100.0)),
                          flags={"adjust_gun_for_robot_turn": 1, "adjust_radar_for_robot_turn": 1,
                                 "adjust_radar_for_gun_turn": 1}),
        ),
        max_turns=140,
    ),
    ScriptedBattle(
        "wall_hits",
        "Wall collisions: straight into the west wall at full speed, into the north wall at an angle, "
        "into a corner, and backing into the south wall.",
        (
            ScriptedRobot(150, 300, 270, ((1, "ahead", 400.0), (30, "turn", deg(-30)), (30, "ahead", 800.0),
                                          (90, "ahead", -900.0))),
            ScriptedRobot(650, 420, 30, ((1, "ahead", 1000.0), (40, "turn", deg(60)), (40, "ahead", 500.0),
                                         (90, "turn", deg(90)), (90, "ahead", 700.0))),
        ),
        max_turns=150,
    ),
    ScriptedBattle(
        "rams",
        "Robot collisions: one robot rams a standing one from the side again and again (at fault), backs "
        "off; the other then backs into it; finally both drive head-on into each other (both at fault).",
        (
            ScriptedRobot(250, 300, 90, _every(1, 60, 6, "ahead", 60.0) + ((60, "ahead", -100.0),
                                        (120, "turn", deg(-90)), (150, "ahead", 2000.0))),
            ScriptedRobot(400, 300, 0, ((75, "turn", deg(-90)), (90, "ahead", -400.0), (118, "ahead", 0.0),
                                        (120, "turn", deg(90)), (150, "ahead", 2000.0))),
        ),
        max_turns=200,
    ),
    ScriptedBattle(
        "fire_until_kill",
        "One robot fires power 3 (then 1, then 0.5) bullets straight north at a standing robot until it "
        "dies; round end scoring and the turns after it.",
        (
            ScriptedRobot(400, 100, 0, _every(31, 400, 1, "fire", 3.0)[:120] + _every(151, 400, 1, "fire", 1.0)),
            ScriptedRobot(400, 500, 90, ()),
        ),
        max_turns=420,
    ),
    ScriptedBattle(
        "duel",
        "Two robots fire at each other (power 3 and 2.5) while moving sideways: hits, misses into walls, "
        "energy returned to the shooter; one dies.",
        (
            ScriptedRobot(200, 150, 0, ((1, "gun", deg(_bearing_deg(200, 150, 600, 450))),)
                          + _every(30, 400, 40, "ahead", 60.0) + _every(50, 400, 40, "ahead", -60.0)
                          + _every(31, 400, 1, "fire", 3.0),
                          flags={"adjust_gun_for_robot_turn": 1}),
            ScriptedRobot(600, 450, 180, ((1, "gun", deg(_bearing_deg(600, 450, 200, 150) - 180)),)
                          + _every(25, 400, 30, "ahead", 40.0) + _every(40, 400, 30, "ahead", -40.0)
                          + _every(31, 400, 1, "fire", 2.5),
                          flags={"adjust_gun_for_robot_turn": 1}),
        ),
        max_turns=400,
    ),
    ScriptedBattle(
        "bullet_hits_bullet",
        "Bullets crossing at right angles in the same turn collide (both removed); a later pair crosses "
        "at different times and both fly on; bullets head-on on one line pass through each other.",
        (
            ScriptedRobot(200, 300, 90, ((31, "fire", 1.0), (60, "fire", 1.0), (90, "gun", deg(-45)))),
            ScriptedRobot(500, 100, 0, ((37, "fire", 1.0), (60, "fire", 1.0))),
            ScriptedRobot(700, 540, 270, ((31, "fire", 0.5),)),
            ScriptedRobot(100, 540, 90, ((31, "fire", 0.5),)),
        ),
        max_turns=120,
    ),
    ScriptedBattle(
        "melee4",
        "Four robots from the corners drive, turn and fire at each other's start points; several hits, "
        "robot collisions and deaths (the engine's random processing order matters here).",
        tuple(
            ScriptedRobot(
                x, y, h,
                ((1, "gun", deg(_bearing_deg(x, y, tx, ty) - h)), (1, "ahead", 200.0), (1, "turn", deg(k * 20)))
                + _every(40, 330, 35, "ahead", -120.0 + 40 * k) + _every(58, 330, 35, "ahead", 150.0)
                + _every(31, 330, 1, "fire", (3.0, 2.0, 3.0, 2.5)[k]),
                flags={"adjust_gun_for_robot_turn": 1},
            )
            for k, (x, y, h, tx, ty) in enumerate(
                ((100, 100, 45, 700, 500), (700, 500, 225, 100, 100), (700, 100, 315, 100, 500),
                 (100, 500, 135, 700, 100))
            )
        ),
        max_turns=250,
    ),
)


def record(battle: ScriptedBattle, out: Path, cpu_constant_ms: float = 20.0) -> dict[str, Any]:
    """Play ``battle`` in the engine, write its self-describing trace to ``out``, return run facts."""
    scripts = {f"script_{i + 1}.txt": r.script_text() for i, r in enumerate(battle.robots)}
    raw = out.with_suffix(".raw.jsonl")
    run = run_battle(
        battle.spec(), EngineOptions(seed=battle.seed, cpu_constant_ms=cpu_constant_ms), trace=raw,
        robot_data={"ScriptBot": scripts},
    )
    lines = [json.loads(line) for line in raw.read_text().splitlines()]
    raw.unlink()
    header = lines[0]
    by_turn: dict[int, list[dict[str, float]]] = {}
    for i, r in enumerate(battle.robots):
        for t, c, v in r.commands:
            slot = by_turn.setdefault(t, [{} for _ in battle.robots])
            slot[i][c] = float(v)
    end: dict[str, Any] = next((ln for ln in lines if ln["type"] in ("round_end", "stopped")), {"robots": []})
    names: list[dict[str, Any]] = end["robots"]
    header.update({
        "format": TRACE_FORMAT, "version": TRACE_VERSION, "engine": f"robocode {ENGINE_VERSION}",
        "name": battle.name, "description": battle.description, "seed": battle.seed,
        "cpu_constant_ms": cpu_constant_ms, "max_turns": battle.max_turns,
        "skipped_turns": sum(run.skipped_turns.values()),
    })
    for i, (meta, r) in enumerate(zip(header["robots"], battle.robots, strict=True)):
        meta.update({
            "name": names[i]["name"] if i < len(names) else None,
            "start": {"x": r.x, "y": r.y, "heading_deg": r.heading_deg},
            "flags": {k: float(v) for k, v in r.flags.items()},
            "script": [[t, c, float(v)] for t, c, v in sorted(r.commands, key=lambda c: c[0])],
        })
    # robots print their events while the engine moves on, so a line may hold events of the turn before;
    # put every event on the line of the turn it happened in (its "time"), robots in index order
    events: dict[int, list[dict[str, Any]]] = {}
    for ln in lines[1:]:
        for ev in ln.get("events", []):
            events.setdefault(ev["time"], []).append(ev)
    for evs in events.values():
        evs.sort(key=lambda e: e["robot"])  # stable: keeps each robot's own order
    seen: set[tuple[int, int, str]] = set()
    with open(out, "w") as f:
        f.write(json.dumps(header) + "\n")
        for ln in lines[1:]:
            if ln["type"] == "turn":
                ln["commands"] = by_turn.get(ln["turn"], [{} for _ in battle.robots])
                ln["bullets"] = _new_bullet_states(ln["bullets"], seen)
                ln["events"] = events.get(ln["turn"], [])
            elif "events" in ln:
                ln["events"] = events.get(ln["turn"], []) if ln["turn"] == 0 else []
            f.write(json.dumps(ln, separators=(",", ":")) + "\n")
    return {"name": battle.name, "turns": run.turns, "skipped": run.skipped_turns, "bytes": out.stat().st_size}


def _new_bullet_states(bullets: list[dict[str, Any]], seen: set[tuple[int, int, str]]) -> list[dict[str, Any]]:
    """Flying bullets every turn; a finished bullet (hit, wall, explosion) only in the turn it changed state."""
    kept = []
    for b in bullets:
        if b["state"] in ("FIRED", "MOVING"):
            kept.append(b)
        elif (b["owner"], b["id"], b["state"]) not in seen:
            seen.add((b["owner"], b["id"], b["state"]))
            kept.append(b)
    return kept


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: record all (or the named) battles into OUT_DIR."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args:
        print(__doc__)
        return 2
    out_dir = Path(args[0])
    out_dir.mkdir(parents=True, exist_ok=True)
    wanted = set(args[1:])
    unknown = wanted - {b.name for b in BATTLES}
    if unknown:
        raise ValueError(f"unknown battle(s) {sorted(unknown)}; known: {[b.name for b in BATTLES]}")
    for battle in BATTLES:
        if not wanted or battle.name in wanted:
            print(record(battle, out_dir / f"{battle.name}.jsonl"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
