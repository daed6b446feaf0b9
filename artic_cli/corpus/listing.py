"""A corpus list: one item a line, ``id<TAB>text``, optionally ``<TAB>rate<TAB>accent<TAB>config``; or a CSV
with those columns named in its header (``id`` and ``text`` required).

``rate`` is the speaking rate (0.5-2, default 1), ``accent`` the mora the pitch falls after in a one-word text
(0: unaccented; empty: the text's own marks), ``config`` a config file (relative to the list's folder) whose
``speech`` section the item is spoken with.  Blank lines and lines starting with ``#`` are skipped.  The list's
form is checked on load (an id that cannot be a file name, a repeated id, a column that is not a number: one
line naming the line); what only speaking can find (an unknown character, a rate outside 0.5-2) becomes that
item's failure in the index.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

from ..errors import ArticError
from ..validation import SAFE_NAME

COLUMNS = ("id", "text", "rate", "accent", "config")


@dataclass(frozen=True)
class Item:
    id: str
    text: str
    rate: float = 1.0
    accent: int | None = None  # None: the text's own marks
    config: str | None = None  # a config file (absolute), None: the corpus's

    def as_dict(self) -> dict:
        return {"id": self.id, "text": self.text, "rate": self.rate, "accent": self.accent, "config": self.config}


def read_listing(path: Path | str) -> list[Item]:
    """The items of a list file (tab-separated text, or CSV by its ``.csv`` suffix)."""
    path = Path(path)
    if not path.is_file():
        raise ArticError(f"corpus list not found: {path}; give a text file of 'id<TAB>text' lines or a CSV")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ArticError(f"{path} is not UTF-8 text; save the list as UTF-8") from None
    rows = _csv_rows(text, path) if path.suffix.lower() == ".csv" else _tsv_rows(text)
    items, seen = [], {}
    for line, cells in rows:
        where = f"{path}, line {line}"
        item = _item(cells, where, path.parent)
        if item.id in seen:
            raise ArticError(f"{where}: id '{item.id}' is already used on line {seen[item.id]}; give each item "
                             "its own id")
        seen[item.id] = line
        items.append(item)
    if not items:
        raise ArticError(f"{path} holds no items; give one 'id<TAB>text' line per item")
    return items


def _tsv_rows(text: str) -> list[tuple[int, dict]]:
    out = []
    for n, raw in enumerate(text.splitlines(), 1):
        if not raw.strip() or raw.lstrip().startswith("#"):
            continue
        cells = raw.split("\t")
        if len(cells) > len(COLUMNS):
            raise ArticError(f"line {n}: {len(cells)} tab-separated columns; give at most {len(COLUMNS)}: "
                             f"{', '.join(COLUMNS)}")
        out.append((n, dict(zip(COLUMNS, cells))))
    return out


def _csv_rows(text: str, path: Path) -> list[tuple[int, dict]]:
    reader = csv.DictReader(io.StringIO(text))
    head = [h.strip() for h in (reader.fieldnames or [])]
    unknown = [h for h in head if h not in COLUMNS]
    if unknown or not {"id", "text"} <= set(head):
        raise ArticError(f"{path}: the header must name 'id' and 'text' (and optionally rate, accent, config); "
                         f"it has {', '.join(head) or 'nothing'}")
    out = []
    for row in reader:
        cells = {k.strip(): (v or "") for k, v in row.items() if k is not None}
        if None in row:
            raise ArticError(f"{path}, line {reader.line_num}: more cells than the header names; quote a text "
                             "that holds a comma")
        if any(v.strip() for v in cells.values()):
            out.append((reader.line_num, cells))
    return out


def _item(cells: dict, where: str, folder: Path) -> Item:
    ident, text = cells.get("id", "").strip(), cells.get("text", "").strip()
    if not SAFE_NAME.fullmatch(ident):
        raise ArticError(f"{where}: id '{ident}' cannot be a file name; use letters, digits, '_', '-' or '.', "
                         "starting with a letter, digit or '_'")
    if "text" not in cells:
        raise ArticError(f"{where}: no text; give 'id<TAB>text'")
    rate = _number(cells.get("rate", ""), "rate", where, float, 1.0)
    accent = _number(cells.get("accent", ""), "accent", where, int, None)
    if accent is not None and accent < 0:
        raise ArticError(f"{where}: accent {accent}; give the mora the pitch falls after (0: unaccented)")
    config = cells.get("config", "").strip() or None
    if config is not None:
        p = Path(config) if Path(config).is_absolute() else folder / config
        if not p.is_file():
            raise ArticError(f"{where}: config {config} not found (relative to {folder}); give an existing file")
        config = str(p.resolve())
    return Item(ident, text, rate, accent, config)


def _number(value: str, name: str, where: str, kind, default):
    value = value.strip()
    if not value:
        return default
    try:
        return kind(value)
    except ValueError:
        raise ArticError(f"{where}: {name} '{value}' is not {'a number' if kind is float else 'a whole number'}"
                         ) from None
