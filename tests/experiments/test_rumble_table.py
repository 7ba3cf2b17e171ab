"""The rumble's table without the engine: shares, intervals and reasons from hand-made battle results, the battle
plan, reading jars and the engine's words, and the command's one-line refusals."""

from __future__ import annotations

import json
import math
import zipfile
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from confront.cli.main import cli
from confront.engine.rumble import Robot, folder_robots, jar_robots, job_key, robot_problems
from confront.experiments.rumble import (
    RumbleSettings,
    battle_shares,
    parse_field,
    plan_jobs,
    table_rows,
    to_csv,
    to_markdown,
)


def _score(name: str, total: float, firsts: int = 0, bullet_dmg: float = 0.0) -> dict[str, Any]:
    return {"name": name, "total": total, "firsts": firsts, "bullet_dmg": bullet_dmg}


def _battle(opponents: list[str], rows: list[dict[str, Any]], rounds: int = 10, status: str = "ok",
            problems: dict[str, str] | None = None, reason: str = "") -> dict[str, Any]:
    return {"opponents": opponents, "contestants": rows, "rounds": rounds, "status": status,
            "problems": problems or {}, "reason": reason}


def test_table_of_two_seeds_by_hand() -> None:
    a, b = Robot("x.A 1.0", "a.jar"), Robot("x.B 1.0", "b.jar")
    results = [
        # seed 0 against A: 60 of 100 points, 3 of 10 rounds first, 40 bullet damage
        _battle([a.name], [_score("me", 60.0, 3, 40.0), _score(a.name, 40.0, 7)]),
        # seed 1 against A: 80 of 100, 5 of 10 first, 60 damage
        _battle([a.name], [_score("me", 80.0, 5, 60.0), _score(a.name, 20.0, 5)]),
        _battle([b.name], [_score("me", 30.0, 1, 10.0), _score(b.name, 90.0, 9)]),
    ]
    rows = {r.opponent: r for r in table_rows([a, b], results, "me")}
    ra = rows[a.name]
    assert ra.battles == 2 and ra.status == "ok" and ra.reason == ""
    assert ra.aps == pytest.approx(0.7)
    # t(0.975, 1) = 12.7062, s = sqrt(0.02) = 0.141421, s / sqrt(2) = 0.1: half width 1.27062
    assert ra.aps_lo == pytest.approx(0.7 - 1.270620, abs=1e-5)
    assert ra.aps_hi == pytest.approx(0.7 + 1.270620, abs=1e-5)
    assert ra.survival_pct == pytest.approx(40.0) and ra.bullet_dmg == pytest.approx(50.0)
    rb = rows[b.name]
    assert rb.aps == pytest.approx(0.25) and math.isnan(rb.aps_lo) and math.isnan(rb.aps_hi)
    assert rb.survival_pct == pytest.approx(10.0)
    md = to_markdown(list(rows.values()), "t")
    assert "| x.A 1.0 | 0.700 | [-0.571, 1.971] | 40.0 | 50.0 | 2 | ok |" in md
    assert "APS over 2 opponent(s): 0.475" in md
    assert to_csv(list(rows.values())).splitlines()[0].startswith("opponent,status,battles,aps,")


def test_melee_shares_are_pairwise() -> None:
    res = _battle(["o.A", "o.B"], [_score("me", 100.0, 2, 80.0), _score("o.A", 300.0), _score("o.B", 0.0)], rounds=4)
    assert battle_shares(res) == {"o.A": (0.25, 0.5, 80.0), "o.B": (1.0, 0.5, 80.0)}
    assert battle_shares({**res, "status": "failed"}) == {}


