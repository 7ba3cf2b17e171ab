"""Every experiment end to end at a tiny size: outputs exist and hold what they claim."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from confront.experiments.reproduce import reproduce
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
    for name in ("migration", "awm", "fuzzy", "transfer"):
        assert f"| {name} |" in report
        claims = json.loads((tiny / name / "claims.json").read_text())
        assert claims and all(c["holds"] in (True, False, None) for c in claims)
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
