"""Exporting a tank policy (an actor over the tank view and tank actions, :mod:`confront.arena.tank`) as the
standalone Robocode robot ``confront.TankBot``, with its Java inference (``TankModel.java``).
:class:`TankPolicy` is the Python twin: the same view (the simulator's ``tank_view_row``, fed what the robot
knows), the same action (greedy, or sampled from uniform draws: ``play``) and the same gun/radar controller
(``smdp.controller_turn`` with ``tank.lead_point``: no lead, linear, or circular with the turn rate of
``observe.remember_scans``; gf with the technique brain's angle, ``robot_control``'s ``gun_aim``). The twin has no
technique brain: with skills, the exported robot is checked against the simulator's battles
(tests/engine/test_tank_skills.py).

Policy file (text, data only): ``confront-tank 1``, ``key value`` lines (lists as space-separated values;
``play sampled`` for a robot that samples its actions, greedy without it; the skills ``surf 1``, ``knowledge 1``
and the lead ``gf``, absent when off, so older files read as before) and ``matrix NAME ROWS COLS``
blocks: ``w0 b0 w1 b1 ...``, weights as (out, in), tanh between layers, the last layer's outputs the logits
of the five heads (distance, body turn, fire power, enemy slot, gun lead) in order.

A run trained on the tank view is exported when its ``model/model.json`` has ``"kind": "ppo"``: the actor
is ``model/actor.npz`` (``w0, b0, w1, b1, ...`` as (out, in), or a torch state dict's
``actor.<i>.weight`` / ``actor.<i>.bias``) and ``model/tank.json`` holds the TankSpace fields (top level or
under ``"tank"``), ``step_turns`` (or ``turns_per_step``) and the ControlConfig values (top level or under
``"control"``).
"""

from __future__ import annotations

import json
import math
import re
import tempfile
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from confront.arena.control import ControlConfig
from confront.arena.observe import float_mod
from confront.arena.rules import java_atan2, java_hypot
from confront.arena.tank import KNOWLEDGE_FEATURES, MEMORY_ROWS, TankSpace, action_table, lead_point, tank_view_row
from confront.engine.export import ROBOTS_FOLDER_HINT, ExportedPolicy, export_robot, write_robot
from confront.engine.install import EngineInstall
from confront.engine.java_build import MODEL_CLASSES, ROBOT_HELPERS
from confront.results import BattleResults

Play = Literal["greedy", "sampled"]  # the most likely action, or one drawn from the policy

__all__ = ["TankPolicy", "PLAYS", "sample_heads", "robot_view", "robot_target", "robot_control", "body_turn",
           "turn_rate", "export_tank_robot", "evaluate_tank_policy", "is_tank_run", "load_tank_policy", "TANK_CLASSES",
           "TANK_ROBOT"]

TANK_CLASSES = ("TankBot", "TankModel", "tech/TechBrain", *MODEL_CLASSES, *ROBOT_HELPERS)
TANK_ROBOT = "confront.TankBot 1.0"  # the exported jar's robot name
EnemyRow = Sequence[float]  # x, y, energy, heading, velocity, energy drop, scan time, turn rate
MAX_RATE = math.pi / 18.0  # Rules.MAX_TURN_RATE, 10 deg/turn
MateRow = Sequence[float]  # x, y, energy
MAX_STEP_TURNS = 500  # turns a decision is held (the configs' tank.decision_turns bound)
PLAYS = ("greedy", "sampled")  # TankPolicy.play: the first maximum of each head, or a draw from its softmax


TANK_CPU_CONSTANT_MS = 10.0  # the robots' time per turn in tank battles (evaluation and engine training)


