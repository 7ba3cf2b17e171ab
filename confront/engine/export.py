"""Exporting a trained policy as a standalone Robocode robot (``confront.PolicyBot``) with its own Java
inference: the paper's state features, a Q table or an MLP, the four macro moves and the fixed gun/radar
controller. :class:`ExportedPolicy` is the Python twin; it is also a bridge policy, so the same object can
be played through the bridge and compared with the exported robot decision by decision.

Policy file (text, data only): ``confront-policy 1``, then ``key value`` lines and ``matrix NAME ROWS
COLS`` blocks (``q``; or ``w0, b0, w1, b1, ...`` with weights as (out, in)).
"""

from __future__ import annotations

import math
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from confront.arena.control import ControlConfig, aim
from confront.arena.observe import (
    N_STATES,
    ObservationConfig,
    discrete_state,
    features,
    field_diagonal,
    robot_observation,
    select_targets,
)
from confront.checkpoint import write_atomic
from confront.engine.bridge import Observation, RobotActing
from confront.engine.install import ENGINE_VERSION, EngineInstall, find_engine
from confront.engine.java_build import MODEL_CLASSES, ROBOT_HELPERS, compile_java

ACTIVATIONS = ("bipolar", "tanh", "relu", "linear")
POLICY_CLASSES = ("PolicyBot", "PolicyModel", *MODEL_CLASSES, *ROBOT_HELPERS)
TEAM_SIZE = 4  # the exported team: our side in every team scenario (4v4, 4v6, 4v10)
# where Debian's robocode (its /usr/games/robocode launcher) keeps the robots it lists
ROBOTS_FOLDER_HINT = f"Debian's robocode: ~/.local/share/robocode/{ENGINE_VERSION}/robots/ after its first start"


