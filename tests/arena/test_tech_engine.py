"""The technique robots' twins replay recorded engine battles of the Java robots (confront.tech.*) turn by turn.

Fixtures: tests/fixtures/traces/tech/*.jsonl, made by tests/fixtures/traces/tech/record_tech_bots.py (each a 1v1 of
two or three whole rounds from the engine's seeded start positions, the 150 turns after each end included): every
robot's x, y, headings, velocity and energy within 1e-6 every turn. Later rounds replay only if the twin keeps what
the Java robot keeps in static fields (visit counts, hit statistics, gun hit rates, the generator) across rounds.
"""

import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from confront.arena.bots import BOT_NAMES, ScriptedBots
from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario
from confront.arena.strictmath import strict_cos, strict_sin
from confront.arena.tech import TECH_ROBOTS, TechBots, poses_per_turn

TRACES = Path(__file__).parents[1] / "fixtures" / "traces" / "tech"
FIXTURES = sorted(p.stem for p in TRACES.glob("*.jsonl"))


def _load(name: str) -> tuple[dict, list[np.ndarray]]:
    lines = [json.loads(ln) for ln in (TRACES / f"{name}.jsonl").read_text().splitlines()]
    rounds: dict[int, list] = {}
    for ln in lines[1:]:
        rounds.setdefault(ln["round"], []).append(ln["robots"])
    return lines[0], [np.array(rounds[r]) for r in sorted(rounds)]


def _replay(name: str, forget_between_rounds: bool = False) -> tuple[list[np.ndarray], list[np.ndarray]]:
    head, eng = _load(name)
    names = head["robots"]
    sc = get_scenario("melee").replace(teams=(1, 1), turns_after_end=150, max_turns=100000)
    arena = Arena(sc, 1, seed=head["seed"], order="engine")
    samples = ScriptedBots(arena, [n if n in BOT_NAMES else None for n in names])
    tech = TechBots(arena, [n if n in TECH_ROBOTS else None for n in names], rounds_per_battle=1 if
                    forget_between_rounds else 35)
    return eng, poses_per_turn(arena, [samples, tech], [len(r) for r in eng])


def _first_difference(eng: np.ndarray, sim: np.ndarray) -> int:
    """First turn (1-based) where a robot differs by more than 1e-6; 0 if none."""
    n = min(len(eng), len(sim))
    bad = np.flatnonzero(np.abs(eng[:n] - sim[:n]).max(axis=(1, 2)) > 1e-6)
    if bad.size:
        return int(bad[0]) + 1
    return 0 if len(eng) == len(sim) else n + 1


def test_every_technique_robot_has_a_trace_of_500_turns():
    covered = set()
    for name in FIXTURES:
        head, eng = _load(name)
        assert sum(len(r) for r in eng) >= 500 and len(eng) >= 2
        covered |= set(head["robots"]) & set(TECH_ROBOTS)
    assert covered == set(TECH_ROBOTS)


@pytest.mark.parametrize("name", FIXTURES)
def test_engine_rounds_replay_exactly(name):
    eng, sim = _replay(name)
    assert len(sim) == len(eng)
    for r, (e, s) in enumerate(zip(eng, sim, strict=True)):
        assert _first_difference(e, s) == 0, f"{name} round {r}"


def test_later_rounds_need_the_battle_memory():
    """A GuessFactor gun that forgets its visit counts between rounds aims differently in round 2."""
    eng, sim = _replay("tech_orbitgf_crazy", forget_between_rounds=True)
    assert _first_difference(eng[0], sim[0]) == 0
    assert _first_difference(eng[1], sim[1]) > 0


def _bits(x: float) -> int:
    return struct.unpack("<q", struct.pack("<d", x))[0]


@pytest.mark.parametrize("x,sin_bits,cos_bits", [
    # StrictMath.sin / cos under Java 17 (Double.doubleToLongBits)
    (0.5, 4602308182625945072, 4606079780542709072),
    (1.2345, 4606677865437197341, 4599616248165729966),
    (-2.9, -4625584151045066525, -4616451203647979319),
    (3.9269908169872414, -4618827765636973620, -4618827765636973618),
    (17.25, -4616193342789623473, -4639426569300090685),
    (-40.1, -4619118687258812490, -4618549564230103097),
    (1e-9, 4472406533629990549, 4607182418800017408),
    (math.pi / 2, 4607182418800017408, 4364452196894661639),
])
def test_strict_sin_cos_are_javas_bits(x, sin_bits, cos_bits):
    assert _bits(strict_sin(x)) == sin_bits
    assert _bits(strict_cos(x)) == cos_bits
