"""One implicit step: ``step(model, state, control, dt) -> state``.

Time discretisation is Houbolt's (the paper's; Bathe 1996), or backward
Euler (``bdf1``) for comparison.  Both write acceleration and velocity as
linear functions of the new positions, a = c_a x + a*, v = c_v x + v*, so the
step is the nonlinear system

    R(x) = M a(x) - sum of the model's force terms F_k(x, v(x)) - F_ext = 0

(:mod:`.term`: cylinders and links, bricks, the condyle guide, muscles, the
wall; loads and gravity make F_ext) with geometric nonlinearity (cylinders and
fibres rotate and stretch).  It is solved by modified Newton: the Cholesky
factor of J = c_a M + c_v C + K_t (positive semidefinite parts only: each
term's blocks and constant part in the band, its rank-one terms by Woodbury)
is kept across iterations and steps and rebuilt only when an iteration
contracts the increment by less than ``refactor_rate``, the step size changes,
or a term's set of active constraints (wall contacts, the fossa stop, guarded
corners) changes.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import ArticError
from .assembly import SystemMatrix, add_low_rank, factorize
from .model import Control, Model, State
from .term import Evaluation

_MAX_INCREMENT = 0.2  # cm: the largest node move one Newton iteration may make
_REUSE_AFTER = 2  # Newton iterations of the last step up to which its matrix is reused
_MAX_HALVINGS = 4  # a step whose Newton stalls is retried as two half steps, down to dt / 16


class SimulationDiverged(ArticError):
    pass


class _Stalled(Exception):
    pass


def evaluation(model: Model, state: State, control: Control, x: np.ndarray, v: np.ndarray | None = None,
               h: float | None = None, c_v: float = 0.0) -> Evaluation:
    """An iterate at positions ``x`` (velocities ``v``, default zero) of a step of ``h`` from ``state``, every
    term's step data prepared and its forces evaluated (``ev.parts``); :func:`forces` sums them."""
    h = float(model.options.dt if h is None else h)
    terms = model.terms
    ev = Evaluation(x=x, v=np.zeros_like(x) if v is None else v, h=h, c_v=c_v, state=state, control=control,
                    step={t.name: t.prepare(model, state, control, h) for t in terms})
    return ev


def forces(model: Model, ev: Evaluation, varying: bool = True) -> np.ndarray:
    """(N, 3) the sum of the terms' forces (dyn) at the iterate: those that depend on the positions, or
    (``varying=False``) the external ones (loads, gravity)."""
    f = np.zeros_like(ev.x)
    for t in model.terms:
        if t.varies == varying:
            t.forces(model, ev, f)
    return f


def tangent(model: Model, ev: Evaluation, c_a: float, signed: bool = True) -> SystemMatrix:
    """The banded part of the Newton matrix: mass, then each term's node-level blocks and constant part
    (``signed=False``: compressed elements' geometric softening dropped, when the signed matrix fails to
    factorise)."""
    lay = model.layout
    blocks = np.zeros((lay.assembly.n_pairs + model.n_nodes, 3, 3))
    terms = model.terms
    for t in terms:
        t.blocks(model, ev, blocks, signed)
    flat = lay.assembly.operator @ blocks.ravel()
    flat += c_a * lay.mass_flat
    for t in terms:
        part = t.flat(model)
        if part is not None:
            flat += part
    return lay.pattern.unpack(flat)


def rank_one_terms(model: Model, ev: Evaluation) -> tuple[np.ndarray, np.ndarray]:
    """Newton terms k v v^T that change often or do not fit the band, every term's: (V (3N, r), k (r,))."""
    cols, ks = [], []
    for t in model.terms:
        part = t.rank_one(model, ev)
        if part is not None:
            cols.append(part[0])
            ks.append(part[1])
    if not cols:
        return np.zeros((3 * model.n_nodes, 0)), np.zeros(0)
    return np.hstack(cols), np.concatenate(ks)


