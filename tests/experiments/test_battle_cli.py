"""`confront battle` in the simulator: one Robocode-like battle by default, split on request, a real replay."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

from click.testing import CliRunner

from confront.arena.bots import bot_battle
from confront.arena.scenarios import get_scenario
from confront.cli.main import cli


def _totals(output: str) -> dict[str, float]:
    rows = [ln.split("|") for ln in output.splitlines() if ln.startswith("| ") and ln[2].isdigit()]
    return {r[2].strip(): float(r[3]) for r in rows}


def test_battle_is_one_battle_unless_split_and_records_its_first_round(tmp_path: Path) -> None:
    runner = CliRunner()
    out = tmp_path / "r" / "first.replay.json.gz"
    args = ["battle", "--robots", "Tracker,RamFire", "--rounds", "6", "--seed", "3"]
    res = runner.invoke(cli, [*args, "--replay", str(out)])
    assert res.exit_code == 0, res.output
    parts, _ = bot_battle(["Tracker", "RamFire"], 6, seed=3, n_battles=1, scenario=get_scenario("1v1"))
    want = {"Tracker": round(float(parts[0].sum()), 1), "RamFire": round(float(parts[1].sum()), 1)}
    assert _totals(res.output) == want
    split = runner.invoke(cli, [*args, "--battles", "3"])
    assert split.exit_code == 0 and _totals(split.output) != want  # other battles, other scores
    data = json.loads(gzip.open(out).read())
    assert set(data["round"]) == {1} and data["n_frames"] == len(data["turn"]) > 100
    assert data["turn"][:3] == [0, 1, 2] and data["names"] == ["Tracker (0)", "RamFire (1)"]
    assert (out.parent / "first.gif").stat().st_size > 10_000 and (out.parent / "first.html").exists()
    bad = runner.invoke(cli, ["battle", "--robots", "Tracker,RamFire", "--battles", "0"])
    assert bad.exit_code == 2 and "'--battles': 0 is not in the range x>=1" in bad.output
