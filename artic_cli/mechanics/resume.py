"""Running again from part-way: a run whose controls agree with an earlier run's up to some step starts from that
run's snapshot there (:func:`.simulate.run`'s ``snapshots_every``) and is spliced onto its frames, so that it is
the same, frame for frame, as running the whole again.

Whether two control courses agree is decided on the values the integrator samples (each step's middle), so
the caller need not know why they differ (a later switch, a pulse shortened by it)."""

from __future__ import annotations

from typing import Callable

import numpy as np

from .model import Control, Model
from .simulate import Trajectory, run


def first_difference(a: Callable[[float], Control], b: Callable[[float], Control], t0: float, dt: float,
                     n_steps: int) -> int:
    """The first step (1-based) at whose middle the two control courses differ, ``n_steps + 1`` if none."""
    for k in range(1, n_steps + 1):
        t = t0 + (k - 0.5) * dt
        ca, cb = a(t), b(t)
        if not (np.array_equal(ca.muscle_force, cb.muscle_force) and np.array_equal(ca.node_force, cb.node_force)):
            return k
    return n_steps + 1


def resumed(model: Model, prior: Trajectory, control_at: Callable[[float], Control], duration: float, dt: float,
            record_every: int, first_changed: int, snapshots_every: int = 0, keep_partial: bool = False
            ) -> Trajectory:
    """``run(model, start, control_at, duration, dt, record_every, ...)`` for controls that agree with the
    ``prior`` run's (from the same start, with the same steps) before step ``first_changed``: run from
    ``prior``'s latest snapshot before that step and spliced onto ``prior``'s frames up to it."""
    n_steps = max(1, int(round(duration / dt)))
    kept = [k for k in prior.snapshots if k < first_changed and k % record_every == 0 and k <= n_steps]
    if not kept:
        raise ValueError("the prior run kept no snapshot before the first changed step")
    at = max(kept)
    if at == n_steps:  # nothing changed
        return prior
    tail, _ = run(model, prior.snapshots[at], control_at, (n_steps - at) * dt, dt, record_every,
                  keep_partial=keep_partial, snapshots_every=snapshots_every)
    return spliced(prior, at, tail, record_every)


def spliced(head: Trajectory, at_step: int, tail: Trajectory, record_every: int) -> Trajectory:
    """``head``'s frames (one every ``record_every`` steps) up to its step ``at_step`` followed by ``tail``'s
    (which starts from that step's state): energies and work carried on from ``head``'s at the joint (the same
    as one run's to rounding), the snapshots and counts renumbered."""
    i = at_step // record_every
    cut = slice(0, i + 1)

    def join(a, b):
        return None if a is None or b is None else np.concatenate([np.asarray(a)[cut], np.asarray(b)[1:]])

    stats = dict(tail.stats)
    stats["steps"] = at_step + int(tail.stats.get("steps", 0))
    stats["newton_iterations"] = int(np.sum(head.iterations[cut])) + int(tail.stats.get("newton_iterations", 0))
    stats["resumed_at_step"] = at_step
    return Trajectory(time=join(head.time, tail.time), x=join(head.x, tail.x), v=join(head.v, tail.v),
                      volume=join(head.volume, tail.volume), iterations=join(head.iterations, tail.iterations),
                      energy=join(head.energy, tail.energy + head.energy[i]),
                      work=join(head.work, tail.work + head.work[i]),
                      inverted=join(head.inverted, tail.inverted), stats=stats,
                      muscle_force=join(head.muscle_force, tail.muscle_force),
                      muscle_length=join(head.muscle_length, tail.muscle_length),
                      contact_count=join(head.contact_count, tail.contact_count),
                      contact_total=join(head.contact_total, tail.contact_total),
                      contact_nodes=list(head.contact_nodes[:i + 1]) + list(tail.contact_nodes[1:]),
                      contact_forces=list(head.contact_forces[:i + 1]) + list(tail.contact_forces[1:]),
                      projected=join(head.projected, tail.projected),
                      snapshots={**{k: s for k, s in head.snapshots.items() if k <= at_step},
                                 **{at_step + k: s for k, s in tail.snapshots.items()}})


__all__ = ["first_difference", "resumed", "spliced"]
