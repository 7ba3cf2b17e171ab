"""Battle descriptions and Robocode battle files (scenario names, teams of sample robots, start positions)."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

from confront.arena.scenarios import SAMPLE_TEAMS, team_members

SAMPLE_ROBOTS: tuple[str, ...] = (
    "SittingDuck", "SpinBot", "Walls", "Tracker", "RamFire", "Fire", "Corners", "Crazy", "TrackFire",
    "Target", "VelociRobot", "MyFirstRobot",
)
TEAM_PACKAGE = "confrontteams"
# the robots of Robocode's sample teams (package sampleteam)
SAMPLE_TEAM_ROBOTS: tuple[str, ...] = tuple(r for team in SAMPLE_TEAMS.values() for r in team)


@dataclass(frozen=True)
class Team:
    """A team written as ``<robots>/confrontteams/<name>.team``; the first member is the leader."""

    name: str
    members: tuple[str, ...]

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ValueError(f"team name must be a Java identifier, got {self.name!r}")
        if not self.members:
            raise ValueError(f"team {self.name!r} has no members")
        object.__setattr__(self, "members", tuple(robot_class(m) for m in self.members))

    @property
    def qualified(self) -> str:
        """The name the engine knows the team by."""
        return f"{TEAM_PACKAGE}.{self.name}*"

    def team_file(self) -> str:
        """Contents of the .team file."""
        return f"team.members={','.join(self.members)}\nrobocode.version=1.9.3.9\n"


Contestant = str | Team
Position = tuple[float | None, float | None, float | None]


_ROBOT_NAME = re.compile(r"^[A-Za-z_$][\w$.]*\*?( [\w.\-]+)?$")


def robot_class(name: str) -> str:
    """Full class name: 'SpinBot' -> 'sample.SpinBot'; names with a package (and an optional version,
    as jar robots have: 'pkg.Bot 1.0') are kept."""
    if not _ROBOT_NAME.match(name or ""):
        raise ValueError(f"bad robot name {name!r}")
    if "." in name:
        return name
    if name in SAMPLE_TEAM_ROBOTS:
        return f"sampleteam.{name}"
    from confront.engine.tech_robots import TECH_ROBOTS, engine_name

    if name in TECH_ROBOTS:
        return engine_name(name)
    if name not in SAMPLE_ROBOTS:
        raise ValueError(f"unknown robot {name!r}: give a package-qualified class or one of "
                         f"{SAMPLE_ROBOTS + SAMPLE_TEAM_ROBOTS + tuple(TECH_ROBOTS)}")
    return f"sample.{name}"


@dataclass(frozen=True)
class BattleSpec:
    """One battle: contestants (robots or teams), field, rounds and rules, optional start positions."""

    contestants: tuple[Contestant, ...]
    rounds: int = 10
    width: int = 800
    height: int = 600
    gun_cooling_rate: float = 0.1
    inactivity_time: int = 450
    initial_positions: tuple[Position, ...] = ()
    name: str = "custom"
    max_turns: int = 0  # stop the battle at this turn of its first round (0 = play it out); for traces
    teams: tuple[Team, ...] = field(init=False, default=())

    def __post_init__(self) -> None:
        if len(self.contestants) < 1:
            raise ValueError("contestants must name at least one robot or team")
        conts = tuple(c if isinstance(c, Team) else robot_class(c) for c in self.contestants)
        object.__setattr__(self, "contestants", conts)
        object.__setattr__(self, "teams", tuple(c for c in conts if isinstance(c, Team)))
        if self.rounds < 1:
            raise ValueError(f"rounds must be >= 1, got {self.rounds}")
        if self.width < 400 or self.height < 400 or self.width > 5000 or self.height > 5000:
            raise ValueError(f"field must be 400..5000 on each side, got {self.width}x{self.height}")
        if not 0.1 <= self.gun_cooling_rate <= 0.7:
            raise ValueError(f"gun_cooling_rate must be in [0.1, 0.7], got {self.gun_cooling_rate}")
        if self.max_turns < 0:
            raise ValueError(f"max_turns must be >= 0, got {self.max_turns}")
        if self.inactivity_time < 0:
            raise ValueError(f"inactivity_time must be >= 0, got {self.inactivity_time}")
        if len(self.initial_positions) > self.robot_count:
            raise ValueError(f"initial_positions has {len(self.initial_positions)} entries for "
                             f"{self.robot_count} robots")
        for pos in self.initial_positions:
            for v in pos:
                # the engine's parser drops '-' and exponents, so only plain non-negative numbers survive
                if v is not None and (not math.isfinite(v) or v < 0):
                    raise ValueError(f"initial position values must be >= 0 or None, got {pos}")

    @property
    def robot_count(self) -> int:
        """Number of robots once teams are expanded."""
        return sum(len(c.members) if isinstance(c, Team) else 1 for c in self.contestants)

    def selected_robots(self) -> str:
        """The engine's selection string."""
        return ",".join(c.qualified if isinstance(c, Team) else c for c in self.contestants)

    def battle_file(self) -> str:
        """Text of a Robocode .battle file (plus the runner's robot-count check)."""
        lines = [
            f"robocode.battleField.width={self.width}",
            f"robocode.battleField.height={self.height}",
            f"robocode.battle.numRounds={self.rounds}",
            f"robocode.battle.gunCoolingRate={self.gun_cooling_rate!r}",
            f"robocode.battle.rules.inactivityTime={self.inactivity_time}",
            "robocode.battle.hideEnemyNames=false",
            f"robocode.battle.selectedRobots={self.selected_robots()}",
            f"confront.expectedRobots={self.robot_count}",
        ]
        if self.max_turns:
            lines.append(f"confront.maxTurns={self.max_turns}")
        if self.initial_positions:
            lines.append(f"robocode.battle.initialPositions={format_positions(self.initial_positions)}")
        return "\n".join(lines) + "\n"


