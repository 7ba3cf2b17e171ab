"""``confront rumble`` in the real engine: a folder of sample robots, a corrupt jar, a robot that throws in run(),
one that never returns from its turn and one that overruns its time give a complete table with the bad ones and
their reasons (exit 0); the same command again plays no battle; a trained run is exported on the way; a local Ray
cluster gives the same table."""

from __future__ import annotations

import json
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from confront.cli.main import cli
from confront.engine.install import EngineInstall
from confront.engine.rumble import sample_jars

pytestmark = pytest.mark.engine

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "rumble"
REPO = Path(__file__).resolve().parents[2]
SAMPLES = ("SpinBot", "Crazy")


def bad_robot_jars(install: EngineInstall, folder: Path) -> None:
    """The fixtures' robots (rumblebad.Thrower, rumblebad.Hanger, rumblebad.Slow) compiled into a jar each, and a
    jar of random bytes."""
    build = folder.parent / "build"
    sources = sorted((FIXTURES / "rumblebad").glob("*.java"))
    subprocess.run([install.javac, "-nowarn", "-encoding", "UTF-8", "-cp", install.classpath, "-d", str(build),
                    *map(str, sources)], check=True, capture_output=True)
    for src in sources:
        with zipfile.ZipFile(folder / f"rumblebad.{src.stem}_1.0.jar", "w") as z:
            for f in sorted((build / "rumblebad").glob(f"{src.stem}*.class")):
                z.write(f, f"rumblebad/{f.name}")
            z.write(src.with_suffix(".properties"), f"rumblebad/{src.stem}.properties")
    (folder / "corrupt.jar").write_bytes(np.random.default_rng(0).bytes(3000))


@pytest.fixture(scope="module")
def folder(install: EngineInstall, tmp_path_factory: pytest.TempPathFactory) -> Path:
    f = tmp_path_factory.mktemp("rumble") / "robots"
    sample_jars(f, SAMPLES, install=install)
    bad_robot_jars(install, f)
    return f


def _rows(out: Path) -> dict[str, dict]:
    return {r["opponent"]: r for r in json.loads((out / "rumble.json").read_text())["rows"]}


def test_rumble_bad_robots_and_resume(folder: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ["rumble", "sample.Tracker", str(folder), "--rounds", "2", "--workers", "2", "--out", str(out), "--quiet"]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 0, res.output
    assert "5 battle(s) played, 0 already done" in res.output
    rows = _rows(out)
    assert sorted(rows) == ["corrupt", "rumblebad.Hanger 1.0", "rumblebad.Slow 1.0", "rumblebad.Thrower 1.0",
                            "sample.Crazy 1.0", "sample.SpinBot 1.0"]
    assert rows["corrupt"]["status"] == "not loaded" and rows["corrupt"]["battles"] == 0
    assert "corrupt.jar is not a readable jar (File is not a zip file)" in rows["corrupt"]["reason"]
    thrower = rows["rumblebad.Thrower 1.0"]
    assert thrower["status"] == "throws"
    assert "IllegalStateException: Thrower fails on purpose in run()" in thrower["reason"]
    assert thrower["aps"] == 1.0  # it never scores
    hanger = rows["rumblebad.Hanger 1.0"]
    assert hanger["status"] == "hangs" and "rumblebad.Hanger 1.0 is not stopping" in hanger["reason"]
    slow = rows["rumblebad.Slow 1.0"]  # 60 ms every tenth turn at a 10 ms CPU constant
    assert slow["status"] == "overran its time" and slow["battles"] == 1
    assert "skipped turn(s) (rumblebad.Slow 1.0: skipped round=0 skipped turn " in slow["reason"]
    for name in ("sample.Crazy 1.0", "sample.SpinBot 1.0"):
        row = rows[name]
        assert row["status"] == "ok" and row["battles"] == 1 and row["reason"] == ""
        battle = json.loads((out / "battles" / f"1v1-{name.replace(' ', '_')}-s0.json").read_text())
        ours, theirs = battle["contestants"]
        assert ours["name"] == "sample.Tracker" and theirs["name"] == name
        assert row["aps"] == pytest.approx(ours["total"] / (ours["total"] + theirs["total"]))
        assert row["survival_pct"] == pytest.approx(100 * ours["firsts"] / 2)
        assert row["bullet_dmg"] == pytest.approx(ours["bullet_dmg"])
    for f in ("rumble.md", "rumble.csv", "rumble.png"):
        assert (out / f).stat().st_size > 0
    assert "| rumblebad.Thrower 1.0 | 1.000 |" in res.output  # the Markdown table is printed
    stamps = {p.name: p.stat().st_mtime_ns for p in (out / "battles").glob("*.json")}
    assert len(stamps) == 5
    again = CliRunner().invoke(cli, args)
    assert again.exit_code == 0, again.output
    assert "0 battle(s) played, 5 already done" in again.output
    assert {p.name: p.stat().st_mtime_ns for p in (out / "battles").glob("*.json")} == stamps
    assert _rows(out) == rows


def test_trained_run_is_exported_on_the_way(folder: Path, tmp_path: Path) -> None:
    one = tmp_path / "one"
    one.mkdir()
    (one / "sample.Crazy_1.0.jar").write_bytes((folder / "sample.Crazy_1.0.jar").read_bytes())
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["rumble", str(REPO / "docs" / "results" / "tanks" / "run"), str(one), "--rounds",
                                   "1", "--workers", "1", "--out", str(out), "--quiet"])
    assert res.exit_code == 0, res.output
    assert (out / "candidate" / "confront-TankBot.jar").is_file()
    row = _rows(out)["sample.Crazy 1.0"]
    assert row["status"] == "ok" and 0.0 <= row["aps"] <= 1.0 and row["battles"] == 1
    battle = json.loads(next((out / "battles").glob("*.json")).read_text())
    assert battle["contestants"][0]["name"] == "confront.TankBot 1.0"


