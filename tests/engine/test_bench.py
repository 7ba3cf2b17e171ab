"""Engine throughput measurement (values are only checked for consistency, not speed)."""

from __future__ import annotations

import pytest

from confront.engine.bench import engine_throughput

pytestmark = pytest.mark.engine


def test_engine_throughput_record(install) -> None:
    rec = engine_throughput("1v1", rounds=1)
    assert (rec["scenario"], rec["batch"], rec["engine"], rec["robots"]) == ("1v1", 1, "robocode", 2)
    assert rec["turns"] > 150  # a round plus the 150 turns after it is decided
    assert rec["turns"] <= rec["robot_turns"] <= 2 * rec["turns"]
    assert rec["turns_per_s"] == pytest.approx(rec["turns"] / rec["elapsed_s"])
    assert rec["turns_per_s_excl_setup"] >= rec["turns_per_s"]