def active_key(model: Model, ev: Evaluation) -> tuple:
    """Every term's active constraints at the iterate."""
    return tuple(t.key(model, ev) for t in model.terms)


def _same_step(state: State, h: float) -> bool:
    """Whether the state's history was taken with steps of ``h`` (then the multistep formulas use it)."""
    return len(state.history) >= 2 and abs(state.history_dt - h) <= 1e-9 * h


def _coefficients(model: Model, state: State, h: float):
    x0, v0 = state.x, state.v
    if model.options.scheme == "bdf1":
        return 1.0 / h**2, -x0 / h**2 - v0 / h, 1.0 / h, -x0 / h, (x0,)
    if _same_step(state, h):
        x1, x2 = state.history[:2]
    else:  # start (or change of step): history consistent with the current velocity
        x1, x2 = x0 - h * v0, x0 - 2.0 * h * v0
    a_known = (-5.0 * x0 + 4.0 * x1 - x2) / h**2
    v_known = (-18.0 * x0 + 9.0 * x1 - 2.0 * x2) / (6.0 * h)
    return 2.0 / h**2, a_known, 11.0 / (6.0 * h), v_known, (x0, x1)


def _predict(state: State, h: float) -> np.ndarray:
    """Starting guess: quadratic extrapolation of the last three positions, linear while the oldest of them
    is made up from the start's velocity (from rest under a sudden load, the quadratic guess doubles the
    first step's move and crushes bricks: 24 Newton iterations instead of 7 in the articulator's second step)."""
    if _same_step(state, h):
        x1, x2 = state.history[:2]
        if state.history_passed:
            return 3.0 * state.x - 3.0 * x1 + x2
        return 2.0 * state.x - x1
    return state.x + h * state.v


def step(model: Model, state: State, control: Control, dt: float | None = None) -> State:
    """Advance ``state`` by ``dt`` (default: the model's step) under ``control``.

    If Newton stalls (a soft mode near a force-length or volume-constraint limit can make modified
    Newton creep), the step is taken as two half steps, recursively, before giving up.
    """
    h = float(model.options.dt if dt is None else dt)
    return _step_split(model, state, control, h, _MAX_HALVINGS)


def _step_split(model: Model, state: State, control: Control, h: float, depth: int) -> State:
    try:
        return _step_once(model, state, control, h)
    except _Stalled:
        if depth == 0:
            raise SimulationDiverged(f"Newton did not converge at t = {state.t * 1e3:.1f} ms even with steps of "
                                     f"{h * 1e3:.3g} ms; lower the loads or --dt") from None
    mid = _step_split(model, state, control, 0.5 * h, depth - 1)
    return _step_split(model, mid, control, 0.5 * h, depth - 1)


def _step_once(model: Model, state: State, control: Control, h: float) -> State:
    c_a, a_known, c_v, v_known, history = _coefficients(model, state, h)
    start = evaluation(model, state, control, state.x, state.v, h, c_v)
    f_ext = forces(model, start, varying=False)
    x = _predict(state, h)
    x[model.fixed] = state.x[model.fixed]
    if model.carried is not None:
        model.carried.place(x)
    x, ev, factor, it, refactors = _newton(model, state, start, x, f_ext, c_a, a_known, v_known)
    v = c_v * x + v_known
    record = {"projected": 0, "wall_cache": None, "contact_nodes": np.zeros(0, dtype=np.int64),
              "contact_force": np.zeros(0), "sigma2": state.sigma2, "fibre_strain": state.fibre_strain}
    terms = model.terms
    for t in terms:  # positions made admissible (the wall), then each term's own state at the step's end
        x, v, done = t.constrain(model, ev, x, v)
        record.update(done)
    for t in terms:
        record.update(t.advance(model, ev, x))
    return replace(state, t=state.t + h, x=x, v=v, history=history, history_dt=h,
                   history_passed=_same_step(state, h), factor=factor, iterations=it, refactors=refactors, **record)


