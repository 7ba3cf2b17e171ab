"""Every experiment end to end at a tiny size: outputs exist and hold what they claim."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from confront.experiments.reproduce import Claim, compare, reproduce, restate_claim
from confront.runs import Run


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("results")
    import os

    os.environ["CONFRONT_CACHE"] = str(out / "cache")
    reproduce("all", seeds=2, rounds=8, out=out, workers=1, episodes=200)
    return out


def test_report_has_every_claim(tiny: Path) -> None:
    report = (tiny / "report.md").read_text()
    assert "Seeds actually run per arm: migration 1000, awm 2, fuzzy 2, transfer 2." in report
    assert "| effect [95% CI] | p | detectable (power 0.8) | verdict | criterion |" in report
    for name in ("migration", "awm", "fuzzy", "transfer"):
        assert f"| {name} |" in report
        claims = json.loads((tiny / name / "claims.json").read_text())
        assert claims and all(c["verdict"] in ("holds", "partly", "no", "n/a") for c in claims)
        assert all(c["holds"] == {"holds": True, "partly": False, "no": False, "n/a": None}[c["verdict"]]
                   for c in claims)
        assert all(c["effect"] and c["p"] and c["mde"] and c["criterion"] for c in claims)
    assert "Paired over 1000 seeds" in (tiny / "migration" / "convergence.md").read_text()
    for fig in ("awm/figures/fig10_12_score_ratio.png", "awm/figures/fig11_fluctuation.png",
                "fuzzy/figures/fig13_fuzzy_learning_rate.png", "fuzzy/figures/fig14_scores.png",
                "transfer/figures/fig16_17_score_ratio.png", "transfer/figures/fig18_score_ratio.png"):
        assert (tiny / fig).stat().st_size > 5000
        assert f"({fig})" in report
    assert (tiny / "report.html").read_text().count("<tr>") >= 10


def test_arms_ran_with_their_settings(tiny: Path) -> None:
    import tomllib

    runs = tiny / "awm" / "runs"
    with_awm = tomllib.loads((runs / "nn-with-awm" / "seed-1" / "config.toml").read_text())
    without = tomllib.loads((runs / "nn-without-awm" / "seed-0" / "config.toml").read_text())
    assert with_awm["learner"]["awm"] is True and without["learner"]["awm"] is False
    assert with_awm["train"]["seed"] == 1 and with_awm["train"]["rounds"] == 8
    for exp in ("awm", "fuzzy"):  # the reference arm beyond the paper: random moves, never learns
        ref = tiny / exp / "runs" / "random-moves" / "seed-0"
        assert tomllib.loads((ref / "config.toml").read_text())["learner"]["kind"] == "random"
        assert json.loads((ref / "summary.json").read_text())["learner"]["updates"] == 0
        claims = json.loads((tiny / exp / "claims.json").read_text())
        assert any("than random moves" in c["text"] for c in claims)
    lm = tomllib.loads((tiny / "fuzzy" / "runs" / "lm-0-95" / "seed-0" / "config.toml").read_text())
    assert lm["learner"]["learning_rate"] == "fixed" and lm["learner"]["alpha"] == 0.95
    # the curriculum: 4v6 with TF starts from the 4v4 source run, 4v10 with TF from the 4v6 with-TF run
    t = tiny / "transfer" / "runs"
    mid = tomllib.loads((t / "with-tf-4v6" / "seed-0" / "config.toml").read_text())
    assert mid["arena"]["scenario"] == "4v6" and mid["transfer"]["source"].endswith("source-4v4/seed-0")
    target = tomllib.loads((t / "with-tf-4v10" / "seed-0" / "config.toml").read_text())
    assert target["transfer"]["source"].endswith("with-tf-4v6/seed-0")
    scratch = tomllib.loads((t / "without-tf-4v10" / "seed-0" / "config.toml").read_text())
    assert scratch["transfer"]["source"] == ""


def test_session_metrics_match_rounds(tiny: Path) -> None:
    run = Run(tiny / "fuzzy" / "runs" / "flm" / "seed-0")
    rounds, sessions = run.read_table("rounds"), run.read_table("sessions")
    assert len(rounds) == 8 and len(sessions) == 2
    o = sum(r["score_ours"] for r in rounds[:4])
    t = sum(r["score_theirs"] for r in rounds[:4])
    assert sessions[0]["score_ratio"] == pytest.approx(o / (o + t))
    assert sessions[1]["fluctuation"] == pytest.approx(sessions[1]["score_ratio"] - sessions[0]["score_ratio"])
    assert all(0.0 <= r["score_ratio"] <= 1.0 for r in rounds)
    assert np.isfinite([r["score_ours"] for r in rounds]).all()


def test_rerun_reuses_finished_runs(tiny: Path) -> None:
    summary = tiny / "awm" / "runs" / "nn-with-awm" / "seed-0" / "summary.json"
    before = summary.stat().st_mtime_ns
    reproduce("awm", seeds=2, rounds=8, out=tiny, workers=1)
    assert summary.stat().st_mtime_ns == before


def test_arms_of_one_seed_share_the_world_and_the_opponent(tiny: Path) -> None:
    """Changing only the learner leaves the draws identical: the arms of a seed differ in learner and transfer
    keys only, so they get the same arena seed (start positions), TD team and opponent stream."""
    from confront.arena.smdp import TeamBattleEnv
    from confront.config import to_dict
    from confront.experiments.reproduce import awm, fuzzy, transfer
    from confront.train.league import td_team
    from confront.train.paper_model import scenario_of, smdp_config
    from confront.train.spec import load_experiment

    for build in (awm, fuzzy, transfer):
        jobs, _ = build(2, tiny, np.random.default_rng(0), 4)
        groups: dict[tuple[int, str], list] = {}
        for j in jobs:
            cfg = load_experiment(j.base, j.overrides + (f"train.seed={j.seed}",))
            groups.setdefault((j.seed, cfg.arena.scenario), []).append(cfg)
        for (seed, _scenario), cfgs in groups.items():
            world = [{k: to_dict(c)[k] for k in ("arena", "opponent")} | {"seed": c.train.seed} for c in cfgs]
            assert all(w == world[0] for w in world) and world[0]["seed"] == seed
    cfgs = [load_experiment("awm", (f"learner.awm={v}", "train.seed=1")) for v in ("true", "false")]
    assert cfgs[0].learner != cfgs[1].learner
    states = []
    for cfg in cfgs:
        env = TeamBattleEnv(scenario_of(cfg.arena.scenario), n_battles=cfg.arena.battles, seed=cfg.train.seed,
                            opponents="td", config=smdp_config(cfg))
        states.append(env.state_dict())
    assert states[0].keys() == states[1].keys()
    for k in states[0]:
        np.testing.assert_array_equal(states[0][k], states[1][k], err_msg=k)
    assert td_team(cfgs[0], 4)[1] == td_team(cfgs[1], 4)[1]


def test_bad_seed_counts_are_refused_in_one_line(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from confront.cli.main import cli

    for option in ("--seeds", "--rounds", "--workers"):  # issue 34 item 19: --rounds and --workers too
        for bad in ("0", "-5"):
            res = CliRunner().invoke(cli, ["reproduce", "migration", option, bad])
            assert res.exit_code == 2
            line = res.output.strip()
            assert line.startswith(f"error: Invalid value for '{option}'") and "\n" not in line, line
    for bad in (0, -1):
        with pytest.raises(ValueError, match="seeds"):
            reproduce("migration", seeds=bad)
        for key in ("rounds", "workers"):
            with pytest.raises(ValueError, match=key):
                reproduce("fuzzy", out=tmp_path / "out", **{key: bad})
    assert not (tmp_path / "out").exists()


def test_paired_compare_gives_three_verdicts() -> None:
    rng = np.random.default_rng(0)
    b = rng.normal(0.5, 0.05, 10)
    noise = np.linspace(-0.01, 0.01, 10)
    # 0.05 better on every seed: significant, but the CI stays below the paper's +0.1 -> partly
    c = compare("x", "-", b + 0.05 + noise, b, "A", "B", rng, paper_diff=0.1)
    assert c.verdict == "partly" and c.holds is False and float(c.p) == pytest.approx(1 / 1024, rel=1e-3)
    assert c.effect.startswith("A - B 0.05 [")
    assert compare("x", "-", b + 0.15 + noise, b, "A", "B", rng, paper_diff=0.1).verdict == "holds"
    worse = compare("x", "-", b - 0.05 + noise, b, "A", "B", rng)
    assert worse.verdict == "no" and float(worse.p) == pytest.approx(1.0)
    assert compare("x", "-", b[:1] + 0.2, b[:1], "A", "B", rng).verdict == "n/a"  # one seed: nothing to test
    assert Claim("t", "-", "o", None).verdict == "n/a" and Claim("t", "-", "o", verdict="partly").holds is False
    with pytest.raises(ValueError, match="verdict"):
        Claim("t", "-", "o", verdict="maybe")


def test_committed_claims_are_restated_from_their_numbers() -> None:
    old = {"text": "With TF the score ratio is higher than without (4v6)", "figure": "Fig. 16",
           "ours": "with TF 0.5 [0.4, 0.6] vs without TF 0.3 [0.2, 0.4] (score ratio); p = 0.01, g = 1.00",
           "holds": True, "detail": "n = 10/10 seeds"}
    c = restate_claim(old, 10)
    # se = hypot(0.2, 0.2) / 3.92 = 0.0722; 0.2 +- 1.96 se = [0.0586, 0.341]
    assert c.verdict == "holds" and c.effect == "with TF - without TF 0.2 [0.0586, 0.341]" and c.p == "0.01"
    level = {"text": "FLM's score ratio stays around 0.8", "figure": "Fig. 14", "ours": "FLM 0.78 [0.76, 0.80]",
             "holds": True, "detail": "holds if the interval lies in 0.8 +- 0.05"}
    assert restate_claim(level, 10).verdict == "holds"
    assert restate_claim({**level, "ours": "FLM 0.72 [0.70, 0.76]"}, 10).verdict == "partly"
    assert restate_claim({**level, "ours": "FLM 0.41 [0.38, 0.43]"}, 10).verdict == "no"
    new = restate_claim(c.__dict__, 10)
    assert new == c


@pytest.mark.parametrize("args", [["--rounds", "0"], ["--rounds", "-5"], ["--workers", "0"], ["--workers", "-3"]])
def test_reproduce_refuses_bad_rounds_and_workers_before_starting(args: list[str], tmp_path: Path,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 34 item 19: ``reproduce migration --rounds 0/-5`` and ``--workers 0/-3`` were accepted silently."""
    from click.testing import CliRunner

    from confront.cli.main import cli

    started: list[dict] = []
    monkeypatch.setattr("confront.experiments.reproduce.reproduce_cli", lambda *a, **kw: started.append(kw))
    res = CliRunner().invoke(cli, ["reproduce", "migration", *args, "--out", str(tmp_path / "out")])
    assert res.exit_code == 2 and started == [], (res.output, started)
    bound = "1<=x<=2147483647" if args[0] == "--rounds" else "x>=1"  # rounds: Robocode's Java int
    assert res.stderr == (f"error: Invalid value for '{args[0]}': {args[1]} is not in the range {bound}. "
                          "(see `cli reproduce --help`)\n"), res.stderr
    assert not (tmp_path / "out").exists()
