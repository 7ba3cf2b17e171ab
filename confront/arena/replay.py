"""Battle replays: a compact JSON file, a GIF and a self-contained HTML player.

Replay file (``confront-replay/1``, JSON; ``.json.gz`` is gzip-compressed)::

    {"format": "confront-replay/1", "scenario": "1v1", "width": 800, "height": 600,
     "names": ["learner", "SpinBot"], "teams": [0, 1], "n_frames": F,
     "turn": [F ints], "round": [F ints],
     "robots": [F * R * 7 ints],   # per frame, per robot: x, y, heading, gun, radar (deg), energy, alive
     "bullets": [[3k ints], ...],  # per frame: x, y, power of each flying bullet
     "scores": [F * R ints] | null}

Every quantity but ``alive`` (0/1), ``turn`` and ``round`` is stored as round(10 * value): 0.1 px, 0.1 deg,
0.1 energy, 0.1 score point.
"""

from __future__ import annotations

import gzip
import json
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from confront.arena.render import FrameData, draw_frame

FORMAT = "confront-replay/1"
N_ROBOT_FIELDS = 7  # x, y, heading, gun, radar, energy, alive


@dataclass
class Replay:
    """A recorded battle: per-frame robot rows (F, R, 7), bullets, scores. Angles in degrees."""

    width: float
    height: float
    names: list[str]
    teams: list[int]
    scenario: str = ""
    turn: list[int] = field(default_factory=list)
    round: list[int] = field(default_factory=list)
    robots: list[np.ndarray] = field(default_factory=list)  # each (R, 7) float
    bullets: list[np.ndarray] = field(default_factory=list)  # each (k, 3) float
    scores: list[np.ndarray] | None = None  # each (R,) float

    def __post_init__(self) -> None:
        if len(self.names) != len(self.teams):
            raise ValueError(f"names has {len(self.names)} entries but teams has {len(self.teams)}")

    @property
    def n_robots(self) -> int:
        """Robots per frame."""
        return len(self.names)

    def __len__(self) -> int:
        return len(self.robots)

    def add(
        self,
        *,
        turn: int,
        round: int,
        x: np.ndarray,
        y: np.ndarray,
        heading: np.ndarray,
        gun_heading: np.ndarray,
        radar_heading: np.ndarray,
        energy: np.ndarray,
        alive: np.ndarray,
        bullets: np.ndarray | None = None,
        scores: np.ndarray | None = None,
    ) -> None:
        """Append one frame; angles in radians, bullets (k, 3) as x, y, power."""
        rows = np.stack(
            [x, y, np.rad2deg(heading), np.rad2deg(gun_heading), np.rad2deg(radar_heading), energy, alive],
            axis=-1,
        ).astype(np.float64)
        if rows.shape != (self.n_robots, N_ROBOT_FIELDS):
            raise ValueError(f"frame has robot rows of shape {rows.shape}, expected ({self.n_robots}, 7)")
        self.turn.append(int(turn))
        self.round.append(int(round))
        self.robots.append(rows)
        b = np.zeros((0, 3)) if bullets is None else np.asarray(bullets, dtype=np.float64).reshape(-1, 3)
        self.bullets.append(b)
        if scores is not None:
            if self.scores is None:
                if len(self.robots) > 1:
                    raise ValueError("scores must be given from the first frame on")
                self.scores = []
            self.scores.append(np.asarray(scores, dtype=np.float64).reshape(self.n_robots))
        elif self.scores is not None:
            raise ValueError("scores missing in a frame after frames that had them")

    def frame(self, i: int) -> FrameData:
        """Frame i for :func:`confront.arena.render.draw_frame`."""
        r = self.robots[i]
        return FrameData(
            x=r[:, 0],
            y=r[:, 1],
            heading=np.deg2rad(r[:, 2]),
            gun_heading=np.deg2rad(r[:, 3]),
            radar_heading=np.deg2rad(r[:, 4]),
            energy=r[:, 5],
            alive=r[:, 6] > 0.5,
            team=np.asarray(self.teams),
            bullets=self.bullets[i],
            scores=None if self.scores is None else self.scores[i],
            text=f"round {self.round[i]}  turn {self.turn[i]}",
        )

    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready dict of the replay file format."""

        def q(a: np.ndarray) -> list[int]:
            return np.rint(np.asarray(a, dtype=np.float64) * 10.0).astype(np.int64).ravel().tolist()

        robots = np.array(self.robots).reshape(len(self), self.n_robots, N_ROBOT_FIELDS)
        packed = np.rint(robots * 10.0).astype(np.int64)
        packed[..., 6] = (robots[..., 6] > 0.5).astype(np.int64)
        return {
            "format": FORMAT,
            "scenario": self.scenario,
            "width": self.width,
            "height": self.height,
            "names": list(self.names),
            "teams": [int(t) for t in self.teams],
            "n_frames": len(self),
            "turn": list(self.turn),
            "round": list(self.round),
            "robots": packed.ravel().tolist(),
            "bullets": [q(b) for b in self.bullets],
            "scores": None if self.scores is None else q(np.array(self.scores)),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Replay:
        """Read the replay file format."""
        if d.get("format") != FORMAT:
            raise ValueError(f"replay format must be {FORMAT!r}, got {d.get('format')!r}")
        n, names = int(d["n_frames"]), list(d["names"])
        r = len(names)
        rob = np.asarray(d["robots"], dtype=np.float64)
        if rob.size != n * r * N_ROBOT_FIELDS:
            raise ValueError(f"replay robots has {rob.size} values, expected {n * r * N_ROBOT_FIELDS}")
        rob = rob.reshape(n, r, N_ROBOT_FIELDS)
        rob[..., :6] /= 10.0
        scores = None
        if d.get("scores") is not None:
            s = np.asarray(d["scores"], dtype=np.float64).reshape(n, r) / 10.0
            scores = list(s)
        return cls(
            width=float(d["width"]),
            height=float(d["height"]),
            names=names,
            teams=[int(t) for t in d["teams"]],
            scenario=str(d.get("scenario", "")),
            turn=[int(t) for t in d["turn"]],
            round=[int(t) for t in d["round"]],
            robots=list(rob),
            bullets=[np.asarray(b, dtype=np.float64).reshape(-1, 3) / 10.0 for b in d["bullets"]],
            scores=scores,
        )

    def save(self, path: str | Path) -> Path:
        """Write the replay as compact JSON (gzip when the name ends in .gz)."""
        p = Path(path)
        text = json.dumps(self.to_dict(), separators=(",", ":"))
        if p.name.endswith(".gz"):
            p.write_bytes(gzip.compress(text.encode()))
        else:
            p.write_text(text)
        return p


def record_frame(replay: Replay, arena: Any, b: int = 0) -> None:
    """Append battle b's current state of an :class:`confront.arena.core.Arena` to ``replay``."""
    s = arena.state
    k = int(s.n_bullets[b])
    slots = s.b_list[b, :k]
    sl = slots[np.isin(s.b_state[b, slots], (1, 2))]  # fired or moving
    replay.add(turn=int(s.time[b]), round=int(s.round[b]), x=s.x[b], y=s.y[b], heading=s.heading[b],
               gun_heading=s.gun_heading[b], radar_heading=s.radar_heading[b], energy=s.energy[b],
               alive=s.alive[b], bullets=np.stack([s.b_x[b, sl], s.b_y[b, sl], s.b_power[b, sl]], axis=-1),
               scores=s.score_total[b].sum(axis=-1) + s.score[b].sum(axis=-1) * ~s.decided[b])