def format_positions(positions: Sequence[Position]) -> str:
    """Robocode's initialPositions string '(x,y,heading_deg),(?,?,?)'."""
    def cell(v: float | None) -> str:
        return "?" if v is None else repr(float(v))

    return ",".join("(" + ",".join(cell(v) for v in p) + ")" for p in positions)


# Team sizes of the paper's scenarios (ours, theirs); melee is four single robots.
SCENARIO_SIZES: dict[str, tuple[int, ...]] = {
    "1v1": (1, 1), "4v4": (4, 4), "4v6": (4, 6), "4v10": (4, 10), "melee": (1, 1, 1, 1),
}


def _side(label: str, size: int, robots: Sequence[str]) -> Contestant:
    if len(robots) == 1 and robots[0] in SAMPLE_TEAMS:  # a sample team: its leader, then droids
        return Team(f"{robots[0]}{size}", tuple(team_members(robots[0], size)))
    members = tuple(robots[i % len(robots)] for i in range(size))
    if size == 1:
        return members[0]
    return Team(f"{label}{size}", members)


def scenario_battle(
    scenario: str,
    ours: str | Sequence[str],
    opponents: str | Sequence[str],
    rounds: int = 10,
    width: int = 800,
    height: int = 600,
) -> BattleSpec:
    """Battle for a named scenario: our side vs opponents, teams filled by cycling the given robots (a sample team's
    name, ``"MyFirstTeam"``, fills a side with its leader and droids).

    For ``melee`` the four robots are ``ours`` followed by ``opponents`` cycled.
    """
    if scenario not in SCENARIO_SIZES:
        raise ValueError(f"unknown scenario {scenario!r}; known: {sorted(SCENARIO_SIZES)}")
    ours_l = [ours] if isinstance(ours, str) else list(ours)
    opp_l = [opponents] if isinstance(opponents, str) else list(opponents)
    if not ours_l or not opp_l:
        raise ValueError("ours and opponents must each name at least one robot")
    sizes = SCENARIO_SIZES[scenario]
    if scenario == "melee":
        for o in opp_l:
            team_members(o, 1)  # a sample team cannot fight alone
        pool = ours_l[:1] + [opp_l[i % len(opp_l)] for i in range(3)]
        conts: tuple[Contestant, ...] = tuple(pool)
    else:
        conts = (_side("Ours", sizes[0], ours_l), _side("Them", sizes[1], opp_l))
    return BattleSpec(conts, rounds=rounds, width=width, height=height, name=scenario)


def single_star(spec: BattleSpec, starred: str) -> BattleSpec:
    """Robots given as loose classes (``confront.PolicyBot*``): a contestant on its own is selected by the starred
    name, while team files list the plain one. ``spec`` names the robot plainly; this stars it where it stands
    alone (the rest of ``spec`` is kept)."""
    plain = starred.rstrip("*")
    return replace(spec, contestants=tuple(starred if c == plain else c for c in spec.contestants))
