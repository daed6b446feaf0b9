"""The report's "This run" row: make paper's wall time from the Makefile's ARTIC_PAPER_RUN."""

from __future__ import annotations

from pathlib import Path

import pytest

from artic_cli.report.run import PAPER_RUN_ENV, paper_run, run_section


@pytest.mark.parametrize("value", [None, "", "1 1", "x 1 2", "1 1 0", "nan 1 2", "1 1 2 3"])
def test_a_missing_or_malformed_run_record_is_not_timed(value, monkeypatch):
    assert paper_run(value) is None
    if value is None:
        monkeypatch.delenv(PAPER_RUN_ENV, raising=False)
    else:
        monkeypatch.setenv(PAPER_RUN_ENV, value)
    (row,), _ = run_section(Path("."), now_s=1000.0)
    assert row.ours == "not timed" and row.verdict.startswith("not compared")


@pytest.mark.parametrize("minutes, verdict", [(10.0, "agrees"), (15.5, "differs")])
def test_a_run_from_scratch_is_compared_with_the_goal(minutes, verdict, monkeypatch):
    monkeypatch.setenv(PAPER_RUN_ENV, "1000.5 1 2")
    (row,), _ = run_section(Path("."), now_s=1000.5 + 60 * minutes)
    assert row.ours == f"{minutes:.1f} min (2 stages at a time, from scratch)"
    assert row.verdict.startswith(verdict + " (goal <= 15 min")


def test_a_partial_rebuild_is_timed_but_not_compared(monkeypatch):
    monkeypatch.setenv(PAPER_RUN_ENV, "0 0 1")
    (row,), _ = run_section(Path("."), now_s=90.0)
    assert row.ours == "1.5 min (1 stage at a time)" and row.verdict.startswith("not compared (OUT held")