@dataclass(frozen=True)
class ExportedPolicy:
    """A greedy policy over the paper's observation: Q table (320 x 4) or MLP on the features."""

    kind: str
    q: np.ndarray | None = None
    weights: tuple[np.ndarray, ...] = ()
    biases: tuple[np.ndarray, ...] = ()
    hidden_activation: str = "bipolar"
    output_activation: str = "linear"
    act_a: float = 1.725  # Eq. 19
    act_b: float = 0.566
    observation: ObservationConfig = field(default_factory=ObservationConfig)
    control: ControlConfig = field(default_factory=ControlConfig)
    step_turns: int = 1
    inputs: str = "features"  # mlp input: the continuous features, or "onehot" of the discrete state
    ties: str = "first"  # equal best values: the first, or one at random (a stochastic policy, e.g. the dodge)

    def __post_init__(self) -> None:
        if self.kind not in ("qtable", "mlp"):
            raise ValueError(f"kind must be 'qtable' or 'mlp', got {self.kind!r}")
        if self.observation.target != "nearest":
            raise ValueError("observation.target must be 'nearest' for export")
        if self.step_turns < 1:
            raise ValueError(f"step_turns must be >= 1, got {self.step_turns}")
        if self.inputs not in ("features", "onehot"):
            raise ValueError(f"inputs must be 'features' or 'onehot', got {self.inputs!r}")
        if self.ties not in ("first", "random"):
            raise ValueError(f"ties must be 'first' or 'random', got {self.ties!r}")
        if self.kind == "qtable":
            if self.q is None or np.shape(self.q) != (N_STATES, 4) or not np.all(np.isfinite(self.q)):
                got = "none" if self.q is None else f"shape {np.shape(self.q)}"
                raise ValueError(f"q must be a finite ({N_STATES}, 4) array, got {got}")
        else:
            if not self.weights or len(self.weights) != len(self.biases):
                raise ValueError("mlp needs as many weight matrices as bias vectors (at least one)")
            n_in = self.observation.n_features if self.inputs == "features" else N_STATES
            for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
                if w.ndim != 2 or w.shape[1] != n_in or b.shape != (w.shape[0],):
                    raise ValueError(f"layer {i}: weights {w.shape} / bias {b.shape} do not chain from {n_in}")
                n_in = w.shape[0]
            if n_in != 4:
                raise ValueError(f"mlp must output 4 action values, got {n_in}")
            for name in ("hidden_activation", "output_activation"):
                if getattr(self, name) not in ACTIVATIONS:
                    raise ValueError(f"{name} must be one of {ACTIVATIONS}, got {getattr(self, name)!r}")

    @classmethod
    def from_learner(
        cls,
        learner: object,
        observation: ObservationConfig | None = None,
        control: ControlConfig | None = None,
        step_turns: int = 1,
    ) -> ExportedPolicy:
        """The greedy policy of a trained learner: a tabular Q learner (``state_dict()["q"]``, 320 x 4) or a
        DMNN (weights ``w0, b0, ...`` stored (in, out), bipolar hidden layers, linear or bipolar output)."""
        state = learner.state_dict()  # type: ignore[attr-defined]
        obs_cfg = observation or ObservationConfig()
        ctl = control or ControlConfig()
        if "q" in state:
            return cls("qtable", q=np.asarray(state["q"], dtype=np.float64), observation=obs_cfg, control=ctl,
                       step_turns=step_turns)
        n = sum(1 for k in state if k.startswith("w") and k[1:].isdigit())
        if n == 0:
            raise ValueError(f"learner state has neither 'q' nor 'w0': keys {sorted(state)}")
        p = learner.params  # type: ignore[attr-defined]
        return cls(
            "mlp", weights=tuple(np.asarray(state[f"w{i}"], dtype=np.float64).T for i in range(n)),
            biases=tuple(np.asarray(state[f"b{i}"], dtype=np.float64) for i in range(n)),
            hidden_activation="bipolar", output_activation=p.output, act_a=p.a, act_b=p.b,
            observation=obs_cfg, control=ctl, step_turns=step_turns,
            inputs="onehot" if learner.observation == "discrete" else "features",  # type: ignore[attr-defined]
        )

    # -- decisions -------------------------------------------------------------------------------
    @staticmethod
    def _enemies(obs: Observation) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        es = obs.enemies()
        return (np.array([s.x for s in es]), np.array([s.y for s in es]), np.array([s.energy for s in es]))

    def _activate(self, name: str, v: np.ndarray) -> np.ndarray:
        if name == "bipolar":
            return self.act_a * np.tanh(self.act_b * v / 2)  # Eq. 19 = a * tanh(b x / 2)
        if name == "tanh":
            return np.tanh(v)
        if name == "relu":
            return np.maximum(v, 0.0)
        return v

    def state_and_features(self, obs: Observation) -> tuple[int, np.ndarray]:
        """The paper's discrete state and the continuous features (float32) of one bridge observation: the
        simulator kernel's rule for one robot (``confront.arena.observe.robot_observation``; this tank is robot
        0, the enemies it has seen are the others, the target the nearest, first of equals), about 10x cheaper
        than the batched functions for one observation; :meth:`state_and_features_batched` gives the same."""
        es = obs.enemies()
        n = len(es) + 1
        x, y, e = np.empty(n), np.empty(n), np.empty(n)
        x[0], y[0], e[0] = obs.x, obs.y, obs.energy
        target, best = -1, math.inf
        for j, s in enumerate(es, 1):
            x[j], y[j], e[j] = s.x, s.y, s.energy
            dx, dy = s.x - obs.x, s.y - obs.y
            if dx * dx + dy * dy < best:
                target, best = j, dx * dx + dy * dy
        dmax = self.observation.max_distance or field_diagonal(obs.width, obs.height)
        feat = np.empty(self.observation.n_features)
        state = robot_observation(x, y, np.full(n, obs.heading), e, 0, target, float(dmax), float(obs.width),
                                  float(obs.height), feat)
        return int(state), feat.astype(np.float32)

    def state_and_features_batched(self, obs: Observation) -> tuple[int, np.ndarray]:
        """:meth:`state_and_features` through the batched ``confront.arena.observe`` functions (the reference
        a test compares the one-robot kernel with)."""
        ex, ey, ee = self._enemies(obs)
        x = np.concatenate([[obs.x], ex])[None, :]
        y = np.concatenate([[obs.y], ey])[None, :]
        energy = np.concatenate([[obs.energy], ee])[None, :]
        heading = np.full_like(x, obs.heading)
        team = np.array([0] + [1] * len(ex))
        target = select_targets(x, y, energy, np.ones_like(x, dtype=bool), team, "nearest")
        dmax = self.observation.max_distance or field_diagonal(obs.width, obs.height)
        state = int(discrete_state(x, y, heading, target, dmax)[0, 0])
        fld = (obs.width, obs.height) if self.observation.include_position else None
        return state, features(x, y, heading, energy, target, dmax, fld)[0, 0]

    def learner_observation(self, obs: Observation, kind: str) -> np.ndarray:
        """What a learner with ``observation`` = ``kind`` ("discrete" or "features") sees, as a batch of 1."""
        state, feats = self.state_and_features(obs)
        if kind == "discrete":
            return np.array([state], dtype=np.int64)
        if kind == "features":
            return feats[None, :].astype(np.float64)
        raise ValueError(f"observation kind must be 'discrete' or 'features', got {kind!r}")

    def values(self, obs: Observation) -> np.ndarray:
        """Action values of the four moves for one observation."""
        return self.values_of(*self.state_and_features(obs))

    def values_of(self, state: int, feats: np.ndarray) -> np.ndarray:
        """Action values of the four moves for the paper's discrete ``state`` and the continuous ``feats``."""
        if self.kind == "qtable":
            assert self.q is not None
            return np.asarray(self.q[state], dtype=np.float64)
        if self.inputs == "onehot":
            h = np.zeros(N_STATES)
            h[state] = 1.0
        else:
            h = feats.astype(np.float64)
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            last = i == len(self.weights) - 1
            h = self._activate(self.output_activation if last else self.hidden_activation, w @ h + b)
        return h

    def act(self, obs: Observation, rng: np.random.Generator | None = None) -> int:
        """Greedy move id: 0 forward, 1 backward, 2 clockwise, 3 anticlockwise; the first maximum, or with
        ``ties="random"`` one of the maxima drawn from ``rng``."""
        v = self.values(obs)
        if self.ties == "random":
            best = np.flatnonzero(v == v.max())
            return int(best[(rng or np.random.default_rng()).integers(len(best))])
        return int(np.argmax(v))

    def gun_radar(self, obs: Observation) -> tuple[float, float, float]:
        """(gun turn, radar turn, fire power) of the fixed controller (``confront.arena.control.aim``) toward
        the nearest enemy at its last scanned position."""
        es = obs.enemies()
        if not es:
            return (math.nan, 2 * math.pi, 0.0)
        d2 = [(s.x - obs.x) ** 2 + (s.y - obs.y) ** 2 for s in es]
        t = es[int(np.argmin(d2))]
        gun, radar, power = aim(np.float64(obs.x), np.float64(obs.y), obs.gun_heading, obs.radar_heading,
                                obs.gun_heat, obs.energy, t.x, t.y, np.True_, self.control)
        return (float(gun), float(radar), float(power))

    def robot_acting(self, max_lag: int = 8) -> RobotActing:
        """Bridge settings for robots that play this (fixed) Q table themselves, first maximum as PolicyBot:
        ``run_bridged_battle(..., every=step_turns, controller=control, acting=policy.robot_acting())``. The
        table never changes, so ``max_lag`` only bounds what a robot sends ahead of a stalled Python side."""
        if self.kind != "qtable":
            raise ValueError("robots act themselves from a Q table only")
        text = self.to_text()
        return RobotActing(model=lambda: text, explore="first", max_lag=max_lag)

    def __call__(self, obs: Observation) -> tuple[float, float, float, float, float]:
        """Bridge policy with the exported robot's timing: a move every ``step_turns`` turns. An observation
        of a robot that has moved itself (``obs.action >= 0``, :meth:`robot_acting`) needs no answer."""
        if obs.action >= 0:
            return (math.nan,) * 5
        ahead = turn = math.nan
        if (obs.turn - 1) % self.step_turns == 0:
            a = self.act(obs)
            c = self.control
            ahead, turn = {0: (c.move_distance, 0.0), 1: (-c.move_distance, 0.0),
                           2: (c.turn_move_distance, c.turn_angle),
                           3: (c.turn_move_distance, -c.turn_angle)}[a]
        gun, radar, fire = self.gun_radar(obs)
        return (ahead, turn, gun, radar, fire)

    # -- file ----------------------------------------------------------------------------------
    def to_text(self) -> str:
        """The policy file read by PolicyModel.java."""
        lines = ["confront-policy 1", f"kind {self.kind}", f"step_turns {self.step_turns}", f"ties {self.ties}",
                 f"target {self.observation.target}", f"max_distance {float(self.observation.max_distance or 0)!r}",
                 f"include_position {int(self.observation.include_position)}"]
        for f in fields(ControlConfig):
            v = getattr(self.control, f.name)
            lines.append(f"{f.name} {int(v) if isinstance(v, bool) else repr(float(v))}")

        def matrix(name: str, a: np.ndarray) -> None:
            a2 = np.atleast_2d(np.asarray(a, dtype=np.float64))
            lines.append(f"matrix {name} {a2.shape[0]} {a2.shape[1]}")
            lines.extend(" ".join(repr(float(v)) for v in row) for row in a2)

        if self.kind == "qtable":
            assert self.q is not None
            matrix("q", self.q)
        else:
            lines += [f"inputs {self.inputs}", f"hidden_activation {self.hidden_activation}",
                      f"output_activation {self.output_activation}",
                      f"act_a {self.act_a!r}", f"act_b {self.act_b!r}"]
            for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
                matrix(f"w{i}", w)
                matrix(f"b{i}", b[None, :])
        return "\n".join(lines) + "\n"


