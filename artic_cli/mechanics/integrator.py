"""One implicit step: ``step(model, state, control, dt) -> state``.

Time discretisation is Houbolt's (the paper's; Bathe 1996), or backward
Euler (``bdf1``) for comparison.  Both write acceleration and velocity as
linear functions of the new positions, a = c_a x + a*, v = c_v x + v*, so the
step is the nonlinear system

    R(x) = M a(x) - F_int(x, v(x)) - F_muscle(x) - F_guide(x) - F_contact(x) - F_ext = 0

with geometric nonlinearity (cylinders and fibres rotate and stretch).  It is
solved by modified Newton: the Cholesky factor of
J = c_a M + c_v C + K_t (positive semidefinite parts only) is kept across
iterations and steps and rebuilt only when an iteration contracts the
increment by less than ``refactor_rate``, the step size changes, or the set
of wall contacts changes.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import ArticError
from . import elements
from .assembly import factorize, pair_blocks
from .contact import ContactPlanes, contact_planes, enforce
from .model import Control, Model, State
from .muscles import FibreState, fibre_state, muscle_forces
from .volume import volume_forces

_EYE = np.eye(3)
_MAX_INCREMENT = 0.2  # cm: the largest node move one Newton iteration may make


class SimulationDiverged(ArticError):
    pass


def internal_forces(model: Model, x: np.ndarray, v: np.ndarray | None = None,
                    frame: elements.DampingFrame | None = None):
    """Forces on the nodes from cylinders, links and the volume constraint (dyn)."""
    cs = elements.evaluate(model.cyl, x)
    f = model.scatter @ elements.axial_forces(model.cyl, cs, frame, v)
    grad = vol = None
    if model.volume_constraint:
        fv, vol, grad = volume_forces(x[: model.n_tongue], model.bricks, model.brick_v0, model.kappa)
        f[: model.n_tongue] += fv
    return f, cs, vol, grad


def guide_forces(model: Model, x: np.ndarray) -> np.ndarray:
    f = np.zeros_like(x)
    gd = model.guide
    if gd is not None:
        d = x[gd.nodes] - gd.origin
        off = np.einsum("gi,gmi->gm", d, gd.normals)
        f[gd.nodes] = -gd.stiffness * np.einsum("gm,gmi->gi", off, gd.normals)
    return f


def contact_forces(model: Model, x: np.ndarray, planes: ContactPlanes | None):
    """Penalty forces of the nodes beyond their step's wall planes, and which are active."""
    f = np.zeros_like(x)
    if planes is None or len(planes.nodes) == 0:
        return f, np.zeros(0, dtype=bool), np.zeros(0)
    g = planes.gaps(x)
    active = g > 0
    mag = model.contact.stiffness * np.where(active, g, 0.0)
    push = mag[:, None] * planes.n
    np.add.at(f, planes.nodes, -push)
    on_jaw = planes.jaw & active
    if on_jaw.any():  # the reaction acts on the mandible
        f[planes.jaw_nodes] += push[on_jaw].sum(axis=0) / len(planes.jaw_nodes)
    return f, active, mag


