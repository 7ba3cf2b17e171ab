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

Reading is strict: a replay file is at most 64 MB of JSON (also after gunzip), the field is within Robocode's
400-5000 range per side [BattlefieldSpecification], 1-256 robots, at most 200,000 frames and 3 million robot rows,
and every list has the length and kind of values the format says; anything else is a :class:`ReplayError`
naming the file and the problem. GIFs are drawn at most ``MAX_GIF_SIDE`` pixels wide or high.
"""

from __future__ import annotations

import gzip
import io
import json
import re
import zlib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from confront.arena.render import FrameData, draw_frame
from confront.checkpoint import write_atomic

FORMAT = "confront-replay/1"
N_ROBOT_FIELDS = 7  # x, y, heading, gun, radar, energy, alive
FIELD_RANGE = (400.0, 5000.0)  # Robocode's battlefield width and height [BattlefieldSpecification]
MAX_ROBOTS = 256
MAX_FRAMES = 200_000  # a round ends after at most max_turns turns; the longest recorded one has 100,000
MAX_ROBOT_ROWS = 3_000_000  # frames x robots
MAX_BULLETS = 100_000  # flying bullets in one frame
MAX_VALUE = 10**9  # |stored value| (tenths)
MAX_NAME = 200  # characters of a robot name
MAX_BYTES = 64 << 20  # a replay's JSON text, also after gunzip
MAX_GIF_SIDE = 1000  # pixels


class ReplayError(ValueError):
    """A replay file that is not a valid ``confront-replay/1`` file within the limits; one line."""


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
            raise ReplayError(f"names has {len(self.names)} entries but teams has {len(self.teams)}")
        for key, v in (("width", self.width), ("height", self.height)):
            if not FIELD_RANGE[0] <= v <= FIELD_RANGE[1]:
                raise ReplayError(f"{key} {v!r} is outside Robocode's {FIELD_RANGE[0]:.0f}-{FIELD_RANGE[1]:.0f}")
        if not 1 <= len(self.names) <= MAX_ROBOTS:
            raise ReplayError(f"{len(self.names)} robots: a replay holds 1 to {MAX_ROBOTS}")
        if any(not isinstance(n, str) or len(n) > MAX_NAME for n in self.names):
            raise ReplayError(f"robot names must be strings of at most {MAX_NAME} characters")
        if any(isinstance(t, bool) or not isinstance(t, int) or not 0 <= t < len(self.names) for t in self.teams):
            raise ReplayError(f"teams must be integers in [0, {len(self.names)})")

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
    def from_dict(cls, d: Any) -> Replay:
        """Read the replay file format; anything outside it or its limits is a :class:`ReplayError`."""
        if not isinstance(d, dict) or d.get("format") != FORMAT:
            got = d.get("format") if isinstance(d, dict) else type(d).__name__
            raise ReplayError(f"replay format must be {FORMAT!r}, got {str(got)[:60]!r}")
        missing = [k for k in ("width", "height", "names", "teams", "n_frames", "turn", "round", "robots", "bullets")
                   if k not in d]
        if missing:
            raise ReplayError(f"replay lacks the keys {', '.join(missing)}")
        width, height = _number(d, "width"), _number(d, "height")
        names, teams = d["names"], d["teams"]
        if not isinstance(names, list) or not isinstance(teams, list):
            raise ReplayError("replay names and teams must be lists")
        n, r = _count(d, "n_frames", 1, MAX_FRAMES), len(names)
        if not 1 <= r <= MAX_ROBOTS or n * r > MAX_ROBOT_ROWS:
            raise ReplayError(f"{n} frames of {r} robots: a replay holds 1 to {MAX_ROBOTS} robots and at most "
                              f"{MAX_ROBOT_ROWS} robot rows")
        rep = cls(width=width, height=height, names=list(names), teams=list(teams),
                  scenario=str(d.get("scenario", ""))[:MAX_NAME])
        rep.turn, rep.round = _ints(d, "turn", n).tolist(), _ints(d, "round", n).tolist()
        rob = _ints(d, "robots", n * r * N_ROBOT_FIELDS).astype(np.float64).reshape(n, r, N_ROBOT_FIELDS)
        rob[..., :6] /= 10.0
        rep.robots = list(rob)
        bullets = d["bullets"]
        if not isinstance(bullets, list) or len(bullets) != n:
            raise ReplayError(f"replay bullets must be a list of {n} frames")
        rep.bullets = []
        for i, b in enumerate(bullets):
            if not isinstance(b, list) or len(b) % 3 or len(b) > 3 * MAX_BULLETS:
                raise ReplayError(f"replay bullets of frame {i} must be x, y, power triples (at most {MAX_BULLETS})")
            rep.bullets.append(_ints({"b": b}, "b", len(b)).astype(np.float64).reshape(-1, 3) / 10.0)
        if d.get("scores") is not None:
            rep.scores = list(_ints(d, "scores", n * r).astype(np.float64).reshape(n, r) / 10.0)
        return rep

    def save(self, path: str | Path) -> Path:
        """Write the replay as compact JSON (gzip when the name ends in .gz)."""
        p = Path(path)
        data = json.dumps(self.to_dict(), separators=(",", ":")).encode()
        write_atomic(p, gzip.compress(data) if p.name.endswith(".gz") else data)
        return p


def _number(d: dict[str, Any], key: str) -> float:
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ReplayError(f"replay {key} must be a number, got {str(v)[:60]!r}")
    return float(v)


def _count(d: dict[str, Any], key: str, lo: int, hi: int) -> int:
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise ReplayError(f"replay {key} must be an integer in [{lo}, {hi}], got {str(v)[:60]!r}")
    return v


def _ints(d: dict[str, Any], key: str, size: int) -> np.ndarray:
    """``d[key]``: a flat list of ``size`` integers within +-MAX_VALUE."""
    v = d[key]
    if not isinstance(v, list) or len(v) != size:
        n = len(v) if isinstance(v, list) else type(v).__name__
        raise ReplayError(f"replay {key} must be a list of {size} integers, got {n}")
    if not all(type(x) is int and -MAX_VALUE <= x <= MAX_VALUE for x in v):
        raise ReplayError(f"replay {key} must hold integers within +-{MAX_VALUE}")
    return np.asarray(v, dtype=np.int64)


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
    """Read a replay file (.json or .json.gz); a file that is not a valid replay within the limits (see the
    module docstring) is a :class:`ReplayError` naming it."""
    p = Path(path)
    try:
        with p.open("rb") as fh:
            if p.name.endswith(".gz"):
                with gzip.GzipFile(fileobj=fh) as gz:
                    raw = gz.read(MAX_BYTES + 1)
            else:
                raw = fh.read(MAX_BYTES + 1)
        if len(raw) > MAX_BYTES:
            raise ReplayError(f"it holds more than {MAX_BYTES >> 20} MB of JSON")
        return Replay.from_dict(json.loads(raw))
    except ReplayError as exc:
        raise ReplayError(f"replay {str(p)!r}: {str(exc).removeprefix('replay ')}") from None
    except (OSError, EOFError, ValueError, RecursionError, zlib.error) as exc:  # gzip, JSON, Unicode errors
        why = str(exc).splitlines()[0][:200] if str(exc).strip() else type(exc).__name__
        raise ReplayError(f"replay {str(p)!r} cannot be read ({why}): give a confront replay .json or .json.gz file"
                          ) from None


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
    """Render the replay to an animated GIF (every ``every``-th frame, at most ``max_frames``; ``scale`` lowered
    so that no side exceeds ``MAX_GIF_SIDE`` pixels)."""
    if len(replay) == 0:
        raise ValueError("replay has no frames")
    scale = min(scale, MAX_GIF_SIDE / max(replay.width, replay.height))
    idx = _frame_indices(len(replay), max_frames, every)
    images = [
        Image.fromarray(draw_frame(replay.frame(i), replay.width, replay.height, scale)).quantize(64)
        for i in idx
    ]
    p = Path(path)
    buf = io.BytesIO()
    images[0].save(
        buf, format="GIF", save_all=True, append_images=images[1:], duration=max(20, int(1000 / fps)), loop=0,
        optimize=False
    )
    write_atomic(p, buf.getvalue())
    return p


def _template() -> str:
    return (resources.files("confront.arena") / "replay_assets" / "player.html").read_text()


def write_html(replay: Replay, path: str | Path, title: str | None = None) -> Path:
    """A single self-contained HTML page (inline JS + canvas) that plays the replay."""
    if len(replay) == 0:
        raise ValueError("replay has no frames")
    # <, > and & only occur inside JSON strings: as \u escapes no name can end the script or open a comment
    data = (json.dumps(replay.to_dict(), separators=(",", ":"))
            .replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026"))
    name = title or f"confront replay {replay.scenario}".strip()
    fill = {"__TITLE__": _escape(name), "__REPLAY_JSON__": data}  # one pass: a name holding a placeholder stays text
    html = re.sub("__TITLE__|__REPLAY_JSON__", lambda m: fill[m.group(0)], _template())
    p = Path(path)
    write_atomic(p, html.encode())
    return p


def _escape(s: str) -> str:
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


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
        raise ValueError(f"no *.replay.json[.gz] files under {str(source)!r}: a run records the last round of its "
                         "trained team in replays/ when train.replay = true (the default), and confront battle "
                         "--replay FILE records a battle")
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
