"""The scripted bots replay recorded engine rounds of Robocode's own sample robots turn by turn.

Fixtures: tests/fixtures/traces/samples/*.jsonl, made by tests/fixtures/traces/samples/record_sample_bots.py (real
sample.Tracker, sample.SpinBot, sample.RamFire; fixed start positions, -DRANDOMSEED=1). Tracker's
onScannedRobot blocks for many turns while scans queue up; the engine hands it the oldest queued event first
(Event.compareTo: time before priority), so it aims from a scan one turn old, and a ram (priority 40) waits
behind an unhandled older scan (priority 10) for a turn.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from confront.arena.bots import ScriptedBots
from confront.arena.core import Arena
from confront.arena.scenarios import get_scenario

TRACES = Path(__file__).parents[1] / "fixtures" / "traces" / "samples"


def _replay(name: str) -> tuple[np.ndarray, np.ndarray]:
    lines = [json.loads(ln) for ln in (TRACES / f"{name}.jsonl").read_text().splitlines()]
    head = lines[0]
    eng = np.array([ln["robots"] for ln in lines[1:]])  # (T, R, 7)
    n = len(head["robots"])
    sc = get_scenario("melee").replace(teams=(1,) * n, initial_positions=tuple(tuple(s) for s in head["starts"]),
                                       turns_after_end=150, max_turns=100000)
    arena = Arena(sc, 1, seed=head["seed"], order="engine")
    bots = ScriptedBots(arena, head["robots"])
    cmd = arena.idle_commands()
    s = arena.state
    sim = []
    for _ in range(len(eng)):
        bots.commands(cmd)
        arena.step(cmd)
        sim.append(np.stack([s.x[0], s.y[0], s.heading[0], s.gun_heading[0], s.radar_heading[0], s.velocity[0],
                             s.energy[0]], 1))
    return eng, np.array(sim)


def _diff(eng: np.ndarray, sim: np.ndarray) -> np.ndarray:
    d = np.abs(eng - sim)
    d[..., 2:5] = np.abs((eng[..., 2:5] - sim[..., 2:5] + math.pi) % (2 * math.pi) - math.pi)
    return d.max(axis=(1, 2))


@pytest.mark.parametrize("name,turns", [("sample_tracker_spinbot", 400), ("sample_tracker_ramfire", 250)])
def test_tracker_matches_the_engine_turn_by_turn(name, turns):
    eng, sim = _replay(name)
    assert len(eng) == turns
    # while both robots live (after a death the winner's victory dance is not scripted)
    alive = (eng[:, :, 6] > 0).all(axis=1)
    last = int(np.argmin(alive)) if not alive.all() else len(eng)
    assert last > 200
    bad = np.flatnonzero(_diff(eng[:last], sim[:last]) > 1e-6)
    assert bad.size == 0, f"first difference in turn {bad[0] + 1}: engine {eng[bad[0]]}, simulator {sim[bad[0]]}"


def test_tracker_aims_from_the_older_scan():
    """Hand check of one turn of the fixture: Tracker's gun turn comes from the queued scan of the turn before."""
    eng, sim = _replay("sample_tracker_spinbot")
    # the simulator's Tracker turns its gun exactly as the engine's whenever it turns it at all
    dg = np.diff(np.unwrap(eng[:200, 0, 3]))
    dg_sim = np.diff(np.unwrap(sim[:200, 0, 3]))
    assert np.abs(dg).max() > 0.1
    np.testing.assert_allclose(dg_sim, dg, atol=1e-9)
