"""Compiled loops: numba's ``njit`` when it is installed (a dependency), else plain Python with the same
numbers.  ``USE_KERNELS = False`` makes every term take its numpy path (the tests compare the two)."""

from __future__ import annotations

try:  # pragma: no cover - exercised whenever numba is installed
    from numba import njit

    AVAILABLE = True
except ImportError:  # pragma: no cover
    AVAILABLE = False

    def njit(*args, **kwargs):
        def wrap(fn):
            return fn
        return wrap(args[0]) if args and callable(args[0]) else wrap

USE_KERNELS = True


def compiled() -> bool:
    """Whether the compiled loops run (numba installed and not switched off)."""
    return AVAILABLE and USE_KERNELS
