"""Experiment configs: one typed dataclass tree, packaged TOML files per experiment, ``--set`` overrides.

Every free choice the paper leaves open is a key here, with its default and the reason in ``doc``.
``confront config show NAME`` prints the resolved tree.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Literal

from confront.arena.scenarios import SAMPLE_TEAMS
from confront.config import ConfigError, field, from_dict, load_toml, merge, parse_override, to_dict
from confront.learning.ppo_config import PPOConfig

CONFIG_PACKAGE = "confront.train.configs"
# the sample robots of confront.arena.bots.BOT_NAMES that fight on their own, known without loading the simulator (a
# test keeps them equal); the sample teams (a leader and droids) are SAMPLE_TEAMS
SCRIPTED_BOTS = ("SittingDuck", "SpinBot", "Walls", "Tracker", "RamFire", "Fire", "Corners", "Crazy", "TrackFire")
# the technique robots of confront.arena.tech.TECH_ROBOTS (Java twins confront.tech.*), known without loading the
# simulator (a test keeps them equal)
TECH_BOTS = ("RamHeadOn", "StopGoCircular", "OrbitLinear", "OrbitCircular", "OrbitVG", "OrbitGF", "SurfCircular",
             "SurfGF", "SurfVG", "SurfAS", "RiskGF")
RUN_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")


def check_scenario(name: str) -> None:
    """``arena.scenario`` must be a built-in scenario or a scenario TOML file that loads (ValueError if not)."""
    from confront.arena.scenarios import load_scenario, scenario_names

    if not name.endswith(".toml"):
        if name not in scenario_names():
            raise ValueError(f"arena.scenario = {name!r} is not allowed: use one of {', '.join(scenario_names())} "
                             "or a scenario .toml file")
        return
    try:
        load_scenario(name)
    except (OSError, ValueError, TypeError, RecursionError) as exc:  # TOML and Unicode errors are ValueErrors
        raise ValueError(f"arena.scenario = {name!r} cannot be used: {str(exc).splitlines()[0][:200]}") from None


@dataclass
class ArenaSection:
    """The battle: scenario, how many battles run side by side, the SMDP step."""

    scenario: str = field("4v4", doc="named scenario (1v1, 4v4, 4v6, 4v10, melee) or a scenario TOML file")
    battles: int = field(8, ge=1, le=4096, doc="battles simulated side by side (rounds are shared out)")
    decision_turns: int = field(10, ge=1, le=500, doc="T: engine turns each macro action is held (SMDP step)")
    fire_power_actions: bool = field(False, doc="extended action set: 4 moves x 3 bullet powers")
    target: Literal["nearest", "weakest"] = "nearest"
    sensing: Literal["scanned", "true"] = field(
        "scanned", doc="what a tank knows of enemies: their last scan (a real robot's view) or the true state")

    def __post_init__(self) -> None:
        check_scenario(self.scenario)


@dataclass
class OpponentSection:
    """Who the learning team fights: the TD team (paper §6.3), scripted sample robots or technique robots."""

    kind: str = field("td", doc="'td' for a TD-trained team, a scripted sample robot (e.g. SpinBot), a sample team "
                      "(MyFirstTeam) or a technique robot (RamHeadOn ... SurfAS, RiskGF)")
    model: str = field("", doc="saved TD-team model (.npz); empty = train one first and cache it")
    pretrain_rounds: int = field(300, ge=0, doc="rounds the TD team trains before the experiment")
    pretrain_against: str = field("SpinBot", doc="scripted or technique robot the TD team trains against")
    learning: bool = field(False, doc="the TD team keeps learning during the experiment")
    alpha: float = field(0.2, gt=0.0, le=1.0, doc="TD team's fixed learning rate")
    gamma: float = field(0.9, ge=0.0, le=1.0)
    exploit: float = field(0.9, ge=0.0, le=1.0, doc="TD team's epsilon-greedy exploitation threshold (paper's eps)")

    def __post_init__(self) -> None:
        for key, value in (("kind", self.kind), ("pretrain_against", self.pretrain_against)):
            if value in SCRIPTED_BOTS or value in TECH_BOTS or (key == "kind" and value in ("td", *SAMPLE_TEAMS)):
                continue
            from confront.arena.bots import BOT_NAMES

            if value not in BOT_NAMES:
                robots = (*BOT_NAMES, *TECH_BOTS)
                allowed = ("td", *robots, *SAMPLE_TEAMS) if key == "kind" else robots
                raise ValueError(f"opponent.{key} = {value!r} is not allowed: use one of {', '.join(allowed)}")


@dataclass
class LearnerSection:
    """The learning team's method (paper §3-4; Table 2)."""

    kind: Literal["dmnn", "ssaq", "random", "ppo"] = field(
        "dmnn", doc="dmnn (§4), ssaq (tabular, §3), random: uniform moves, a reference that never learns, or ppo: "
        "the recommended shared-policy actor-critic on the tank view (sections tank, ppo, league)")
    learning_rate: Literal["fuzzy", "fixed"] = field("fuzzy", doc="RL learning rate: fuzzy (Eq. 11-17) or fixed alpha")
    alpha: float = field(0.1, gt=0.0, le=1.0, doc="fixed RL learning rate (Table 2: 0.1)")
    gamma: float = field(0.9, ge=0.0, le=1.0, doc="discount (Table 2: 0.9)")
    t_max: float = field(0.1, gt=0.0, doc="Boltzmann temperature at the start (Table 2: 0.1)")
    t_min: float = field(0.01, gt=0.0, doc="temperature floor (Table 2: 0.01)")
    eta: float = field(0.9, ge=0.0, le=1.0, doc="annealing factor (Eq. 7; Table 2: 0.9)")
    backup: Literal["paper", "smdp"] = field("paper", doc="Eq. 8-10 as corrected in paper-notes §3, or textbook SMDP")
    hidden: tuple[int, ...] = field((16,), ge=1, le=4096, doc="DMNN hidden layer sizes")
    awm: bool = field(True, doc="adaptive momentum (Eq. 23-24) on; off = plain back-propagation")
    nn_rate: float = field(0.9, gt=0.0, le=1.0, doc="NN learning rate without AWM (Table 2: 0.9)")
    momentum: float = field(0.95, ge=0.0, lt=1.0, doc="momentum constant beta (Table 2: 0.95)")
    output: Literal["linear", "bipolar"] = field("linear", doc="DMNN output layer: linear, or Eq. 20's bipolar")
    q_scale: float = field(10.0, gt=0.0, doc="DMNN network units: Q = q_scale * output (not in the paper)")
    td_clip: float = field(1.0, ge=0.0, doc="clip of the TD error in network units, 0 = off (not in the paper; "
                           "measured: at 5 the fuzzy AWM network diverged on Eq. 35's heavy-tailed rewards)")