def policy_data_source(text: str, chunk: int = 30000, name: str = "PolicyData") -> str:
    """Java source of ``confront.<name>`` (default PolicyData): the policy text as string constants (each
    < 64 KB)."""
    def lit(part: str) -> str:
        return '"' + part.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'

    parts = [text[i:i + chunk] for i in range(0, len(text), chunk)]
    body = ",\n        ".join(lit(p) for p in parts)
    return ("package confront;\n\n/** Exported policy (generated by confront.engine.export). */\n"
            f"public final class {name} {{\n    public static final String[] CHUNKS = {{\n        "
            + body + f"\n    }};\n\n    private {name}() {{\n    }}\n}}\n")


def export_robot(policy: ExportedPolicy, out: str | Path, install: EngineInstall | None = None,
                 version: str = "1.0") -> Path:
    """Write the standalone robot ``confront.PolicyBot`` with ``policy``: a robots folder or a ``.jar``.

    A folder gets ``confront/PolicyBot.class``, ``PolicyModel.class``, the classes it shares with TankBot
    (:data:`POLICY_CLASSES`), ``PolicyData.class`` (the policy compiled in as string constants, so the robot
    reads no file), ``PolicyBot.properties``, ``policy.txt``,
    the team ``PolicyTeam.team`` (four PolicyBots, the paper's team size) and the Java sources; a jar holds the same
    files and can be dropped into Robocode's robots folder.
    """
    return write_robot(out, "PolicyBot", POLICY_CLASSES, "PolicyData", "policy.txt", policy.to_text(),
                       "A policy trained with confront (fuzzy RL), exported with its own inference", install, version,
                       team="PolicyTeam")