def test_reasons_most_serious_first_and_unplayable_rows() -> None:
    bad = Robot("corrupt", "corrupt.jar", problem="not loaded: corrupt.jar is not a readable jar (x)")
    hang = Robot("x.H 1.0", "h.jar")
    results = [
        _battle([hang.name], [_score("me", 10.0), _score(hang.name, 0.0)],
                problems={hang.name: "hangs: Robot x.H 1.0 is not stopping", "me": "overran its time: 2 skipped"}),
        _battle([hang.name], [], status="timed out", reason="timed out: killed after 60 s"),
    ]
    rows = table_rows([bad, hang], results, "me")
    assert rows[0].status == "not loaded" and rows[0].battles == 0 and math.isnan(rows[0].aps)
    assert rows[1].status == "timed out" and rows[1].battles == 1 and rows[1].aps == pytest.approx(1.0)
    assert rows[1].reason == "timed out: killed after 60 s; candidate overran its time: 2 skipped"


def test_engine_words_are_read_per_robot() -> None:
    summary = {
        "errors": ["Robot x.H 1.0 is not stopping.  Forcing a stop.", "Can't find 'x.Gone 2.0'"],
        "messages": ["Round 1 initializing..", ".x.T 1.0: Exception: java.lang.IllegalStateException: boom\n."],
        "robot_reports": ["x.S 1.0: skipped round=0 turn 31"],
        "skipped_turns": {"x.S 1.0": 3},
    }
    found = robot_problems(summary, ["x.H 1.0", "x.Gone 2.0", "x.T 1.0", "x.S 1.0", "x.Fine 1.0"])
    assert found == {
        "x.H 1.0": "hangs: Robot x.H 1.0 is not stopping. Forcing a stop",
        "x.Gone 2.0": "not loaded: Can't find 'x.Gone 2.0'",
        "x.T 1.0": "throws: x.T 1.0: Exception: java.lang.IllegalStateException: boom",
        "x.S 1.0": "overran its time: 3 skipped turn(s) (x.S 1.0: skipped round=0 turn 31)",
    }
    # a robot whose name begins another's (the candidate sample.Tracker, the jar's sample.Tracker 1.0)
    other = {"errors": ["Robot sample.Tracker 1.0 (2) is not stopping."], "skipped_turns": {"sample.Tracker (1)": 2}}
    assert robot_problems(other, ["sample.Tracker", "sample.Tracker 1.0"]) == {
        "sample.Tracker": "overran its time: 2 skipped turn(s)",
        "sample.Tracker 1.0": "hangs: Robot sample.Tracker 1.0 (2) is not stopping"}


def test_jars_and_teams_are_read_from_properties(tmp_path: Path) -> None:
    with zipfile.ZipFile(tmp_path / "a.jar", "w") as z:
        z.writestr("p/Bot.properties", "#c\nrobot.classname=p.Bot\nrobot.version=2.1\n")
        z.writestr("p/Bot.class", b"\xca\xfe")
        z.writestr("p/Duo.team", "team.members=p.Bot 2.1,p.Bot 2.1\nteam.version=1.0\n")
    (tmp_path / "b.jar").write_bytes(b"not a zip at all")
    with zipfile.ZipFile(tmp_path / "c.jar", "w") as z:
        z.writestr("readme.txt", "no robot")
    robots = folder_robots(tmp_path)
    assert [(r.name, r.jar, r.members) for r in robots] == [
        ("p.Bot 2.1", "a.jar", ()), ("p.Duo 1.0", "a.jar", ("p.Bot 2.1", "p.Bot 2.1")),
        ("b", "b.jar", ()), ("c", "c.jar", ())]
    assert robots[2].problem.startswith("not loaded: b.jar is not a readable jar")
    assert "holds no robot" in jar_robots(tmp_path / "c.jar")[0].problem