@dataclass
class TransferSection:
    """Curriculum transfer (paper §5, Eq. 34): act from a source model with a cooling probability."""

    source: str = field("", doc="run folder of the source task; empty = learn from scratch")
    epsilon0: float = field(0.9, ge=0.0, le=1.0, doc="eps(t0): initial probability of acting from the source")
    decay: float = field(0.002, ge=0.0, doc="p in eps(t) = eps(t0) exp(-p (t - t0)), t in SMDP steps (learn calls)")
    floor: float = field(0.05, ge=0.0, le=1.0, doc="stable value eps(t) decays to")
    init_from_source: bool = field(True, doc="start the learner from the source model's weights (Eq. 33)")


@dataclass
class TankSection:
    """What a PPO tank sees and chooses (confront.arena.tank): finer moves, fire power or hold, target slot."""

    decision_turns: int = field(5, ge=1, le=100, doc="T: turns each tank action is held")
    distances: tuple[float, ...] = field((-150.0, -50.0, 0.0, 50.0, 150.0), ge=-1000, le=1000,
                                         doc="move distances, px (+ ahead)")
    turns_deg: tuple[float, ...] = field((-90.0, -45.0, 0.0, 45.0, 90.0), ge=-360, le=360,
                                         doc="body angles, degrees (+ clockwise), see turn_mode")
    turn_mode: Literal["target", "body"] = field(
        "target", doc="target: the body ends at that angle to the target's bearing (0 faces it, +-90 circles it); "
        "body: turn by that angle")
    fire_powers: tuple[float, ...] = field((0.0, 1.0, 2.0, 3.0), ge=0.0, le=3.0, doc="bullet powers, 0 = hold fire")
    enemy_slots: int = field(4, ge=1, le=16, doc="K nearest scanned enemies in the view (and target choices)")
    mate_slots: int = field(3, ge=0, le=16, doc="M nearest team-mates in the view")
    leads: tuple[str, ...] = field(("none", "circular"),
                                   doc="the gun's lead, chosen per step among: none, linear, circular (turn rate "
                                   "between scans), gf (the technique brain's GuessFactor aim; a skill)")
    surf: bool = field(False, doc="a skill: one more move choice, the body follows the technique brain's wave "
                       "surfing (minimum risk in melee) for the step")
    knowledge: bool = field(False, doc="a skill: the view ends with 8 features of what the technique brain knows "
                            "about this battle (virtual-gun hit rates, enemy waves, how peaked its statistics are)")
    brain: Literal["SurfGF", "SurfAS"] = field(
        "SurfGF", doc="the technique robot the skills follow: SurfGF (wave surfing, GuessFactor gun) or SurfAS (the "
        "same with an anti-surfer GuessFactor gun beside it: fading visit counts, aiming while they hit more)")
    skill_prior: float = field(0.0, ge=0.0, le=10.0, doc="the untrained policy's logit bonus for the skills' "
                               "choices (surf, the gf lead): at 3 it surfs and aims by GuessFactor 80% of the time "
                               "and learns when not to; 0: every choice alike")
    reward: Literal["score", "eq35"] = field("score", doc="team's Robocode score margin per turn, or Eq. 35")

    def __post_init__(self) -> None:
        for key in ("distances", "turns_deg", "fire_powers", "leads"):
            if not getattr(self, key):
                raise ValueError(f"tank.{key} must not be empty")
        if any(p != 0 and not 0.1 <= p <= 3.0 for p in self.fire_powers):
            raise ValueError(f"tank.fire_powers = {list(self.fire_powers)} is not allowed: use 0 (hold) or 0.1..3")
        bad = [v for v in self.leads if v not in ("none", "linear", "circular", "gf")]
        if bad:
            raise ValueError(f"tank.leads entry {bad[0]!r} is not allowed: use none, linear, circular or gf")


