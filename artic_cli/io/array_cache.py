"""Arrays kept on disk by the hash of what made them: ``FOLDER/KIND-SHA.npz``, each written atomically.

A cache entry is a pure function's result (for example where a set of muscle forces held from the rest posture
takes the articulators): its key names everything the result depends on, so an entry is never stale, only
unused.  A damaged or unreadable entry counts as missing and is made again."""

from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np

from .fingerprint import digest
from .store import atomic_path


class ArrayCache:
    """``get(key)`` / ``put(key, arrays)`` for one kind of result under ``folder``; ``key`` is any JSON-like
    value (arrays are hashed as their lists), ``scope`` what every key of this cache shares (the model's
    recipe)."""

    def __init__(self, folder: Path | str, kind: str, scope=None):
        self.folder, self.kind, self.scope = Path(folder), kind, scope

    def path(self, key) -> Path:
        return self.folder / f"{self.kind}-{digest([self.scope, key])[:32]}.npz"

    def get(self, key) -> dict[str, np.ndarray] | None:
        path = self.path(key)
        if not path.is_file():
            return None
        with contextlib.suppress(Exception), np.load(path, allow_pickle=False) as f:
            return {name: f[name] for name in f.files}
        return None

    def put(self, key, arrays: dict[str, np.ndarray]) -> None:
        path = self.path(key)
        with atomic_path(path, suffix=".npz") as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **{k: np.asarray(v) for k, v in arrays.items()})


__all__ = ["ArrayCache"]
