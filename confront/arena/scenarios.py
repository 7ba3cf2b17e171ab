"""Named battle scenarios (like SMAC's map names) and user scenarios from TOML.

A scenario fixes the teams (sizes), the field, Robocode's battle settings and the round limits.
Team 0 is the learning side by convention; ``opponents`` is the default opponent for the other
teams (``"td"`` for a TD-trained team or a scripted bot name from :mod:`confront.arena.bots`),
which experiment configs may override.

TOML format (all keys but ``name`` and ``teams`` optional)::

    name = "2v3"
    teams = [2, 3]
    width = 800
    height = 600
    gun_cooling_rate = 0.1
    inactivity_time = 450
    max_turns = 4000
    turns_after_end = 0
    opponents = "SpinBot"
    advanced = true                 # learning/team robots are AdvancedRobots (wall damage)
    team_leaders = true             # first member of a team of 2+ is its leader (200 energy, -30 on death)
    initial_positions = [[100, 100, 90], [700, 500, 270]]   # (x, y, heading deg) per robot
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, fields
from importlib import resources
from numbers import Integral
from pathlib import Path
from typing import Any

__all__ = ["Scenario", "get_scenario", "load_scenario", "scenario_names", "scenario_from_dict", "SAMPLE_TEAMS",
           "team_members", "opponent_members"]

MAX_ROBOTS = 256  # robots of a battle (the replay format's limit; the simulator's arrays grow with its square)
# Robocode's sample team (sampleteam.MyFirstTeam): its leader first, then droids to fill the team
SAMPLE_TEAMS = {"MyFirstTeam": ("MyFirstLeader", "MyFirstDroid")}


def team_members(name: str, size: int) -> list[str]:
    """The robots of a team of ``size`` named ``name``: a sample team's leader and droids, or ``size`` copies of a
    robot (a team of 1 cannot be a sample team: its leader alone has no droid to command)."""
    if name not in SAMPLE_TEAMS:
        return [name] * size
    if size < 2:
        raise ValueError(f"{name} needs teams of 2 or more robots (a leader and droids), got a team of {size}")
    leader, droid = SAMPLE_TEAMS[name]
    return [leader] + [droid] * (size - 1)


@dataclass(frozen=True)
class Scenario:
    """One battle set-up: teams, field, Robocode battle settings, round limits."""

    name: str
    teams: tuple[int, ...]
    width: float = 800.0
    height: float = 600.0
    gun_cooling_rate: float = 0.1
    inactivity_time: int = 450
    max_turns: int = 4000
    turns_after_end: int = 0
    opponents: str = "td"
    advanced: bool = True
    team_leaders: bool = True
    initial_positions: tuple[tuple[float, float, float], ...] | None = None
    description: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if not self.teams or any(isinstance(t, bool) or not isinstance(t, Integral) or t < 1 for t in self.teams):
            raise ValueError(f"teams must be a non-empty list of positive whole sizes, got {_show(self.teams)}")
        object.__setattr__(self, "teams", tuple(int(t) for t in self.teams))
        if sum(self.teams) > MAX_ROBOTS:
            raise ValueError(f"teams={_show(self.teams)} make {sum(self.teams)} robots: a battle holds at most "
                             f"{MAX_ROBOTS}")
        if len(self.teams) < 2 and self.teams[0] < 2:
            raise ValueError(f"teams={self.teams!r}: a battle needs at least two robots")
        if not (400 <= self.width <= 5000 and 400 <= self.height <= 5000):  # [BattlefieldSpecification]
            raise ValueError(f"width/height must be in Robocode's 400-5000, got {self.width}x{self.height}")
        if not 0.1 <= self.gun_cooling_rate <= 0.7:
            raise ValueError(f"gun_cooling_rate must be in [0.1, 0.7], got {self.gun_cooling_rate}")
        if self.inactivity_time < 0:
            raise ValueError(f"inactivity_time must be >= 0, got {self.inactivity_time}")
        if self.max_turns < 1:
            raise ValueError(f"max_turns must be >= 1, got {self.max_turns}")
        if self.turns_after_end < 0:
            raise ValueError(f"turns_after_end must be >= 0, got {self.turns_after_end}")
        if self.initial_positions is not None:
            if len(self.initial_positions) != self.n_robots:
                raise ValueError(
                    f"initial_positions has {len(self.initial_positions)} entries, expected {self.n_robots}"
                )
            for p in self.initial_positions:
                if len(p) != 3 or not all(math.isfinite(float(v)) for v in p):
                    raise ValueError(f"initial_positions entry {p!r} must be (x, y, heading_deg)")
                if not (18 <= p[0] <= self.width - 18 and 18 <= p[1] <= self.height - 18):
                    raise ValueError(f"initial_positions entry {p!r} lies outside the field")

    @property
    def n_robots(self) -> int:
        """Total number of robots."""
        return int(sum(self.teams))

    @property
    def n_teams(self) -> int:
        """Number of contestants (teams; a melee has teams of 1)."""
        return len(self.teams)

    def team_ids(self) -> list[int]:
        """Team id of each robot, in robot order."""
        return [t for t, n in enumerate(self.teams) for _ in range(n)]

    def replace(self, **changes: Any) -> Scenario:
        """A copy with some fields changed (validated)."""
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d.update(changes)
        return scenario_from_dict(d)


def opponent_members(scenario: Scenario, name: str) -> list[str]:
    """One robot name per robot of the scenario's other teams when ``name`` plays them all (copies of a robot, or each
    team a sample team's leader and droids); ValueError if a sample team meets a team of 1."""
    return [n for size in scenario.teams[1:] for n in team_members(name, size)]


