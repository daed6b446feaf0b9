"""The report's row on the place heard in the noise (issue 45: /sh/'s centroid below /s/'s)."""

from __future__ import annotations

from artic_cli.report.speech import centroid_rows


def test_the_centroid_row_agrees_only_when_every_sh_lies_below_every_s():
    (row,) = centroid_rows({"s": [6500.0, 7800.0], "sh": [4200.0]})
    assert row.verdict.startswith("agrees") and "4200" in row.ours and "7800" in row.ours
    (row,) = centroid_rows({"s": [6500.0, 7800.0], "sh": [4200.0, 7000.0]})
    assert row.verdict.startswith("differs")  # one /sh/ above one /s/
    assert centroid_rows({"s": [6500.0], "sh": []}) == []
