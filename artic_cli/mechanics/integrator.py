"""One implicit step: ``step(model, state, control, dt) -> state``.

Time discretisation is Houbolt's (the paper's; Bathe 1996), or backward
Euler (``bdf1``) for comparison.  Both write acceleration and velocity as
linear functions of the new positions, a = c_a x + a*, v = c_v x + v*, so the
step is the nonlinear system

    R(x) = M a(x) - F_int(x, v(x)) - F_ext = 0

with geometric nonlinearity (cylinders rotate and stretch).  It is solved by
modified Newton: the banded Cholesky factor of
J = c_a M + c_v C + K_t (positive semidefinite parts only) is kept across
iterations and steps and rebuilt only when an iteration contracts the
increment by less than ``refactor_rate`` or the step size changes.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import ArticError
from . import elements
from .assembly import factorize, pair_blocks
from .model import Control, Model, State
from .volume import volume_forces

_EYE = np.eye(3)
_MAX_INCREMENT = 0.2  # cm: the largest node move one Newton iteration may make


class SimulationDiverged(ArticError):
    pass


def internal_forces(model: Model, x: np.ndarray, v: np.ndarray | None = None,
                    frame: elements.DampingFrame | None = None):
    """Forces on the nodes from cylinders and the volume constraint (dyn)."""
    cs = elements.evaluate(model.cyl, x)
    f = model.scatter @ elements.axial_forces(model.cyl, cs, frame, v)
    grad = vol = None
    if model.volume_constraint:
        fv, vol, grad = volume_forces(x, model.bricks, model.brick_v0, model.kappa)
        f += fv
    return f, cs, vol, grad


def tangent_band(model: Model, cs: elements.CylinderState, frame: elements.DampingFrame, grad,
                 c_a: float, c_v: float) -> np.ndarray:
    k_geo = np.maximum(cs.elastic, 0.0) / cs.length
    k_nn = np.maximum(elements.axial_stiffness(model.cyl, cs), 0.0) - k_geo
    k3 = (k_nn[:, None, None] * (cs.n[:, :, None] * cs.n[:, None, :]) + k_geo[:, None, None] * _EYE
          + (c_v * frame.c)[:, None, None] * (frame.n[:, :, None] * frame.n[:, None, :]))
    ab = c_a * model.mass_band + model.pattern.assemble(model.cyl_index, pair_blocks(k3))
    if grad is not None:
        g = grad.reshape(len(model.brick_v0), 24)
        w = model.kappa / model.brick_v0
        ab += model.pattern.assemble(model.brick_index, w[:, None, None] * g[:, :, None] * g[:, None, :])
    return ab


def _coefficients(model: Model, state: State, h: float):
    x0, v0 = state.x, state.v
    if model.options.scheme == "bdf1":
        return 1.0 / h**2, -x0 / h**2 - v0 / h, 1.0 / h, -x0 / h, (x0,)
    if len(state.history) >= 2 and np.isclose(state.history_dt, h):
        x1, x2 = state.history[:2]
    else:  # start (or change of step): history consistent with the current velocity
        x1, x2 = x0 - h * v0, x0 - 2.0 * h * v0
    a_known = (-5.0 * x0 + 4.0 * x1 - x2) / h**2
    v_known = (-18.0 * x0 + 9.0 * x1 - 2.0 * x2) / (6.0 * h)
    return 2.0 / h**2, a_known, 11.0 / (6.0 * h), v_known, (x0, x1)


def _predict(state: State, h: float) -> np.ndarray:
    """Starting guess: quadratic extrapolation of the last three positions."""
    if len(state.history) >= 2 and np.isclose(state.history_dt, h):
        x1, x2 = state.history[:2]
        return 3.0 * state.x - 3.0 * x1 + x2
    return state.x + h * state.v


def step(model: Model, state: State, control: Control, dt: float | None = None) -> State:
    h = float(model.options.dt if dt is None else dt)
    opt = model.options
    c_a, a_known, c_v, v_known, history = _coefficients(model, state, h)
    f_ext = control.force + model.node_mass[:, None] * model.gravity
    free = model.pattern.free_dofs
    x = _predict(state, h)
    x[model.fixed] = state.x[model.fixed]
    factor = state.factor if state.factor is not None and state.factor.key == (c_a, c_v) else None
    refactors = state.refactors
    frame = elements.damping_frame(model.cyl, state.x)
    prev = None
    fresh = False
    for it in range(1, opt.max_iter + 1):
        a = c_a * x + a_known
        v = c_v * x + v_known
        f_int, cs, _, grad = internal_forces(model, x, v, frame)
        resid = (model.mass @ a - f_int - f_ext).ravel()[free]
        if factor is None:
            try:
                factor = factorize(tangent_band(model, cs, frame, grad, c_a, c_v), (c_a, c_v))
            except np.linalg.LinAlgError:
                raise SimulationDiverged(f"the tissue lost stability at t = {state.t * 1e3:.1f} ms (tangent not "
                                         "positive definite); lower the loads or --dt") from None
            refactors += 1
            fresh = True
        dx = factor.solve(resid)
        size = float(np.abs(dx).max()) if dx.size else 0.0
        if size > _MAX_INCREMENT:  # damp wild iterates (stale factor, sudden loads)
            dx *= _MAX_INCREMENT / size
            factor = None if not fresh else factor
        x.reshape(-1)[free] -= dx

        if not np.isfinite(size):
            raise SimulationDiverged(f"simulation diverged at t = {state.t * 1e3:.1f} ms; try a smaller --dt")
        if size < opt.tol:
            break
        if prev is not None and size > opt.refactor_rate * prev and not fresh:
            factor = None
        fresh = False
        prev = size
    else:
        raise SimulationDiverged(
            f"Newton did not converge at t = {state.t * 1e3:.1f} ms in {opt.max_iter} iterations; try a smaller --dt")
    v_new = c_v * x + v_known
    return replace(state, t=state.t + h, x=x, v=v_new, history=history, history_dt=h, factor=factor,
                   iterations=it, refactors=refactors)
