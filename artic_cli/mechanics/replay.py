"""A schedule run from the rest posture: what ``artic simulate`` does, callable from the solver so that an
answer is checked in exactly the model a user runs (the same start, forces, step and duration)."""

from __future__ import annotations

from typing import Callable

from ..schedule import Schedule, parse_schedule
from .loads import load_program
from .model import Model, State, rest_state
from .simulate import Trajectory, run, settle


def held_forces(forces_n: dict[str, float], duration_ms: float, max_force_n: float = 10.0) -> Schedule:
    """The schedule that switches every force (N; jaw and tongue muscles, groups) on at 0 ms and holds it for
    ``duration_ms``."""
    return parse_schedule({"duration_ms": duration_ms,
                           "muscles": [{"muscle": m, "force_n": float(f), "onset_ms": 0.0, "duration_ms": duration_ms}
                                       for m, f in sorted(forces_n.items()) if f > 0]},
                          "<held forces>", max_force_n)


def run_schedule(model: Model, schedule: Schedule, duration_s: float, dt_s: float | None = None,
                 tongue_only: bool = False, record_every: int = 1, source: str = "schedule",
                 progress: Callable[[int, int], None] | None = None, start: State | None = None) -> Trajectory:
    """``schedule`` from the rest posture (settled under gravity for the articulator; ``start``: that rest,
    already settled), as ``artic simulate`` runs it."""
    program = load_program(model, schedule, source)
    if start is None:
        start = rest_state(model) if tongue_only else settle(model)
    traj, _ = run(model, start, program.control_at, duration_s, dt_s, record_every=record_every,
                  progress=progress, keep_partial=True)
    return traj
