"""A corpus's index: one row per item, as ``index.csv`` and its JSON-lines twin ``index.jsonl``.

Both are rewritten atomically, in the list's order, after every finished item, so an interrupted run leaves an
index of what finished.  The files' hashes are sha256 of their bytes, except the HDF5 record's: its
``content_sha256`` (what it holds; the file also records when it was written).  ``wall_s`` is the only column
that differs between two runs of the same list.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

from ..io.store import file_hash, stored_content_hash, write_text_atomic

FIELDS = ("id", "text", "rate", "accent", "status", "exit_code", "error", "phones", "duration_s", "sample_rate_hz",
          "wav", "textgrid", "h5", "ema", "wav_sha256", "textgrid_sha256", "h5_content_sha256", "ema_sha256",
          "recipe_sha256", "wall_s")
FILES = (("wav", "wav_sha256"), ("textgrid", "textgrid_sha256"), ("ema", "ema_sha256"))
STATUSES = ("ok", "unreachable", "failed")
# exit codes of a result that would come out the same again: done (0), bad input (2), unreachable (3), not
# physical (4); anything else (a crash, a lost worker) is tried again on the next run
FINAL_EXITS = (0, 2, 3, 4)


def index_paths(folder: Path | str) -> tuple[Path, Path]:
    return Path(folder) / "index.csv", Path(folder) / "index.jsonl"


def read_index(folder: Path | str) -> dict[str, dict]:
    """The rows of an earlier run by id (none if there is no index or it cannot be read: those items are
    checked again, and their up-to-date records are kept)."""
    _, jsonl = index_paths(folder)
    rows: dict[str, dict] = {}
    if not jsonl.is_file():
        return rows
    try:
        for line in jsonl.read_text(encoding="utf-8").splitlines():
            if line.strip():
                row = json.loads(line)
                rows[str(row["id"])] = row
    except (ValueError, KeyError, TypeError, UnicodeDecodeError):
        return {}
    return rows


def write_index(folder: Path | str, rows: list[dict]) -> None:
    """Both files, each through a temporary file and a rename."""
    csv_path, jsonl = index_paths(folder)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=FIELDS, lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    for r in rows:
        w.writerow({k: "" if r.get(k) is None else r[k] for k in FIELDS})
    write_text_atomic(csv_path, buf.getvalue())
    write_text_atomic(jsonl, "".join(json.dumps({k: r.get(k) for k in FIELDS}, ensure_ascii=False) + "\n"
                                     for r in rows))


def item_hashes(folder: Path | str, row: dict) -> dict[str, str | None]:
    """The hashes of an item's files as they are on disk now (None: missing)."""
    folder = Path(folder)
    out = {}
    for name, key in FILES:
        p = folder / row[name] if row.get(name) else None
        out[key] = file_hash(p) if p is not None and p.is_file() else None
    h5 = folder / row["h5"] if row.get("h5") else None
    out["h5_content_sha256"] = stored_content_hash(h5) if h5 is not None and h5.is_file() else None
    return out


def finished(folder: Path | str, row: dict | None, recipe: str) -> bool:
    """Whether an earlier row is this item's final result: the same recipe, a result that would come out the
    same, and (for a spoken item) every file still there with the hash the row records."""
    if row is None or row.get("recipe_sha256") != recipe or row.get("exit_code") not in FINAL_EXITS:
        return False
    if row.get("status") != "ok":
        return True
    now = item_hashes(folder, row)
    return all(now[k] is not None and now[k] == row.get(k) for k in now)