def _factor(model: Model, ev: Evaluation, base, c_a: float, key: tuple, terms_key: tuple, t_ms: float):
    """The Newton matrix's factor: the band (``base``, factorised here when None) and every term's rank-one
    part; returns (factor, base, whether the band was factorised)."""
    fresh_band = base is None
    try:
        if base is None:
            try:
                base = factorize(tangent(model, ev, c_a), key)
            except np.linalg.LinAlgError:
                base = factorize(tangent(model, ev, c_a, signed=False), key)
        vecs, ks = rank_one_terms(model, ev)
        factor = add_low_rank(base, np.asarray(model.layout.pattern.reduce_t @ vecs), ks, terms_key)
    except np.linalg.LinAlgError:
        raise SimulationDiverged(f"the tissue lost stability at t = {t_ms:.1f} ms (tangent not positive "
                                 "definite); lower the loads or --dt") from None
    return factor, base, fresh_band


def _newton(model: Model, state: State, start: Evaluation, x: np.ndarray, f_ext: np.ndarray, c_a: float,
            a_known: np.ndarray, v_known: np.ndarray):
    """Modified Newton on the step's residual from the guess ``x``: (x, last iterate, factor, iterations,
    factorisations so far)."""
    opt, pattern = model.options, model.layout.pattern
    key = (c_a, start.c_v)
    refactors = state.refactors
    # the last step's matrix serves again only if that step converged within two iterations: in motion a
    # matrix 5 ms old contracts at theta ~ 1 and costs an iteration before the refactor anyway
    reuse = state.factor is not None and state.factor.key == key and state.iterations <= _REUSE_AFTER
    base = state.factor.base if reuse else None
    factor = state.factor if base is not None else None  # rank-one part too, while the active sets hold
    prev, fresh, last, halved = None, False, None, False  # last: (update, residual norm before it)
    for it in range(1, opt.max_iter + 1):
        ev = Evaluation(x=x, v=start.c_v * x + v_known, h=start.h, c_v=start.c_v, state=state,
                        control=start.control, step=start.step)
        f = forces(model, ev)
        terms_key = active_key(model, ev)
        if factor is not None and terms_key != factor.terms_key:
            factor = None  # an active set changed: keep the band, redo the small Woodbury part
        resid = pattern.reduce_t @ (model.mass @ (c_a * x + a_known) - f - f_ext).ravel()
        norm = float(np.linalg.norm(resid))
        if last is not None and norm > last[1] and not halved:
            # the update raised the residual (the tangent leaves out the bricks' indefinite second derivatives):
            # go back to half of it, once
            x = x + 0.5 * last[0]
            halved = True
            continue
        halved = False
        if factor is None:
            factor, base, band = _factor(model, ev, base, c_a, key, terms_key, state.t * 1e3)
            refactors += band
            fresh = True
        dx = factor.solve(resid)
        size = float(np.abs(dx).max()) if dx.size else 0.0
        if not np.isfinite(size):
            raise SimulationDiverged(f"simulation diverged at t = {state.t * 1e3:.1f} ms; try a smaller --dt")
        if size > _MAX_INCREMENT:  # damp wild iterates (stale factor, sudden loads)
            dx *= _MAX_INCREMENT / size
            if not fresh:
                factor = base = None
        last = ((pattern.reduce @ dx).reshape(-1, 3), norm)
        x -= last[0]
        # stop when the error left after this update is below tol: the increment itself, or, with a
        # contraction rate theta < 1 measured, the geometric tail theta / (1 - theta) * size (Hairer &
        # Wanner's stopping rule for simplified Newton)
        theta = size / prev if prev else None
        if size < opt.tol or (theta is not None and theta < 1.0 and theta / (1.0 - theta) * size < opt.tol):
            return x, ev, factor, it, refactors
        if prev is not None and size > opt.refactor_rate * prev and not fresh:
            factor = base = None
        fresh = False
        prev = size
    raise _Stalled()
