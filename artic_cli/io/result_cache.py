"""Results kept on disk by the hash of what made them, each written atomically: arrays as
``FOLDER/KIND-SHA.npz``, an object (a built model) pickled as ``FOLDER/KIND-SHA.pickle``.

A cache entry is a pure function's result (for example where a set of muscle forces held from the rest posture
takes the articulators): its key names everything the result depends on, so an entry is never stale, only
unused.  A damaged or unreadable entry counts as missing and is made again.  What is put is written on
:meth:`ResultCache.commit`, once the run that made it has succeeded.  A pickle runs code when read: the
folder is for one user's own runs, as a solutions folder is."""

from __future__ import annotations

import contextlib
import pickle
from pathlib import Path

import numpy as np

from .fingerprint import digest
from .store import atomic_path


class ResultCache:
    """``get(key)`` / ``put(key, arrays)`` (or ``get_object`` / ``put_object``) for one kind of result under
    ``folder``; ``key`` is any JSON-like value (arrays are hashed as their lists), ``scope`` what every key of
    this cache shares (the model's recipe)."""

    def __init__(self, folder: Path | str, kind: str, scope=None):
        self.folder, self.kind, self.scope = Path(folder), kind, scope
        self.pending: dict[Path, tuple[str, object]] = {}  # put, not yet written (:meth:`commit`)

    def path(self, key, suffix: str = ".npz") -> Path:
        return self.folder / f"{self.kind}-{digest([self.scope, key])[:32]}{suffix}"

    def get(self, key) -> dict[str, np.ndarray] | None:
        return self._read(self.path(key), lambda fh: dict(np.load(fh, allow_pickle=False)))

    def put(self, key, arrays: dict[str, np.ndarray]) -> None:
        self.pending[self.path(key)] = ("npz", {k: np.asarray(v) for k, v in arrays.items()})

    def get_object(self, key):
        return self._read(self.path(key, ".pickle"), pickle.load)

    def put_object(self, key, obj) -> None:
        self.pending[self.path(key, ".pickle")] = ("pickle", obj)

    def _read(self, path: Path, load):
        """What was put at ``path`` and not yet written, else the file read by ``load`` (None: missing or
        damaged)."""
        if path in self.pending:
            return self.pending[path][1]
        if not path.is_file():
            return None
        with contextlib.suppress(Exception), open(path, "rb") as fh:
            return load(fh)
        return None

    def commit(self) -> None:
        """Write what was put (a run that failed commits nothing, and leaves no folder behind)."""
        for path, (how, value) in self.pending.items():
            with atomic_path(path, suffix=path.suffix) as tmp, open(tmp, "wb") as fh:
                if how == "npz":
                    np.savez(fh, **value)
                else:
                    pickle.dump(value, fh, protocol=pickle.HIGHEST_PROTOCOL)
        self.pending.clear()


__all__ = ["ResultCache"]