_FIELDS = {f.name for f in fields(Scenario)}


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def scenario_from_dict(d: dict[str, Any]) -> Scenario:
    """Build a validated Scenario from a plain dict (TOML table)."""
    for k in d:
        if k not in _FIELDS:
            raise ValueError(f"unknown scenario key {k!r}")
    if "name" not in d or "teams" not in d:
        raise ValueError("a scenario needs 'name' and 'teams'")
    d = dict(d)
    if isinstance(d["teams"], str) or not isinstance(d["teams"], list | tuple):
        raise ValueError(f"teams must be a list of team sizes, got {_show(d['teams'])}")
    d["teams"] = tuple(d["teams"])  # whole numbers only: 1.7 is refused, not read as 1
    for k in ("width", "height", "gun_cooling_rate"):
        if k in d:
            d[k] = float(d[k])
    for k in ("inactivity_time", "max_turns", "turns_after_end"):
        if k in d:
            if not isinstance(d[k], int) or isinstance(d[k], bool):
                raise ValueError(f"scenario key {k!r} must be an integer, got {d[k]!r}")
    if d.get("initial_positions") is not None:
        d["initial_positions"] = tuple(tuple(float(v) for v in p) for p in d["initial_positions"])
    return Scenario(**d)


def load_scenario(path: str | Path) -> Scenario:
    """Read a user scenario from a TOML file (at most ``confront.config.MAX_FILE`` bytes)."""
    from confront.config import load_toml

    return scenario_from_dict(load_toml(path))


def _builtin_dir() -> Any:
    return resources.files("confront.arena") / "scenarios"


def scenario_names() -> list[str]:
    """Names of the built-in scenarios."""
    return sorted(p.name[:-5] for p in _builtin_dir().iterdir() if p.name.endswith(".toml"))


def get_scenario(name: str) -> Scenario:
    """A built-in scenario by name (``1v1``, ``4v4``, ``4v6``, ``4v10``, ``melee``, ...)."""
    p = _builtin_dir() / f"{name}.toml"
    if not p.is_file():
        raise ValueError(f"unknown scenario {name!r}; known: {', '.join(scenario_names())}")
    d = tomllib.loads(p.read_text())
    return scenario_from_dict(d)
