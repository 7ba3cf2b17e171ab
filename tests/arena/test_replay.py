"""Replay file round trip, recording from the SMDP env, GIF, rendering, and the HTML player in Chromium."""

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from confront.arena.render import TEAM_COLOURS, FrameData, draw_frame
from confront.arena.replay import Replay, load_replay, write_gif, write_html
from confront.arena.smdp import SMDPConfig, TeamBattleEnv


def _synthetic(n: int = 60) -> Replay:
    rp = Replay(800.0, 600.0, ["a", "b"], [0, 1], scenario="1v1")
    for t in range(n):
        rp.add(turn=t, round=1, x=np.array([100.0 + 2 * t, 600.0]), y=np.array([300.0, 300.0 - t]),
               heading=np.array([np.pi / 2, np.pi]), gun_heading=np.array([0.1 * t, 1.0]),
               radar_heading=np.array([0.2 * t, 2.0]), energy=np.array([100.0 - 0.5 * t, 80.0]),
               alive=np.array([True, t < 50]), bullets=np.array([[300.0 + 5 * t, 310.0, 2.0]]),
               scores=np.array([t, 2.0 * t]))
    return rp


def test_replay_round_trip(tmp_path: Path) -> None:
    rp = _synthetic()
    for name in ("r.json", "r.json.gz"):
        back = load_replay(rp.save(tmp_path / name))
        assert len(back) == 60 and back.names == ["a", "b"] and back.teams == [0, 1]
        np.testing.assert_allclose(back.robots[10][0], [120.0, 300.0, 90.0, 57.3, 114.6, 95.0, 1.0], atol=0.051)
        assert back.robots[55][1, 6] == 0.0
        np.testing.assert_allclose(back.bullets[3], [[315.0, 310.0, 2.0]])
        assert back.scores is not None and back.scores[7].tolist() == [7.0, 14.0]
    d = json.loads((tmp_path / "r.json").read_text())
    assert d["format"] == "confront-replay/1" and all(isinstance(v, int) for v in d["robots"][:14])


def test_replay_bad_input() -> None:
    with pytest.raises(ValueError, match="format"):
        Replay.from_dict({"format": "other"})
    rp = Replay(800.0, 600.0, ["a"], [0])
    with pytest.raises(ValueError, match="shape"):
        z = np.zeros(2)
        rp.add(turn=0, round=0, x=z, y=z, heading=z, gun_heading=z, radar_heading=z, energy=z, alive=z)


def test_recording_from_env_follows_the_battle(tmp_path: Path) -> None:
    env = TeamBattleEnv("1v1", 2, seed=1, opponents="SpinBot", config=SMDPConfig(turns_per_step=5))
    env.reset()
    rep = env.start_recording(battle=1)
    for _ in range(10):
        env.step(np.zeros((2, 2), dtype=np.int64))
    env.stop_recording()
    assert len(rep) == 51  # the start frame and 50 turns
    assert rep.turn[:3] == [0, 1, 2]
    s = env.arena.state
    np.testing.assert_allclose(rep.robots[-1][:, 0], s.x[1], atol=1e-9)
    np.testing.assert_allclose(rep.robots[-1][:, 5], s.energy[1], atol=1e-9)
    back = load_replay(rep.save(tmp_path / "b.json"))
    np.testing.assert_allclose(back.robots[-1][:, :2], rep.robots[-1][:, :2], atol=0.05)


def test_draw_frame_pixels() -> None:
    f = FrameData(x=np.array([100.0, 500.0]), y=np.array([100.0, 400.0]), heading=np.zeros(2),
                  gun_heading=np.full(2, np.pi), radar_heading=np.full(2, np.pi), energy=np.array([100.0, 50.0]),
                  alive=np.array([True, False]), team=np.array([0, 1]), bullets=np.array([[300.0, 300.0, 3.0]]))
    img = draw_frame(f, 800.0, 600.0, scale=1.0)
    assert img.shape == (600, 800, 3)
    assert tuple(img[600 - 110, 100]) == TEAM_COLOURS[0]  # body ahead of the centre (gun points south)
    assert tuple(img[600 - 410, 500]) == (90, 90, 90)  # dead robot is grey
    assert tuple(img[300, 300]) == (255, 255, 255)  # bullet
    assert tuple(img[5, 795]) == (24, 26, 32)  # empty field