def sample_heads(logits: np.ndarray, dims: Sequence[int], u: Sequence[float]) -> int:
    """Joint action with each head drawn from the softmax of its logits by one uniform draw in [0, 1): the
    first choice whose running sum of probabilities (exp(z - max z), divided by their sum, in float64) exceeds
    the draw, else the last (TankModel.sample does the same)."""
    if len(u) != len(dims):
        raise ValueError(f"sampling needs one draw per head ({len(dims)}), got {len(u)}")
    joint, off = 0, 0
    for n, draw in zip(dims, u, strict=True):
        z = logits[off:off + n]
        top = max(float(v) for v in z)
        w = [math.exp(float(v) - top) for v in z]
        total = sum(w)
        pick, acc = n - 1, 0.0
        for i in range(n):
            acc += w[i] / total
            if draw < acc:
                pick = i
                break
        joint = joint * n + pick
        off += n
    return joint


def robot_view(own: Sequence[float], counts: Sequence[int], enemies: Sequence[EnemyRow], mates: Sequence[MateRow],
               time: float, width: float, height: float, space: TankSpace,
               knowledge: Sequence[float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The tank view (float64, (F,)) and enemy slots ((K,), rows of ``enemies``, -1 empty) of one robot, from
    what TankBot knows: ``own`` = (x, y, heading, velocity, energy, gun heat), ``counts`` = (enemies alive,
    enemies at the start, mates alive, mates at the start), the known enemies' rows and the mates' rows, and
    with ``space.knowledge`` its brain's knowledge block (``knowledge``, 8 values).
    Computed by the simulator's ``tank_view_row`` (self = robot 0, then the enemies, then the mates)."""
    ne, nm = len(enemies), len(mates)
    n = 1 + ne + nm
    x, y, h, v, e, heat = (np.zeros(n) for _ in range(6))
    x[0], y[0], h[0], v[0], e[0], heat[0] = own
    team = np.array([0] + [1] * ne + [0] * nm, dtype=np.int64)
    memory = np.zeros((MEMORY_ROWS, n, n))
    seen = np.full((n, n), -1, dtype=np.int64)
    for j, row in enumerate(enemies, start=1):
        x[j], y[j], e[j] = row[0], row[1], row[2]
        for r in range(6):
            memory[r, 0, j] = row[r]
        memory[6, 0, j] = 1.0
        memory[7, 0, j] = row[7]
        memory[8, 0, j] = row[6]
        seen[0, j] = int(row[6])
    for j, row in enumerate(mates, start=1 + ne):
        x[j], y[j], e[j] = row
    out = np.zeros(space.n_features)
    slots = np.full(space.enemy_slots, -1, dtype=np.int64)
    tank_view_row(x, y, h, v, e, heat, np.ones(n, dtype=np.bool_), team, 0, memory, seen, float(time),
                  float(width), float(height), space.enemy_slots, space.mate_slots, np.stack([x, y, e]), True, out,
                  slots, np.empty(n))
    ea, es, ma, ms = counts  # the counts TankBot has (its mates' messages may be missing at turn 0)
    out[9] = ea / es if es > 0 else 0.0
    out[10] = ma / ms if ms > 0 else 0.0
    if space.knowledge and knowledge is not None:
        out[-KNOWLEDGE_FEATURES:] = knowledge
    return out, np.where(slots >= 0, slots - 1, -1)


def robot_target(x: float, y: float, enemies: Sequence[EnemyRow], chosen: int) -> int:
    """Row to aim at: ``chosen`` when it is a known enemy, else the nearest (squared distance, first of
    equals; observe.target_of), -1 without enemies."""
    if 0 <= chosen < len(enemies):
        return chosen
    best, best_d = -1, math.inf
    for j, row in enumerate(enemies):
        d = (row[0] - x) * (row[0] - x) + (row[1] - y) * (row[1] - y)
        if d < best_d:
            best, best_d = j, d
    return best


def _relative(a: float) -> float:
    """Angle wrapped to [-pi, pi) (smdp_kernel.relative_angle)."""
    return float(float_mod(a + math.pi, 2 * math.pi)) - math.pi


def turn_rate(previous: EnemyRow | None, heading: float, time: float) -> float:
    """An enemy's turn rate at a new scan (``observe.remember_scans``): its heading change since the previous
    scan this round (``previous``, None: none) over the turns between them, within +-10 deg/turn."""
    if previous is None or not time - previous[6] > 0:
        return 0.0
    return min(max(_relative(heading - previous[3]) / (time - previous[6]), -MAX_RATE), MAX_RATE)


def body_turn(space: TankSpace, x: float, y: float, heading: float, enemies: Sequence[EnemyRow], target: int,
              turn: float) -> float:
    """The body turn commanded at a step's start for the action's ``turn`` (smdp_kernel.smdp_turns): with
    ``turn_mode="target"`` and a target, the turn putting the body at that angle to the target's bearing from
    its last scanned position, wrapped to [-pi, pi); else ``turn``."""
    if space.turn_mode != "target" or target < 0:
        return turn
    row = enemies[target]
    return _relative(java_atan2(row[0] - x, row[1] - y) + turn - heading)


def robot_control(control: ControlConfig, lead: str, x: float, y: float, gun_heading: float, radar_heading: float,
                  gun_heat: float, energy: float, enemies: Sequence[EnemyRow], target: int, power: float,
                  time: float, width: float, height: float, gun_aim: float = math.nan) -> tuple[float, float, float]:
    """(gun turn (NaN = keep), radar turn, fire power) of the controller (smdp.controller_turn) toward
    ``enemies[target]`` with the step's ``lead`` (one of TankSpace.leads: "none", "linear", or "circular" with
    the row's turn rate; ``lead_point``, bullet power ``power`` or 2 when not set; "gf": the gun to the brain's
    absolute angle ``gun_aim``, circular when NaN); ``power`` -1 holds fire, 0 picks it by distance band."""
    if target < 0:
        return math.nan, 2 * math.pi, 0.0
    row = enemies[target]
    tx, ty = float(row[0]), float(row[1])
    aimed = lead == "gf" and not math.isnan(gun_aim)
    if lead != "none" and not aimed:
        rate = float(row[7]) if lead in ("circular", "gf") else 0.0  # gf without an aim: circular
        tx, ty = lead_point(x, y, tx, ty, float(row[3]), float(row[4]), rate, float(time - row[6]),
                            power if power > 0 else 2.0, float(width), float(height))
    dx, dy = tx - x, ty - y
    bearing = java_atan2(dx, dy)  # Math.atan2's bits, as TankModel
    dist = java_hypot(dx, dy)
    gun = _relative((gun_aim if aimed else bearing) - gun_heading)
    radar = _relative(bearing - radar_heading)
    radar = radar + float(np.sign(radar)) * control.radar_overshoot
    shoot = abs(gun) <= control.aim_tolerance and gun_heat == 0 and energy > 0 and control.fire
    if not shoot or power < 0:
        p = 0.0
    elif power > 0:
        p = power
    elif dist < control.near_distance:
        p = control.power_near
    elif dist < control.far_distance:
        p = control.power_mid
    else:
        p = control.power_far
    return gun, radar, float(p)


@dataclass(frozen=True)
class TankPolicy:
    """A tank policy: the actor MLP (weights (out, in), tanh hidden layers, linear logits) over the tank view,
    its TankSpace, the controller's settings, the step length in turns and how it plays (``play``: greedy, or
    sampled from each head's softmax)."""

    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]
    space: TankSpace = field(default_factory=TankSpace)
    control: ControlConfig = field(default_factory=ControlConfig)
    step_turns: int = 5
    play: Play = "greedy"

    def __post_init__(self) -> None:
        if self.play not in PLAYS:
            raise ValueError(f"play must be one of {', '.join(PLAYS)}, got {self.play!r}")
        if isinstance(self.step_turns, bool) or not isinstance(self.step_turns, int) \
                or not 1 <= self.step_turns <= MAX_STEP_TURNS:
            raise ValueError(f"step_turns must be a whole number from 1 to {MAX_STEP_TURNS}, got "
                             f"{str(self.step_turns)[:40]}")
        if not self.weights or len(self.weights) != len(self.biases):
            raise ValueError("the actor needs as many weight matrices as bias vectors (at least one)")
        n_in = self.space.n_features
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            if w.ndim != 2 or w.shape[1] != n_in or b.shape != (w.shape[0],):
                raise ValueError(f"layer {i}: weights {w.shape} / bias {b.shape} do not chain from {n_in}")
            if not (np.all(np.isfinite(w)) and np.all(np.isfinite(b))):
                raise ValueError(f"layer {i} has non-finite values")
            n_in = w.shape[0]
        if n_in != sum(self.space.dims):
            raise ValueError(f"the actor outputs {n_in} logits, the heads {self.space.dims} need "
                             f"{sum(self.space.dims)}")

    @classmethod
    def from_state(cls, state: Mapping[str, np.ndarray], space: TankSpace | None = None,
                   control: ControlConfig | None = None, step_turns: int = 5) -> TankPolicy:
        """From the actor's arrays: ``w0, b0, w1, b1, ...`` (weights (out, in)), or a torch state dict's linear
        layers ``actor.<i>.weight`` / ``actor.<i>.bias`` (in the order of i)."""
        if "w0" in state:
            n = sum(1 for k in state if re.fullmatch(r"w\d+", k))
            names = [(f"w{i}", f"b{i}") for i in range(n)]
        else:
            idx = sorted(int(m.group(1)) for k in state if (m := re.fullmatch(r"actor\.(\d+)\.weight", k)))
            if not idx:
                raise ValueError(f"no actor weights (w0 or actor.<i>.weight) among {sorted(state)}")
            names = [(f"actor.{i}.weight", f"actor.{i}.bias") for i in idx]
        missing = [k for pair in names for k in pair if k not in state]
        if missing:
            raise ValueError(f"actor arrays missing: {missing}")
        return cls(tuple(np.asarray(state[w], dtype=np.float64) for w, _ in names),
                   tuple(np.asarray(state[b], dtype=np.float64).reshape(-1) for _, b in names),
                   space or TankSpace(), control or ControlConfig(), step_turns)

    # -- decisions -------------------------------------------------------------------------------
    def logits(self, view: np.ndarray) -> np.ndarray:
        """The actor's logits for one view (rounded to float32 first, as the simulator hands it over)."""
        h = np.asarray(view, dtype=np.float32).astype(np.float64)
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            h = w @ h + b
            if i < len(self.weights) - 1:
                h = np.tanh(h)
        return h

    def act(self, view: np.ndarray, u: Sequence[float] | None = None) -> int:
        """Joint action (``np.ravel_multi_index`` over TankSpace.dims): the first maximum of each head, or with
        ``play`` sampled, :func:`sample_heads` with the uniform draws ``u`` (one per head)."""
        z = self.logits(view)
        if self.play == "sampled":
            if u is None:
                raise ValueError("a sampling policy needs its uniform draws u (one per head)")
            return sample_heads(z, self.space.dims, u)
        joint, off = 0, 0
        for n in self.space.dims:
            joint = joint * n + int(np.argmax(z[off:off + n]))
            off += n
        return joint

    def decode(self, action: int) -> tuple[float, float, float, int, str]:
        """(distance, body turn rad (see body_turn), fire power (-1 = hold), enemy slot, gun lead) of a joint
        action (action_table)."""
        d, t, p, k = action_table(self.space)[action][:4]
        lead = self.space.leads[int(np.unravel_index(action, self.space.dims)[-1])]
        return float(d), float(t), float(p), int(k), lead

    # -- file ----------------------------------------------------------------------------------
    def to_text(self) -> str:
        """The policy file read by TankModel.java."""
        s = self.space

        def nums(v: Sequence[float]) -> str:
            return " ".join(repr(float(x)) for x in v)

        lines = ["confront-tank 1", f"step_turns {self.step_turns}", f"distances {nums(s.distances)}",
                 f"turns_deg {nums(s.turns_deg)}", f"turn_mode {s.turn_mode}",
                 f"fire_powers {nums(s.fire_powers)}", f"enemy_slots {s.enemy_slots}",
                 f"mate_slots {s.mate_slots}", f"leads {' '.join(s.leads)}"]
        lines += [f"{name} 1" for name in ("surf", "knowledge") if getattr(s, name)]  # skills: absent when off
        if s.skills and s.brain != "SurfGF":  # absent: SurfGF, the brain of older files
            lines.append(f"brain {s.brain}")
        if self.play != "greedy":
            lines.append(f"play {self.play}")
        for f in fields(ControlConfig):
            v = getattr(self.control, f.name)
            lines.append(f"{f.name} {int(v) if isinstance(v, bool) else repr(float(v))}")
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            for name, a in ((f"w{i}", w), (f"b{i}", b[None, :])):
                lines.append(f"matrix {name} {a.shape[0]} {a.shape[1]}")
                lines.extend(" ".join(repr(float(v)) for v in row) for row in a)
        return "\n".join(lines) + "\n"


def export_tank_robot(policy: TankPolicy, out: str | Path, install: EngineInstall | None = None,
                      embed: bool = True) -> Path:
    """Write the standalone robot ``confront.TankBot`` with ``policy``: a robots folder or a ``.jar``.

    It holds ``confront/TankBot.class``, ``TankModel.class``, the classes it shares with PolicyBot
    (:data:`TANK_CLASSES`), ``TankData.class`` (the policy
    as string constants, so the robot reads no file), ``TankBot.properties``, ``tank_policy.txt``, the team
    ``TankTeam.team`` (four TankBots: Robocode lists it as ``confront.TankTeam 1.0``) and the Java sources.
    ``embed=False`` leaves out TankData (no javac run: engine training): the robot then reads the file the JVM
    property ``confront.tank.model`` names, else its ``tank_policy.txt``; both need the engine run with
    ``-DNOSECURITY=true`` (the sandbox refuses robots reading files, their own jar included)."""
    return write_robot(out, "TankBot", TANK_CLASSES, "TankData" if embed else None, "tank_policy.txt",
                       policy.to_text(), "A tank policy trained with confront (PPO), exported with its own inference",
                       install, team="TankTeam")


def evaluate_tank_policy(policy: TankPolicy, scenario: str, opponents: str | Sequence[str], rounds: int = 100,
                         seed: int = 0, cpu_constant_ms: float = TANK_CPU_CONSTANT_MS,
                         install: EngineInstall | None = None, opponent_policy: ExportedPolicy | None = None,
                         one_cpu: bool = False, visible: bool = False) -> tuple[BattleResults, float]:
    """Play the exported TankBot (a jar, no Python in the loop) for our side of ``scenario`` (``1v1``,
    ``4v4``, ...) against ``opponents`` in the engine, or with ``opponent_policy`` against that paper policy
    exported as ``confront.PolicyBot`` (e.g. the TD team, the dodge); return (results, our score ratio).
    ``one_cpu``: the engine process on one CPU, as training in the engine runs it (``EngineOptions.one_cpu``);
    ``visible``: in Robocode's battle window (``EngineOptions.visible``)."""
    from confront.engine.battle import scenario_battle, single_star
    from confront.engine.runner import EngineOptions, run_battle

    with tempfile.TemporaryDirectory(prefix="confront-tank-eval-") as tmp:
        robots = [export_tank_robot(policy, Path(tmp) / "tankbot.jar", install)]
        if opponent_policy is not None:
            robots.append(export_robot(opponent_policy, Path(tmp) / "robots", install))
            opponents = "confront.PolicyBot"
        spec = single_star(scenario_battle(scenario, TANK_ROBOT, opponents, rounds=rounds), "confront.PolicyBot*")
        opts = EngineOptions(seed=seed, cpu_constant_ms=cpu_constant_ms, one_cpu=one_cpu, visible=visible)
        res = run_battle(spec, opts,
                         extra_robots=robots, install=install).results
    # by name: in 1v1 against an exported PolicyBot both robots' names start with "confront."
    ours = next(r for r in res.contestants if r.name.startswith((TANK_ROBOT.split()[0], "confrontteams.Ours")))
    return res, res.score_ratio(ours.name)


def _model_dir(run: str | Path) -> Path:
    p = Path(run)
    return p / "model" if (p / "model").is_dir() else p


def is_tank_run(run: str | Path) -> bool:
    """True when the run's (or model folder's) ``model.json`` says ``"kind": "ppo"``."""
    try:
        info = json.loads((_model_dir(run) / "model.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(info, dict) and info.get("kind") == "ppo"


def load_tank_policy(run: str | Path, play: Play = "greedy") -> TankPolicy:
    """The policy of a PPO run (or model folder): ``actor.npz`` and ``tank.json``, playing ``play``. Files that
    are missing give a FileNotFoundError, files that are corrupt or do not fit (a hand-edited ``tank.json``, a
    truncated ``actor.npz``, NaN weights, a step of 1e30 turns) a CheckpointError naming the folder."""
    from confront.checkpoint import CheckpointError

    folder = _model_dir(run)
    try:
        return _read_tank_policy(folder, play)
    except FileNotFoundError as exc:
        raise FileNotFoundError(f"no trained tank model in {run} (its {Path(exc.filename or '').name} is missing)"
                                ) from None
    except (OSError, ValueError, TypeError, KeyError, AttributeError, EOFError, RecursionError,
            zipfile.BadZipFile) as exc:  # JSON, Unicode and numpy errors are ValueErrors
        why = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise CheckpointError(f"model {folder} cannot be used: {why}") from None


def _read_tank_policy(folder: Path, play: Play) -> TankPolicy:
    with (folder / "tank.json").open("rb") as fh:
        cfg = json.loads(fh.read(1 << 20))
    if not isinstance(cfg, dict):
        raise ValueError("tank.json is not a table")
    tank_cfg = cfg.get("tank", cfg)
    names = {f.name for f in fields(TankSpace)}
    given: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in tank_cfg.items() if k in names}
    space = TankSpace(**given)
    ctl_cfg = cfg.get("control", cfg)
    control = ControlConfig(**{f.name: ctl_cfg[f.name] for f in fields(ControlConfig) if f.name in ctl_cfg})
    step = cfg.get("step_turns", cfg.get("turns_per_step"))
    if step is None:
        raise ValueError("tank.json lacks step_turns")
    if isinstance(step, bool) or not isinstance(step, int):
        raise ValueError(f"tank.json's step_turns must be a whole number of turns, got {str(step)[:40]}")
    if "dims" in cfg and tuple(cfg["dims"]) != space.dims:
        raise ValueError(f"tank.json: dims {str(cfg['dims'])[:60]} do not match the action heads {space.dims}")
    with np.load(folder / "actor.npz", allow_pickle=False) as z:
        state = {k: z[k] for k in z.files}
    return replace(TankPolicy.from_state(state, space, control, int(step)), play=play)


def export_tank_cli(run: str | Path, out: str | Path, play: Play = "sampled") -> Path:
    """``confront export`` for a PPO run: write confront.TankBot (playing ``play``) and say where."""
    import click

    path = export_tank_robot(load_tank_policy(run, play), out)
    click.echo(f"wrote the robot confront.TankBot and the team confront.TankTeam (4 TankBots) to {path}: copy it "
               f"into Robocode's robots folder ({ROBOTS_FOLDER_HINT}; no Python needed to run it), or open Robocode "
               f"with it: confront robocode {path}")
    return path