def test_local_ray_cluster_gives_the_same_table(folder: Path, tmp_path: Path) -> None:
    ray = pytest.importorskip("ray")
    from confront.experiments.rumble import RumbleSettings, run_rumble

    two = tmp_path / "two"
    two.mkdir()
    for name in SAMPLES:
        (two / f"sample.{name}_1.0.jar").write_bytes((folder / f"sample.{name}_1.0.jar").read_bytes())
    # a long CPU constant: no robot skips a turn on a busy machine, so both runs play the same battles
    settings = RumbleSettings("1v1", seeds=1, rounds=2, cpu_constant_ms=50.0)
    local = run_rumble("sample.Tracker", two, settings, tmp_path / "local", workers=2, progress=False)
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        on_ray = run_rumble("sample.Tracker", two, settings, tmp_path / "ray", address="auto", progress=False)
    finally:
        ray.shutdown()
    assert on_ray.stats.played == 2 and local.stats.played == 2
    assert on_ray.markdown == local.markdown  # the same table, number for number
    assert (tmp_path / "ray" / "rumble.csv").read_text() == (tmp_path / "local" / "rumble.csv").read_text()
    assert all(r.status == "ok" and r.battles == 1 for r in on_ray.rows)


@pytest.mark.parametrize("mode", ["teams", "melee"])
def test_teams_and_melee(folder: Path, tmp_path: Path, mode: str) -> None:
    two = tmp_path / "two"
    two.mkdir()
    for name in SAMPLES:
        (two / f"sample.{name}_1.0.jar").write_bytes((folder / f"sample.{name}_1.0.jar").read_bytes())
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["rumble", "sample.Tracker", str(two), "--mode", mode, "--team-size", "2",
                                   "--rounds", "2", "--field", "800x800", "--out", str(out), "--quiet"])
    assert res.exit_code == 0, res.output
    battles = [json.loads(p.read_text()) for p in sorted((out / "battles").glob("*.json"))]
    assert len(battles) == (2 if mode == "teams" else 1)  # a battle per opponent, or one melee of all three
    rows = _rows(out)
    for b in battles:
        ours = b["contestants"][0]
        assert ours["name"] == ("confrontteams.Ours (1)" if mode == "teams" else "sample.Tracker")
        for opp, theirs in zip(b["opponents"], b["contestants"][1:], strict=True):
            assert mode == "teams" or theirs["name"] == opp
            assert rows[opp]["aps"] == pytest.approx(ours["total"] / (ours["total"] + theirs["total"]))
            assert rows[opp]["survival_pct"] == pytest.approx(100 * ours["firsts"] / 2)