def write_robot(out: str | Path, bot: str, classes: tuple[str, ...], data: str | None, policy_file: str, text: str,
                description: str, install: EngineInstall | None = None, version: str = "1.0",
                team: str | None = None) -> Path:
    """A robot ``confront.<bot>`` as a robots folder or a ``.jar``: the project's compiled ``classes`` and their
    sources, ``<bot>.properties``, the policy ``text`` as ``policy_file`` and compiled into the class ``data``
    (string constants: the robot reads no file, in the engine's sandbox or from a jar; ``None``: no such class,
    no javac run). ``team``: also ``confront/<team>.team``, :data:`TEAM_SIZE` of the robot, which Robocode lists
    as the team ``confront.<team> <version>``."""
    install = install or find_engine()
    compiled = compile_java(install)
    out = Path(out)
    with tempfile.TemporaryDirectory(prefix="confront-export-") as tmp:
        root = Path(tmp) / "robot" if out.suffix == ".jar" else out
        pkg = root / "confront"
        pkg.mkdir(parents=True, exist_ok=True)
        src = Path(__file__).parent / "java" / "confront"
        for cls in classes:  # a name may hold a subpackage's folder ("tech/TechBrain")
            (pkg / cls).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(compiled / "confront" / f"{cls}.class", pkg / f"{cls}.class")
            shutil.copy2(src / f"{cls}.java", pkg / f"{cls}.java")
        (pkg / f"{bot}.properties").write_text(
            f"robot.classname=confront.{bot}\nrobot.name={bot}\nrobot.version={version}\n"
            f"robot.description={description}\nrobot.java.source.included=true\nrobocode.version=1.9.3.9\n"
        )
        (pkg / policy_file).write_text(text)
        if team is not None:
            members = ",".join([f"confront.{bot} {version}"] * TEAM_SIZE)
            (pkg / f"{team}.team").write_text(
                f"team.members={members}\nteam.author.name=confront\nteam.version={version}\n"
                f"team.description={TEAM_SIZE} {bot}s sharing one trained policy\nrobocode.version=1.9.3.9\n")
        if data is not None:
            (pkg / f"{data}.java").write_text(policy_data_source(text, name=data))
            proc = subprocess.run([install.javac, "-nowarn", "-encoding", "UTF-8", "-d", str(root),
                                   str(pkg / f"{data}.java")], capture_output=True, text=True, check=False)
            if proc.returncode != 0:
                raise RuntimeError(f"javac failed on the policy data:\n{proc.stderr.strip()}")
        if out.suffix == ".jar":  # built aside, then put in place atomically (a link there is replaced)
            jar = shutil.which("jar") or str(Path(install.javac).with_name("jar"))
            built = Path(tmp) / "robot.jar"
            subprocess.run([jar, "cf", str(built), "-C", str(root), "."], check=True, capture_output=True)
            write_atomic(out, built.read_bytes())
    return out
