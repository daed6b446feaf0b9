"""The pipeline's stages, one module each (the table of them: :mod:`artic_cli.stages.table`).

Each stage module declares ``STAGE`` (its config sections, the stages it reads, its artefact's kind), a
``compute`` over objects and arrays, and ``write(path, ...)`` / ``read(path)``; its file-level entry
(``build_mesh``, ``simulate``, ``build_ep_maps``, ...) is what the CLI and ``make`` call.  The common entries
are importable from here.
"""

from __future__ import annotations

import importlib

_ENTRIES = {"build_mesh": "mesh", "simulate": "simulate", "load_model": "simulate", "validate_cuboid": "cuboid",
            "run_experiment": "experiments", "build_muscle_function": "muscle_function",
            "build_ep_maps": "epmap", "build_dynamic_map": "dynamic", "solve_target": "solve",
            "load_context": "solve", "write_report": "report"}


def __getattr__(name: str):
    if name in _ENTRIES:
        return getattr(importlib.import_module(f"{__name__}.{_ENTRIES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = sorted(_ENTRIES)
