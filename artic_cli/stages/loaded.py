"""Artefacts loaded once per process: a corpus worker speaks item after item on the same maps, mesh and
config, and loads (and builds the model from) them once, not per item.

A loaded thing is kept under its files' identities (path, size, modification time), so a file rewritten
since is loaded again; the few most recent are kept.  What is kept is only read afterwards: the maps, the
model, the simulators (whose answers depend on their inputs alone).
"""

from __future__ import annotations

import os
from collections import OrderedDict
from pathlib import Path
from typing import Callable, TypeVar

T = TypeVar("T")
KEEP = 4  # things of each kind: a corpus uses one set of maps; a test suite's many small ones come and go
_kept: dict[str, OrderedDict] = {}


def identity(path: Path | str | None) -> tuple | None:
    """A file as the cache knows it (None: no file given; a missing file is its path alone)."""
    if path is None:
        return None
    p = Path(path)
    try:
        st = os.stat(p)
    except OSError:
        return (str(p.absolute()),)
    return str(p.resolve()), st.st_size, st.st_mtime_ns, st.st_ino


def once(kind: str, make: Callable[[], T], files: tuple, extra: tuple = ()) -> T:
    """``make()`` the first time ``kind`` is asked for with these files (as they are now) and ``extra``; the
    kept result afterwards."""
    key = (tuple(identity(f) for f in files), extra)
    kept = _kept.setdefault(kind, OrderedDict())
    if key in kept:
        kept.move_to_end(key)
        return kept[key]
    value = make()
    kept[key] = value
    while len(kept) > KEEP:
        kept.popitem(last=False)
    return value


def forget() -> None:
    """Drop everything kept (tests; a worker that wants its memory back)."""
    _kept.clear()