@dataclass
class LeagueSection:
    """The PPO opponents: battles of each kind side by side, every rollout."""

    opponents: tuple[str, ...] = field(
        ("1v1:SittingDuck", "1v1:SpinBot", "1v1:Walls", "1v1:Tracker", "1v1:RamFire", "1v1:Fire", "1v1:Corners",
         "1v1:Crazy", "1v1:dodge", "1v1:self", "4v4:SpinBot", "4v4:Walls", "4v4:Tracker", "4v4:RamFire",
         "4v4:Crazy", "4v4:td", "4v4:dodge", "4v4:self"),
        doc="SCENARIO:OPPONENT entries: a scripted sample robot or a technique robot (RamHeadOn ... SurfAS, RiskGF; "
        "a team of it), a sample team (MyFirstTeam: a leader and droids, in scenarios whose other teams have 2 or "
        "more robots), td, random, dodge, strafe, or self (snapshots)")
    battles: int = field(8, ge=1, le=4096, doc="battles per entry")
    focus: tuple[str, ...] = field((), doc="entries of opponents that get focus_weight times the battles; one "
                                   "written ENTRY*W gets W times")
    focus_weight: int = field(3, ge=1, le=64, doc="battle multiplier of the focus entries")
    snapshot_every: int = field(20, ge=1, doc="updates between self-play snapshots")
    snapshots: int = field(5, ge=1, le=100, doc="snapshots kept; self-play battles sample one per update")
    prioritise: bool = field(False, doc="prioritised sampling: each rollout only some entries play, each with "
                             "probability growing as (1 - its recent share)^pfsp_power (AlphaStar's PFSP), so the "
                             "battles go to what the policy still loses to")
    play_fraction: float = field(0.5, gt=0.0, le=1.0, doc="with prioritise: entries playing a rollout, on average")
    play_floor: float = field(0.1, gt=0.0, le=1.0, doc="with prioritise: every entry's least chance to play a "
                              "rollout (nothing is forgotten)")
    pfsp_power: float = field(2.0, ge=0.0, le=10.0, doc="with prioritise: the weight's exponent (0 = uniform)")
    share_window: int = field(100, ge=1, le=100000, doc="with prioritise: an entry's recent share is over its "
                              "last share_window rounds (0.5 before any)")

    def __post_init__(self) -> None:
        from confront.arena.scenarios import get_scenario, opponent_members, scenario_names

        kinds = (*SCRIPTED_BOTS, *TECH_BOTS, *SAMPLE_TEAMS, "td", "random", "dodge", "strafe", "self")
        for e in self.opponents:
            scen, _, opp = e.partition(":")
            if scen not in scenario_names() or opp not in kinds:
                raise ValueError(f"league.opponents entry {e!r} is not allowed: use SCENARIO:OPPONENT with a "
                                 f"scenario of {', '.join(scenario_names())} and an opponent of {', '.join(kinds)}")
            try:
                opponent_members(get_scenario(scen), opp)
            except ValueError as err:
                raise ValueError(f"league.opponents entry {e!r} is not allowed: {err}") from None
        if not self.opponents:
            raise ValueError("league.opponents must not be empty")
        for e in self.focus:
            name, star, w = e.partition("*")
            if name not in self.opponents:
                raise ValueError(f"league.focus entry {name!r} is not one of league.opponents")
            if star and not (w.isdigit() and 1 <= int(w) <= 64):
                raise ValueError(f"league.focus entry {e!r}: the weight after '*' must be an integer in 1..64")

    def focus_weights(self) -> dict[str, int]:
        """Battle multiplier of each focus entry: its own W (ENTRY*W) or ``focus_weight``."""
        parts = [e.partition("*") for e in self.focus]
        return {name: int(w) if star else self.focus_weight for name, star, w in parts}

    def battles_of(self, entry: str) -> int:
        """Battles of one entry: ``battles``, times ``focus_weight`` for a focus entry (times W for ENTRY*W)."""
        return self.battles * self.focus_weights().get(entry, 1)