def test_write_gif(tmp_path: Path) -> None:
    p = write_gif(_synthetic(), tmp_path / "r.gif", every=3)
    with Image.open(p) as im:
        assert im.n_frames == 20 and im.size == (400, 300)


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def _run_chromium(args: list[str], url: str, profile: Path) -> subprocess.CompletedProcess:
    base = [_chromium() or "chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
            "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync",
            f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0"]
    return subprocess.run(base + args + [url], capture_output=True, text=True, timeout=120)


@pytest.mark.browser
def test_html_player_in_headless_chromium(tmp_path: Path) -> None:
    if _chromium() is None:
        pytest.skip("chromium not installed")
    page = write_html(_synthetic(120), tmp_path / "r.html")
    url = page.resolve().as_uri()
    dom = _run_chromium(["--virtual-time-budget=1500", "--dump-dom"], url, tmp_path / "p1")
    m = re.search(r'<body[^>]*data-frame="(\d+)"', dom.stdout)
    assert m is not None, dom.stderr[-2000:]
    assert int(m.group(1)) > 10  # frames advanced while playing
    assert "data-errors" not in dom.stdout
    console = [ln for ln in dom.stderr.splitlines() if "CONSOLE" in ln or "Uncaught" in ln]
    assert console == []
    shot = tmp_path / "shot.png"
    _run_chromium(["--hide-scrollbars", "--window-size=1000,800", "--virtual-time-budget=300",
                   f"--screenshot={shot}"], url, tmp_path / "p2")
    img = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    for colour in TEAM_COLOURS[:2]:  # both teams' tanks are on screen
        hits = np.all(np.abs(img - np.array(colour)) <= 3, axis=-1).sum()
        assert hits > 100, colour


def test_export_replays_from_a_run_folder(tmp_path: Path) -> None:
    run = tmp_path / "run" / "replays"
    run.mkdir(parents=True)
    _synthetic(10).save(run / "round1.replay.json.gz")
    _synthetic(10).save(run / "round2.replay.json")
    (run / "other.json").write_text("{}")
    from confront.arena.replay import export_replays, find_replays

    assert [p.name for p in find_replays(tmp_path / "run")] == ["round1.replay.json.gz", "round2.replay.json"]
    out = export_replays(tmp_path / "run", tmp_path / "out")
    assert sorted(p.name for p in out) == ["round1.gif", "round1.html", "round2.gif", "round2.html"]
    assert "__REPLAY_JSON__" not in (tmp_path / "out" / "round1.html").read_text()
    with pytest.raises(ValueError, match="neither"):
        find_replays(tmp_path / "missing")


def _hostile(n: int = 120) -> Replay:
    rp = _synthetic(n)
    rp.names = ["<!--<script>", "</script><b>&amp;__TITLE__"]
    return rp


def test_html_player_escapes_robot_names(tmp_path: Path) -> None:
    """Issue 34 item 17: a robot name cannot end the player's script, open a comment or fill a placeholder."""
    page = write_html(_hostile(), tmp_path / "r.html", title="x __REPLAY_JSON__ <y>").read_text()
    script = page[page.index("const R = "):]
    script = script[:script.index("</script>")]
    assert "<!--" not in script and "<script" not in script
    data = json.loads(script.removeprefix("const R = ").split(";\n", 1)[0])
    assert data["names"] == ["<!--<script>", "</script><b>&amp;__TITLE__"]
    assert "<title>x __REPLAY_JSON__ &lt;y&gt;</title>" in page


@pytest.mark.browser
def test_html_player_with_hostile_names_plays_in_chromium(tmp_path: Path) -> None:
    if _chromium() is None:
        pytest.skip("chromium not installed")
    url = write_html(_hostile(), tmp_path / "r.html").resolve().as_uri()
    dom = _run_chromium(["--virtual-time-budget=1500", "--dump-dom"], url, tmp_path / "p1")
    m = re.search(r'<body[^>]*data-frame="(\d+)"', dom.stdout)
    assert m is not None and int(m.group(1)) > 10, dom.stderr[-2000:]
    assert "&lt;!--&lt;script&gt;" in dom.stdout


def test_replay_outputs_replace_a_link_instead_of_following_it(tmp_path: Path) -> None:
    """Issue 34 item 3: a symlinked output name is replaced by the new file; the link's target is unchanged."""
    from confront.arena.replay import export_replays

    target = tmp_path / "precious.txt"
    target.write_text("keep")
    _synthetic(10).save(tmp_path / "ok.replay.json")
    for name in ("ok.html", "ok.gif"):
        (tmp_path / name).symlink_to(target)
    export_replays(tmp_path / "ok.replay.json")
    assert target.read_text() == "keep"
    assert not (tmp_path / "ok.html").is_symlink() and "const R" in (tmp_path / "ok.html").read_text()
    assert not (tmp_path / "ok.gif").is_symlink()
    (tmp_path / "r.json").symlink_to(target)
    _synthetic(5).save(tmp_path / "r.json")
    assert target.read_text() == "keep" and len(load_replay(tmp_path / "r.json")) == 5