def new_replay(arena: Any, names: list[str] | None = None) -> Replay:
    """An empty replay for an Arena's scenario (robot names default to ``team<t>.<i>``)."""
    sc = arena.scenario
    teams = sc.team_ids()
    if names is None:
        names = [f"team{t}.{i}" for i, t in enumerate(teams)]
    return Replay(float(sc.width), float(sc.height), list(names), teams, scenario=sc.name, scores=None)


def load_replay(path: str | Path) -> Replay:
    """Read a replay file (.json or .json.gz)."""
    p = Path(path)
    raw = p.read_bytes()
    if p.name.endswith(".gz"):
        raw = gzip.decompress(raw)
    return Replay.from_dict(json.loads(raw))


def _frame_indices(n: int, max_frames: int | None, every: int) -> list[int]:
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    idx = list(range(0, n, every))
    if max_frames is not None and len(idx) > max_frames:
        idx = np.linspace(0, n - 1, max_frames).round().astype(int).tolist()
    return idx


def write_gif(
    replay: Replay,
    path: str | Path,
    scale: float = 0.5,
    every: int = 2,
    fps: float = 30.0,
    max_frames: int | None = 600,
) -> Path:
    """Render the replay to an animated GIF (every ``every``-th frame, at most ``max_frames``)."""
    if len(replay) == 0:
        raise ValueError("replay has no frames")
    idx = _frame_indices(len(replay), max_frames, every)
    images = [
        Image.fromarray(draw_frame(replay.frame(i), replay.width, replay.height, scale)).quantize(64)
        for i in idx
    ]
    p = Path(path)
    images[0].save(
        p, save_all=True, append_images=images[1:], duration=max(20, int(1000 / fps)), loop=0, optimize=False
    )
    return p


def _template() -> str:
    return (resources.files("confront.arena") / "replay_assets" / "player.html").read_text()


def write_html(replay: Replay, path: str | Path, title: str | None = None) -> Path:
    """A single self-contained HTML page (inline JS + canvas) that plays the replay."""
    if len(replay) == 0:
        raise ValueError("replay has no frames")
    data = json.dumps(replay.to_dict(), separators=(",", ":")).replace("</", "<\\/")
    name = title or f"confront replay {replay.scenario}".strip()
    html = _template().replace("__TITLE__", _escape(name)).replace("__REPLAY_JSON__", data)
    p = Path(path)
    p.write_text(html)
    return p


def _escape(s: str) -> str:
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


REPLAY_SUFFIXES = (".replay.json", ".replay.json.gz")


def find_replays(source: str | Path) -> list[Path]:
    """Replay files named by ``source``: the file itself, or every ``*.replay.json[.gz]`` under a run folder."""
    p = Path(source)
    if p.is_file():
        return [p]
    if p.is_dir():
        return sorted(f for f in p.rglob("*") if f.is_file() and f.name.endswith(REPLAY_SUFFIXES))
    raise ValueError(f"replay source {str(source)!r} is neither a file nor a folder")


def export_replays(source: str | Path, out_dir: str | Path | None = None, gif: bool = True,
                   html: bool = True) -> list[Path]:
    """Write a GIF and an HTML player beside each replay of ``source`` (or into ``out_dir``); the paths."""
    written: list[Path] = []
    files = find_replays(source)
    if not files:
        raise ValueError(f"no *.replay.json[.gz] files under {str(source)!r}")
    for f in files:
        rep = load_replay(f)
        stem = f.name
        for suffix in (".gz", ".json", ".replay"):
            stem = stem.removesuffix(suffix)
        folder = Path(out_dir) if out_dir is not None else f.parent
        folder.mkdir(parents=True, exist_ok=True)
        if gif:
            written.append(write_gif(rep, folder / f"{stem}.gif"))
        if html:
            written.append(write_html(rep, folder / f"{stem}.html", title=f"confront replay {stem}"))
    return written