def test_plan_keys_and_melee_groups() -> None:
    me = Robot("sample.Tracker")
    opps = [Robot(f"o.R{i} 1.0", f"r{i}.jar") for i in range(12)]
    one = plan_jobs(me, opps[:2], RumbleSettings("1v1", seeds=2))
    assert [j.key for j in one] == ["1v1-o.R0_1.0-s0", "1v1-o.R1_1.0-s0", "1v1-o.R0_1.0-s1", "1v1-o.R1_1.0-s1"]
    assert (one[0].rounds, one[0].width, one[0].height) == (35, 800, 600)
    melee = plan_jobs(me, opps, RumbleSettings("melee", seeds=2))
    assert [len(j.opponents) for j in melee] == [9, 3, 9, 3]
    for seed in (0, 1):  # every opponent meets the candidate once per seed
        met = [o.name for j in melee if j.seed == seed for o in j.opponents]
        assert sorted(met) == sorted(o.name for o in opps)
    assert melee[0].key == job_key("melee", melee[0].opponents, 0) and melee[0].width == 1000
    teams = plan_jobs(me, opps[:1], RumbleSettings("teams", team_size=3))
    assert teams[0].spec().robot_count == 6 and teams[0].rounds == 10 and teams[0].width == 1200


def test_settings_and_field_refused() -> None:
    assert parse_field("1000x800") == (1000, 800)
    for bad in ("800", "x600", "800x600x2", "-800x600"):
        with pytest.raises(ValueError, match="WIDTHxHEIGHT"):
            parse_field(bad)
    with pytest.raises(ValueError, match="400..5000"):
        RumbleSettings(width=300, height=600)
    with pytest.raises(ValueError, match="mode must be"):
        RumbleSettings("duel")


def _jar(path: Path, cls: str) -> Path:
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(cls.replace(".", "/") + ".properties", f"robot.classname={cls}\n")
    return path


@pytest.mark.parametrize("args, words", [
    (["{tmp}/me.jar", "{tmp}/nope"], "no such folder"),
    (["{tmp}/me.jar", "{tmp}/empty"], "no robots in"),
    (["{tmp}/gone.jar", "{tmp}/empty"], "no such robot jar"),
    (["{tmp}/me.jar", "{tmp}/empty", "--field", "10x10"], "field must be 400..5000"),
    (["{tmp}/me.jar", "{tmp}/empty", "--mode", "duel"], "'duel' is not one of"),
    (["{tmp}/me.jar", "{tmp}/empty", "--field", "big"], "field must be WIDTHxHEIGHT"),
    (["{tmp}/me.jar", "{tmp}/empty", "--seeds", "0"], "--seeds"),
])
def test_bad_input_is_one_line(tmp_path: Path, args: list[str], words: str) -> None:
    (tmp_path / "empty").mkdir()
    _jar(tmp_path / "me.jar", "p.Me")
    res = CliRunner().invoke(cli, ["rumble", *(a.format(tmp=tmp_path) for a in args)])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and words in lines[0] and "Traceback" not in res.output


def test_changed_settings_refused(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "settings.json").write_text(json.dumps({"candidate": "other"}))
    (tmp_path / "f").mkdir()
    _jar(tmp_path / "f" / "a.jar", "p.Bot")
    res = CliRunner().invoke(cli, ["rumble", str(_jar(tmp_path / "me.jar", "p.Me")), str(tmp_path / "f"), "--out",
                                   str(out)])
    assert res.exit_code == 2 and "holds a rumble with other settings" in res.output


def test_a_battle_that_cannot_run_is_a_row_and_not_stored(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import confront.engine.rumble as rumble

    def broken(job: object, jars: object) -> dict[str, Any]:
        raise RuntimeError("javac failed:\nsomething")

    monkeypatch.setattr(rumble, "_play_from_files", broken)
    jobs = plan_jobs(Robot("sample.Tracker"), [Robot("o.A 1.0", "a.jar")], RumbleSettings(seeds=2))
    stats = rumble.run_jobs(jobs, {"a.jar": tmp_path / "a.jar"}, tmp_path / "battles", progress=False)
    assert stats.played == 0 and len(stats.unplayed) == 2 and not (tmp_path / "battles").exists()
    row = table_rows([Robot("o.A 1.0", "a.jar")], stats.unplayed, "sample.Tracker")[0]
    assert row.status == "failed" and row.battles == 0
    assert row.reason == ("failed: the battle could not be run (RuntimeError: javac failed: something); the next run "
                          "tries it again")