@dataclass
class TrainSection:
    """Length, sessions, seeds, checkpoints."""

    rounds: int = field(500, ge=1, doc="rounds in total (paper: 500)")
    session_rounds: int = field(10, ge=1, doc="rounds per session (paper: 10)")
    seed: int = field(0, ge=0, le=2**32 - 1)
    checkpoint_every: int = field(50, ge=1, doc="rounds between checkpoints")
    init: str = field("", doc="PPO: a run folder whose model (model/ppo.npz) the learner starts from (e.g. a "
                      "simulator run fine-tuned in the engine); empty = from scratch")
    replay: bool = field(True, doc="record the last round of battle 0 as a replay")


@dataclass
class ExperimentConfig:
    """One training arm."""

    name: str = "demo"
    description: str = ""
    arena: ArenaSection = field(default_factory=ArenaSection)
    opponent: OpponentSection = field(default_factory=OpponentSection)
    learner: LearnerSection = field(default_factory=LearnerSection)
    transfer: TransferSection = field(default_factory=TransferSection)
    train: TrainSection = field(default_factory=TrainSection)
    tank: TankSection = field(default_factory=TankSection)
    ppo: PPOConfig = field(default_factory=PPOConfig)
    league: LeagueSection = field(default_factory=LeagueSection)

    def __post_init__(self) -> None:
        if not RUN_NAME.fullmatch(self.name):
            raise ValueError(f"name = {self.name[:60]!r} is not allowed: it names run folders, so use 1-64 letters, "
                             "digits, '.', '_' or '-', starting with a letter or digit")
        if self.learner.t_min > self.learner.t_max:
            raise ValueError(
                f"learner.t_min = {self.learner.t_min} must not exceed learner.t_max = {self.learner.t_max}"
            )
        if self.train.session_rounds > self.train.rounds:
            raise ValueError(
                f"train.session_rounds = {self.train.session_rounds} exceeds train.rounds = {self.train.rounds}"
            )
        if self.opponent.kind in SAMPLE_TEAMS:
            from confront.arena.scenarios import get_scenario, load_scenario, opponent_members

            scen = self.arena.scenario
            try:
                opponent_members(load_scenario(scen) if scen.endswith(".toml") else get_scenario(scen),
                                 self.opponent.kind)
            except ValueError as err:
                raise ValueError(f"opponent.kind = {self.opponent.kind!r} with arena.scenario = {scen!r}: {err}") \
                    from None


def list_experiments() -> list[str]:
    """Names of the packaged experiment configs."""
    root = resources.files(CONFIG_PACKAGE)
    return sorted(p.name.removesuffix(".toml") for p in root.iterdir() if p.name.endswith(".toml"))


def experiment_data(name_or_path: str) -> dict:
    """The raw TOML table of a packaged experiment name or a file path."""
    if name_or_path.endswith(".toml") or Path(name_or_path).exists():
        return load_toml(name_or_path)
    names = list_experiments()
    if name_or_path not in names:
        raise ConfigError(f"unknown experiment {name_or_path!r}: use one of {', '.join(names)} or a .toml file")
    with resources.as_file(resources.files(CONFIG_PACKAGE) / f"{name_or_path}.toml") as p:
        return load_toml(p)


def load_experiment(name_or_path: str, overrides: tuple[str, ...] | list[str] = ()) -> ExperimentConfig:
    """Resolve an experiment: defaults <- TOML file <- ``key=value`` overrides, validated."""
    data = to_dict(ExperimentConfig())
    data = merge(data, experiment_data(name_or_path))
    for text in overrides:
        data = merge(data, parse_override(text))
    return from_dict(ExperimentConfig, data)


def config_from_dict(data: dict) -> ExperimentConfig:
    """Validate a resolved config table (e.g. a run folder's config.toml)."""
    return from_dict(ExperimentConfig, merge(to_dict(ExperimentConfig()), data))
