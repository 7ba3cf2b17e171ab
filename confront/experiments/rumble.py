"""``confront rumble``: a robot against every robot of a folder of jars in the real engine, as a table per opponent.

The candidate is a trained run folder (exported on the way as ``confront export`` does), a robot jar or a class of
Robocode's own robots (``sample.Tracker``). Battles come from :mod:`confront.engine.rumble` (one JVM each, stored
as ``<out>/battles/<key>.json``, never played twice); this module plans them, checks the input, and turns the stored
results into the table: per opponent the candidate's APS (its share of the two sides' total score; in melee the
RoboRumble's pairwise share against that opponent in the battles they met), mean over seeds with a 95% t-interval,
survival (rounds the candidate's side finished first, over rounds), its bullet damage per battle, and what the engine
said about a robot that could not be loaded, threw, hung or overran its time. Written as ``rumble.md``,
``rumble.csv``, ``rumble.json`` and the bar plot ``rumble.png``.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
import textwrap
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from confront.engine.rumble import (
    MELEE_OTHERS,
    MODES,
    PROBLEMS,
    TEAM_SIZE,
    BattleJob,
    Robot,
    RunStats,
    default_timeout_s,
    folder_robots,
    jar_robots,
    job_key,
    run_jobs,
    write_json_atomic,
)
from confront.stats import t_interval


@dataclass(frozen=True)
class RumbleSettings:
    """What every battle of a rumble shares (validated here: the command's bad input is a ValueError)."""

    mode: str = "1v1"
    seeds: int = 1
    rounds: int = 0  # 0: the mode's RoboRumble default
    width: int = 0  # 0: the mode's default field
    height: int = 0
    cpu_constant_ms: float = 10.0
    team_size: int = TEAM_SIZE
    timeout_s: float = 0.0  # 0: default_timeout_s
    one_cpu: bool = False  # each battle's JVM on one claimed CPU with C1 only (EngineOptions.one_cpu)

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        rounds, width, height = MODES[self.mode]
        object.__setattr__(self, "rounds", self.rounds or rounds)
        if bool(self.width) != bool(self.height):
            raise ValueError("give the field's width and height together")
        object.__setattr__(self, "width", self.width or width)
        object.__setattr__(self, "height", self.height or height)
        if self.seeds < 1 or self.rounds < 1:
            raise ValueError(f"seeds and rounds must be >= 1, got {self.seeds} and {self.rounds}")
        if not (400 <= self.width <= 5000 and 400 <= self.height <= 5000):
            raise ValueError(f"field must be 400..5000 on each side, got {self.width}x{self.height}")
        if not (math.isfinite(self.cpu_constant_ms) and self.cpu_constant_ms > 0):
            raise ValueError(f"cpu constant must be > 0 ms, got {self.cpu_constant_ms}")
        if not 1 <= self.team_size <= 10:
            raise ValueError(f"team size must be 1..10, got {self.team_size}")
        if self.timeout_s < 0:
            raise ValueError(f"timeout must be > 0 s, got {self.timeout_s}")

    def shared(self) -> dict[str, Any]:
        """The settings a stored battle depends on (seeds and the time limit may change between runs)."""
        d = asdict(self)
        del d["seeds"], d["timeout_s"]
        return d


def parse_field(text: str) -> tuple[int, int]:
    """'800x600' -> (800, 600)."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if m is None:
        raise ValueError(f"field must be WIDTHxHEIGHT, e.g. 800x600, got {text!r}")
    return int(m.group(1)), int(m.group(2))


_CLASS = re.compile(r"^[A-Za-z_$][\w$]*(\.[A-Za-z_$][\w$]*)+$")


def resolve_candidate(candidate: str, out: Path) -> tuple[Robot, Path | None]:
    """The candidate robot and its jar (None for one of the engine's own robots): a trained run folder is exported
    into ``<out>/candidate/``, a jar must hold one robot, a class name must be one of Robocode's robots."""
    path = Path(candidate)
    if path.is_dir():
        from confront.experiments.evaluate import run_jar

        (out / "candidate").mkdir(parents=True, exist_ok=True)
        jar = run_jar(path, out / "candidate")
    elif candidate.endswith(".jar"):
        if not path.is_file():
            raise FileNotFoundError(f"no such robot jar: {path}")
        jar = path
    else:
        from confront.engine.install import find_engine

        own = find_engine().samples / (candidate.replace(".", "/") + ".class")
        if not _CLASS.match(candidate) or not own.is_file():
            raise ValueError(f"candidate {candidate!r} is neither a run folder, a robot jar nor a class of "
                             "Robocode's own robots (e.g. sample.Tracker)")
        return Robot(candidate), None
    robots = [r for r in jar_robots(jar) if not r.is_team]
    if len(robots) != 1 or robots[0].problem:
        found = robots[0].problem if robots and robots[0].problem else f"{len(robots)} robots"
        raise ValueError(f"candidate jar {jar.name} must hold one robot, found {found}")
    return robots[0], jar


def plan_jobs(candidate: Robot, opponents: Sequence[Robot], settings: RumbleSettings) -> list[BattleJob]:
    """The battles: each opponent at each seed (1v1, teams); in melee, per seed, the opponents in a seeded order,
    cut into groups of up to 9 that each meet the candidate."""
    s = settings
    groups: list[tuple[int, tuple[Robot, ...]]] = []
    for seed in range(s.seeds):
        if s.mode == "melee":
            order = np.random.default_rng(seed).permutation(len(opponents))
            picked = [opponents[i] for i in order]
            groups += [(seed, tuple(picked[i:i + MELEE_OTHERS])) for i in range(0, len(picked), MELEE_OTHERS)]
        else:
            groups += [(seed, (o,)) for o in opponents]
    jobs = []
    for seed, group in groups:
        n = s.team_size + sum(len(o.members) or s.team_size for o in group) if s.mode == "teams" else 1 + len(group)
        jobs.append(BattleJob(job_key(s.mode, group, seed), s.mode, candidate, group, seed, s.rounds, s.width,
                              s.height, s.cpu_constant_ms, s.team_size,
                              s.timeout_s or default_timeout_s(s.rounds, n), s.one_cpu))
    return jobs


# -- the table ----------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RumbleRow:
    """One opponent's line of the table (NaN where no battle gave a number)."""

    opponent: str
    status: str
    battles: int
    aps: float
    aps_lo: float
    aps_hi: float
    survival_pct: float
    bullet_dmg: float
    reason: str = ""


def battle_shares(result: dict[str, Any]) -> dict[str, tuple[float, float, float]]:
    """Per opponent of one stored battle: (the candidate's share, its survival fraction, its bullet damage). The
    share is the candidate side's total over the candidate's and that opponent's totals (0 when both are 0);
    contestants are in the battle's order, the candidate's side first."""
    rows = result.get("contestants", [])
    if result.get("status") != "ok" or len(rows) != 1 + len(result["opponents"]):
        return {}
    ours = rows[0]
    survival = ours["firsts"] / result["rounds"]
    out = {}
    for name, theirs in zip(result["opponents"], rows[1:], strict=True):
        total = ours["total"] + theirs["total"]
        out[name] = (ours["total"] / total if total > 0 else 0.0, survival, float(ours["bullet_dmg"]))
    return out


def _worst(found: Sequence[str]) -> str:
    """The most serious of some problem texts ('kind: words'), '' for none."""
    ranked = sorted(found, key=lambda p: next((i for i, k in enumerate(PROBLEMS) if p.startswith(k)), len(PROBLEMS)))
    return ranked[0] if ranked else ""


def table_rows(opponents: Sequence[Robot], results: Sequence[dict[str, Any]], candidate: str) -> list[RumbleRow]:
    """The table, one row per opponent in the given order, from the stored battles."""
    rows = []
    for opp in opponents:
        mine = [r for r in results if opp.name in r["opponents"]]
        values = [battle_shares(r)[opp.name] for r in mine if opp.name in battle_shares(r)]
        found = [opp.problem] if opp.problem else []
        for r in mine:
            if r["status"] != "ok":
                found.append(r["reason"])
            names = (*opp.members, opp.name)
            found += [p for n, p in r.get("problems", {}).items() if n in names]
        own = _worst([p for r in mine for n, p in r.get("problems", {}).items() if n == candidate])
        reason = _worst(found)
        if own:
            reason = f"{reason}; candidate {own}" if reason else f"candidate {own}"
        status = reason.split(":")[0] if reason and not reason.startswith("candidate") else "ok"
        arr = np.array(values, dtype=np.float64).reshape(-1, 3)
        iv = t_interval(arr[:, 0])
        nan = float("nan")
        rows.append(RumbleRow(opp.name, status, len(values), iv.mean, iv.lo, iv.hi,
                              float(arr[:, 1].mean() * 100) if len(values) else nan,
                              float(arr[:, 2].mean()) if len(values) else nan, reason))
    return rows


def _num(v: float, fmt: str = ".3f") -> str:
    return "-" if math.isnan(v) else format(v, fmt)


def to_markdown(rows: Sequence[RumbleRow], title: str) -> str:
    """The table as Markdown, with the mean APS over the opponents that gave a number."""
    lines = [f"### {title}", "", "| opponent | APS | 95% CI | survival % | bullet dmg | battles | status | "
             "the engine's words |", "|---|---:|---|---:|---:|---:|---|---|"]
    for r in rows:
        ci = "-" if math.isnan(r.aps_lo) else f"[{r.aps_lo:.3f}, {r.aps_hi:.3f}]"
        words = r.reason.replace("|", "/")
        lines.append(f"| {r.opponent} | {_num(r.aps)} | {ci} | {_num(r.survival_pct, '.1f')} | "
                     f"{_num(r.bullet_dmg, '.1f')} | {r.battles} | {r.status} | {words} |")
    scored = [r.aps for r in rows if not math.isnan(r.aps)]
    lines += ["", f"APS over {len(scored)} opponent(s): {np.mean(scored):.3f}" if scored else "no battle scored"]
    return "\n".join(lines) + "\n"


def to_csv(rows: Sequence[RumbleRow]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(asdict(rows[0]) if rows else ["opponent"]), lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow(asdict(r))
    return buf.getvalue()


def plot_rows(rows: Sequence[RumbleRow], title: str, path: Path) -> None:
    """Horizontal bars of APS with their intervals; opponents with a problem in grey."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 0.4 * len(rows) + 1.5))
    y = np.arange(len(rows))[::-1]
    aps = np.array([0.0 if math.isnan(r.aps) else r.aps for r in rows])
    lo = np.array([a if math.isnan(r.aps_lo) else r.aps_lo for a, r in zip(aps, rows, strict=True)])
    hi = np.array([a if math.isnan(r.aps_hi) else r.aps_hi for a, r in zip(aps, rows, strict=True)])
    colors = ["tab:blue" if r.status == "ok" else "tab:gray" for r in rows]
    ax.barh(y, aps, color=colors, xerr=np.vstack([aps - lo, hi - aps]).clip(0), capsize=3)
    ax.set_yticks(y, [r.opponent if r.status == "ok" else f"{r.opponent} ({r.status})" for r in rows])
    ax.axvline(0.5, color="k", lw=0.6, ls=":")
    ax.set_xlim(0, 1)
    ax.set_xlabel("APS: the candidate's share of the score\n(95% t-interval over seeds)")
    ax.set_title("\n".join(textwrap.wrap(title, 50)), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# -- the command --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RumbleReport:
    """What :func:`run_rumble` did and found."""

    rows: list[RumbleRow]
    stats: RunStats
    markdown: str
    out: Path
    title: str = ""


def opponents_of(folder: Path, candidate: Robot, mode: str) -> list[Robot]:
    """The folder's robots that meet the candidate in ``mode`` (teams only in teams mode; not the candidate)."""
    robots = [r for r in folder_robots(folder) if (mode == "teams" or not r.is_team) and r.name != candidate.name]
    if not robots:
        raise ValueError(f"no robots in {folder}: it holds no robot jar" + ("" if mode == "teams" else
                                                                            " with a robot other than the candidate"))
    return robots


def run_rumble(candidate: str, folder: str | os.PathLike[str], settings: RumbleSettings, out: str | os.PathLike[str],
               workers: int = 1, address: str | None = None, progress: bool = True) -> RumbleReport:
    """Play the rumble's missing battles and write the table (rumble.md/.csv/.json, rumble.png) into ``out``."""
    folder, out = Path(folder), Path(out)
    if not folder.is_dir():
        raise FileNotFoundError(f"no such folder: {folder}")
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    robot, jar = resolve_candidate(candidate, out)
    opponents = opponents_of(folder, robot, settings.mode)
    out.mkdir(parents=True, exist_ok=True)
    stored = {"candidate": robot.name, **settings.shared()}
    settings_file = out / "settings.json"
    if settings_file.is_file() and json.loads(settings_file.read_text()) != stored:
        raise ValueError(f"{out} holds a rumble with other settings ({settings_file}): give another --out")
    write_json_atomic(settings_file, stored)
    playable = [o for o in opponents if not o.problem]
    jobs = plan_jobs(robot, playable, settings)
    jar_files = {p.name: p for p in folder.glob("*.jar")}
    if jar is not None:
        jar_files[jar.name] = jar
        if robot.jar != jar.name:
            raise ValueError(f"candidate jar {jar.name} is not where its robot was read")
    stats = run_jobs(jobs, jar_files, out / "battles", workers=workers, address=address, progress=progress)
    results = [json.loads(f.read_text()) for j in jobs if (f := out / "battles" / f"{j.key}.json").is_file()]
    results += stats.unplayed
    rows = table_rows(opponents, results, robot.name)
    s = settings
    title = (f"{robot.name} ({s.mode}{f', teams of {s.team_size}' if s.mode == 'teams' else ''}), {s.rounds} rounds "
             f"on {s.width}x{s.height} x {s.seeds} seed(s), CPU constant {s.cpu_constant_ms:g} ms")
    markdown = to_markdown(rows, title)
    (out / "rumble.md").write_text(markdown)
    (out / "rumble.csv").write_text(to_csv(rows))
    write_json_atomic(out / "rumble.json", {"title": title, "settings": {**stored, "seeds": s.seeds},
                                            "rows": [asdict(r) for r in rows]})
    plot_rows(rows, title, out / "rumble.png")
    return RumbleReport(rows, stats, markdown, out, title)


def default_workers() -> int:
    """Local battles at once by default: the CPUs this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def rumble_cli(candidate: str, folder: Path, mode: str, seeds: int, rounds: int | None, field: str | None,
               cpu_constant: float, team_size: int, workers: int | None, address: str | None, out: Path | None,
               timeout: float | None, one_cpu: bool, quiet: bool) -> None:
    """``confront rumble``: run, then print the Markdown table."""
    import click

    try:
        width, height = parse_field(field) if field else (0, 0)
        settings = RumbleSettings(mode, seeds, rounds or 0, width, height, cpu_constant, team_size, timeout or 0.0,
                                  one_cpu)
        if out is None:
            stem = Path(candidate).stem if candidate.endswith(".jar") or Path(candidate).is_dir() else candidate
            out = Path("rumbles") / (re.sub(r"[^\w.-]+", "_", stem) + f"-{mode}")
        report = run_rumble(candidate, folder, settings, out, workers=workers or default_workers(), address=address,
                            progress=not quiet)
    except ValueError as err:
        raise click.UsageError(str(err)) from None
    click.echo(report.markdown)
    st = report.stats
    click.echo(f"{st.played} battle(s) played, {st.done_before} already done"
               + (f", {len(st.unplayed)} could not be run (tried again next time)" if st.unplayed else "")
               + f"; table, CSV, JSON and plot in {out}")