def tangent(model: Model, cs: elements.CylinderState, frame: elements.DampingFrame, grad,
            fs: FibreState | None, planes: ContactPlanes | None, active: np.ndarray, c_a: float, c_v: float):
    k_geo = np.maximum(cs.elastic, 0.0) / cs.length
    k_nn = np.maximum(elements.axial_stiffness(model.cyl, cs), 0.0) - k_geo
    k3 = (k_nn[:, None, None] * (cs.n[:, :, None] * cs.n[:, None, :]) + k_geo[:, None, None] * _EYE
          + (c_v * frame.c)[:, None, None] * (frame.n[:, :, None] * frame.n[:, None, :]))
    idx = [model.cyl_index]
    val = [pair_blocks(k3)]
    if grad is not None:
        g = grad.reshape(len(model.brick_v0), 24)
        w = model.kappa / model.brick_v0
        idx.append(model.brick_index)
        val.append(w[:, None, None] * g[:, :, None] * g[:, None, :])
    if fs is not None:
        t = np.maximum(fs.tension[model.muscles.seg_fibre], 0.0) / fs.seg_length
        kk = t[:, None, None] * (_EYE - fs.n[:, :, None] * fs.n[:, None, :])
        idx.append(model.seg_index)
        val.append(pair_blocks(kk))
    if model.guide is not None:
        gd = model.guide
        idx.append(gd.index)
        val.append(gd.stiffness * np.einsum("gmi,gmj->gij", gd.normals, gd.normals))
    if planes is not None and active.any():
        k = model.contact.stiffness
        wall_side = active & ~planes.jaw
        if wall_side.any():
            pos = np.searchsorted(model.contact.nodes, planes.nodes[wall_side])
            n = planes.n[wall_side]
            idx.append(model.contact_index[pos])
            val.append(k * n[:, :, None] * n[:, None, :])
        jaw_side = active & planes.jaw
        if jaw_side.any():
            jn = planes.jaw_nodes
            nodes = np.column_stack([planes.nodes[jaw_side], np.broadcast_to(jn, (jaw_side.sum(), len(jn)))])
            n = planes.n[jaw_side]
            vec = np.concatenate([n[:, None, :], np.repeat(-n[:, None, :] / len(jn), len(jn), axis=1)], axis=1)
            vec = vec.reshape(len(n), -1)
            idx.append(model.pattern.block_index(nodes))
            val.append(k * vec[:, :, None] * vec[:, None, :])
    flat_i = np.concatenate([i.ravel() for i in idx])
    flat_v = np.concatenate([v.ravel() for v in val])
    return c_a * model.mass_matrix + model.pattern.assemble(flat_i, flat_v)


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
    refactors = state.refactors
    frame = elements.damping_frame(model.cyl, state.x)
    planes = contact_planes(model.contact, state.x) if model.contact is not None else None
    ms = model.muscles
    act = control.activation if control.activation is not None else (np.zeros(len(ms.names)) if ms else None)
    key = (c_a, c_v)
    factor = state.factor if state.factor is not None and state.factor.key[:2] == key else None
    active_prev = state.factor.key[2] if state.factor is not None and len(state.factor.key) > 2 else None
    prev = None
    fresh = False
    fs = None
    for it in range(1, opt.max_iter + 1):
        a = c_a * x + a_known
        v = c_v * x + v_known
        f_int, cs, _, grad = internal_forces(model, x, v, frame)
        f = f_int + guide_forces(model, x)
        if ms is not None:
            fs = fibre_state(ms, x, act, state.sigma2, state.fibre_strain, h)
            f += muscle_forces(ms, fs)
        fc, active, _ = contact_forces(model, x, planes)
        f += fc
        active_key = None if planes is None else (tuple(planes.nodes[active]))
        if factor is not None and planes is not None and active_key != active_prev:
            factor = None
        resid = (model.mass @ a - f - f_ext).ravel()[free]
        if factor is None:
            try:
                factor = factorize(tangent(model, cs, frame, grad, fs, planes, active, c_a, c_v), (*key, active_key))
            except np.linalg.LinAlgError:
                raise SimulationDiverged(f"the tissue lost stability at t = {state.t * 1e3:.1f} ms (tangent not "
                                         "positive definite); lower the loads or --dt") from None
            refactors += 1
            fresh = True
            active_prev = active_key
        dx = factor.solve(resid)
        size = float(np.abs(dx).max()) if dx.size else 0.0
        if not np.isfinite(size):
            raise SimulationDiverged(f"simulation diverged at t = {state.t * 1e3:.1f} ms; try a smaller --dt")
        if size > _MAX_INCREMENT:  # damp wild iterates (stale factor, sudden loads)
            dx *= _MAX_INCREMENT / size
            factor = None if not fresh else factor
        x.reshape(-1)[free] -= dx
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
    projected = 0
    contact_nodes = np.zeros(0, dtype=np.int64)
    contact_force = np.zeros(0)
    if model.contact is not None:
        _, active, mag = contact_forces(model, x, planes)
        contact_nodes, contact_force = planes.nodes[active], mag[active]
        x, v_new, projected = enforce(model.contact, x, v_new)
    sigma2, strain = state.sigma2, state.fibre_strain
    if ms is not None:
        fs = fibre_state(ms, x, act, state.sigma2, state.fibre_strain, h)
        sigma2, strain = fs.sigma2, fs.strain
    return replace(state, t=state.t + h, x=x, v=v_new, history=history, history_dt=h, factor=factor,
                   iterations=it, refactors=refactors, sigma2=sigma2, fibre_strain=strain,
                   contact_nodes=contact_nodes, contact_force=contact_force, projected=projected)