def test_tank_report_rumble_rows_are_the_rumbles_table(folder: Path, tmp_path: Path) -> None:
    """tank_report --rumble: the report's rows (results.json and report.md) are the rumble's own table, each APS
    the stored battle's share; a second report plays no battle, and `confront rumble` on its folder gives the same
    table."""
    import shutil

    from confront.experiments.tank_report import ReportRumble, report

    two = tmp_path / "robots"
    two.mkdir()
    for name in SAMPLES:
        shutil.copy(folder / f"sample.{name}_1.0.jar", two)
    run = tmp_path / "seed0"  # the shipped run under another name: the earlier report is found by its training
    shutil.copytree(REPO / "docs" / "results" / "tanks" / "run", run)
    summary = json.loads((run / "summary.json").read_text())
    earlier = tmp_path / "earlier.json"
    earlier.write_text(json.dumps({"runs": ["seed0x"], "rounds": 10, "play": "sampled", "engine_seeds": 1,
                                   "trained": [{k: summary[k] for k in ("rounds", "wall_time_s", "decisions")}],
                                   "engine_runs": [], "unseen": [],
                                   "rows": [{"entry": "1v1:Walls", "sim": [0.9], "engine": [0.91],
                                             "engine_runs": None, "target": 0.9}]}))
    out = tmp_path / "report"
    res = report([run], out, 10, False, 1, play="sampled", rumble=ReportRumble((two,), seeds=1, rounds=2, workers=2),
                 results_from=earlier)
    own = out / "rumble" / "robots-sampled"
    table = json.loads((own / "rumble.json").read_text())
    [rum] = res["rumbles"]
    assert rum["title"] == table["title"] == ("confront.TankBot 1.0 (1v1), 2 rounds on 800x600 x 1 seed(s), "
                                              "CPU constant 10 ms")
    assert json.dumps(rum["rows"]) == json.dumps(table["rows"])  # NaN intervals (one seed) included
    assert json.dumps(json.loads((out / "results.json").read_text())["rumbles"]) == json.dumps(res["rumbles"])
    md, own_md = (out / "report.md").read_text(), (own / "rumble.md").read_text()
    assert own_md.rstrip("\n") in md and "| 1v1:Walls |" in md
    rows = {r["opponent"]: r for r in rum["rows"]}
    assert sorted(rows) == ["sample.Crazy 1.0", "sample.SpinBot 1.0"]
    for name, row in rows.items():
        battle = json.loads((own / "battles" / f"1v1-{name.replace(' ', '_')}-s0.json").read_text())
        ours, theirs = battle["contestants"]
        assert ours["name"] == "confront.TankBot 1.0" and theirs["name"] == name
        assert row["status"] == "ok" and row["battles"] == 1
        assert row["aps"] == pytest.approx(ours["total"] / (ours["total"] + theirs["total"]))
        assert row["survival_pct"] == pytest.approx(100 * ours["firsts"] / 2)
    stamps = {p.name: p.stat().st_mtime_ns for p in (own / "battles").glob("*.json")}
    again = report([run], out, 10, False, 1, play="sampled", rumble=ReportRumble((two,), seeds=1, rounds=2),
                   results_from=out / "results.json")
    assert json.dumps(again["rumbles"]) == json.dumps(res["rumbles"])
    assert {p.name: p.stat().st_mtime_ns for p in (own / "battles").glob("*.json")} == stamps
    cli_run = CliRunner().invoke(cli, ["rumble", str(run), str(two), "--seeds", "1", "--rounds", "2",
                                       "--out", str(own), "--quiet"])
    assert cli_run.exit_code == 0, cli_run.output
    assert "0 battle(s) played, 2 already done" in cli_run.output
    assert own_md in cli_run.output  # the table the report holds, as the command prints it
