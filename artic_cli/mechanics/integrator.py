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
from ..jit import compiled
from .assembly import add_low_rank, factorize
from .contact import ContactPlanes, contact_planes, enforce
from .elements import cylinder_blocks
from .model import Control, Model, State
from .penalty import ramp
from .muscles import FibreState, fibre_state, fibre_stiffness, length_gradients, muscle_forces, segment_blocks
from ..geometry.hexahedra import SHAPE_GRADIENTS_CORNER, SHAPE_GRADIENTS_GAUSS
from .volume import GUARD_FRACTION, brick_blocks, brick_terms, corner_guard, volume_forces

_EYE = np.eye(3)
_MAX_INCREMENT = 0.2  # cm: the largest node move one Newton iteration may make
# Fibres stiffer than this along their length (dyn/cm; active muscles on the steep side of Eq. 9) enter the
# tangent exactly, as rank-one terms k g g^T solved by Woodbury; softer ones are split over their segments.
_RANK_ONE_STIFFNESS = 2.0e4


class SimulationDiverged(ArticError):
    pass


def internal_forces(model: Model, x: np.ndarray, v: np.ndarray | None = None,
                    frame: elements.DampingFrame | None = None):
    """Forces on the nodes from cylinders, links and the volume constraint (dyn)."""
    cs = elements.evaluate(model.springs, x)
    f = elements.nodal_forces(model.springs, cs, frame, v, model.scatter)
    grad = vol = None
    nt = model.n_tongue
    if compiled() and model.corner_j0 is not None:
        kappa = model.kappa if model.volume_constraint else np.zeros_like(model.kappa)
        fb, vol, grad, pairs, g, w = brick_terms(
            np.ascontiguousarray(x[:nt]), model.bricks, SHAPE_GRADIENTS_GAUSS, SHAPE_GRADIENTS_CORNER, model.brick_v0, kappa,
            model.corner_j0, model.guard_weight, GUARD_FRACTION)
        f[:nt] += fb
        guard = (pairs[:, 0], pairs[:, 1], g, w) if len(pairs) else None
        if not model.volume_constraint:
            vol = grad = None
        return f, cs, vol, grad, guard
    if model.volume_constraint:
        fv, vol, grad = volume_forces(x[:nt], model.bricks, model.brick_v0, model.kappa)
        f[:nt] += fv
    guard = None
    if model.corner_j0 is not None:
        fg, guard = corner_guard(x[:nt], model.bricks, model.corner_j0, model.guard_weight)
        f[:nt] += fg
    return f, cs, vol, grad, guard


def _fibre_stiffness(model: Model, fs: FibreState, act: np.ndarray, h: float) -> np.ndarray:
    """(F,) the fibres' stiffness along their length (:func:`.muscles.fibre_stiffness`); a mirrored model's
    twins get their mean, so that both fall on the same side of the rank-one threshold."""
    kf = fibre_stiffness(model.muscles, fs, act, h)
    return kf if model.fibre_twin is None else 0.5 * (kf + kf[model.fibre_twin])


def guide_forces(model: Model, x: np.ndarray, stop: np.ndarray | None = None) -> np.ndarray:
    """The condyle guide's forces (dyn); ``stop``: which guided nodes press on their back stop
    (:func:`guide_stop`, computed when not given)."""
    f = np.zeros_like(x)
    gd = model.guide
    if gd is not None:
        d = x[gd.nodes] - gd.origin
        off = (d[:, None, :] * gd.normals).sum(axis=2)  # (G,2)
        fg = -gd.stiffness * (off[:, :, None] * gd.normals).sum(axis=1)
        stop = guide_stop(gd, x) if stop is None else stop
        if stop.any():
            push, _ = ramp(-(d * gd.path).sum(axis=1), gd.onset)
            fg += gd.stiffness * push[:, None] * gd.path
        f[gd.nodes] = fg
    return f


def total_muscle_force(model: Model, muscle_force: np.ndarray | None) -> np.ndarray | None:
    """The control's muscle forces plus the model's postural tone (dyn), or None without muscles."""
    if model.muscles is None:
        return None
    act = np.zeros(len(model.muscles.names)) if muscle_force is None else muscle_force
    return act + model.tone if model.tone is not None else act


def guide_stop(gd, x: np.ndarray) -> np.ndarray:
    """(G,) which guided nodes press on the back stop of their line."""
    if gd is None or gd.path is None:
        return np.zeros(0 if gd is None else len(gd.nodes), dtype=bool)
    return ((x[gd.nodes] - gd.origin) * gd.path).sum(axis=1) < 0.0


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
            fs: FibreState | None, act: np.ndarray | None, h: float, c_a: float, c_v: float,
            signed_geometry: bool = True, kf: np.ndarray | None = None):
    """The banded part of the Newton matrix: mass, cylinders and links, volume, fibres' own blocks, guide
    (``kf``: the fibres' stiffness, :func:`_fibre_stiffness`, computed when not given)."""
    # geometric stiffness T / l with its sign: compressed cylinders soften sideways (the mass term keeps
    # the matrix positive definite at these loads; a failed factorisation falls back to clipping)
    cyl, asm = model.springs, model.assembly
    axial = elements.axial_stiffness(cyl, cs)
    nb = len(model.brick_v0)
    grad = np.zeros((0, 8, 3)) if grad is None else grad.reshape(nb, 8, 3)
    w = model.kappa / model.brick_v0
    ms = model.muscles
    if fs is not None:
        t = np.maximum(fs.tension[ms.seg_fibre], 0.0) / fs.seg_length
        nn = fs.n[:, :, None] * fs.n[:, None, :]
        kf = _fibre_stiffness(model, fs, act, h) if kf is None else kf
        soft = np.where(kf < _RANK_ONE_STIFFNESS, kf * ms.fibre_l0, 0.0)  # split in series
        k_seg = t[:, None, None] * (_EYE - nn) + (soft[ms.seg_fibre] / ms.seg_l0)[:, None, None] * nn
        seg, seg_pair = (ms.seg_i, ms.seg_j), asm.seg_pair
    else:  # no fibres (or none evaluated): no segment blocks
        k_seg = np.zeros((0, 3, 3))
        seg_pair = np.zeros(0, dtype=np.int64)
        seg = (seg_pair, seg_pair)
    if compiled():
        blocks = np.zeros((asm.n_pairs + model.n_nodes, 3, 3))
        cylinder_blocks(blocks, cs.n, cs.length, cs.elastic, axial, frame.n, frame.c, c_v, signed_geometry, cyl.i,
                        cyl.j, asm.cyl_pair, asm.n_pairs)
        brick_blocks(blocks, model.bricks, asm.brick_pair, grad, w, asm.n_pairs)
        segment_blocks(blocks, seg[0], seg[1], seg_pair, k_seg, asm.n_pairs)
    else:
        k_geo = (cs.elastic if signed_geometry else np.maximum(cs.elastic, 0.0)) / cs.length
        k_nn = np.maximum(axial, 0.0) - k_geo
        k3 = (k_nn[:, None, None] * (cs.n[:, :, None] * cs.n[:, None, :]) + k_geo[:, None, None] * _EYE
              + (c_v * frame.c)[:, None, None] * (frame.n[:, :, None] * frame.n[:, None, :]))
        blocks = asm.blocks(model.n_nodes, (cyl.i, cyl.j), k3, model.bricks, grad, w, seg, k_seg)
    flat = asm.operator @ blocks.ravel()
    flat += c_a * model.mass_flat
    flat += model.guide_flat
    return model.pattern.unpack(flat)


def rank_one_terms(model: Model, x: np.ndarray, fs: FibreState | None, act: np.ndarray | None, h: float,
                   planes: ContactPlanes | None, active: np.ndarray, guard=None, stop: np.ndarray | None = None,
                   kf: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Newton terms k v v^T that change often or do not fit the band: (V (3N, r), k (r,)).

    Stiff fibres (along their whole length), active wall contacts (with the reaction on the mandible)
    and condyles on the fossa stop.  They update the banded factor by Woodbury, so a change of the
    contact set does not refactor the band.  In a mirrored model a fibre and its twin have one folded
    gradient: they enter as one term of twice the stiffness (fewer Woodbury columns).  ``stop``
    (:func:`guide_stop`) and ``kf`` (:func:`_fibre_stiffness`) are computed when not given.
    """
    n3 = 3 * model.n_nodes
    cols, ks = [], []
    if fs is not None:
        kf = _fibre_stiffness(model, fs, act, h) if kf is None else kf
        stiff = np.flatnonzero(kf >= _RANK_ONE_STIFFNESS)
        k = kf[stiff]
        if model.fibre_twin is not None:  # twins' gradients fold onto the same column: one, twice as stiff
            twin = model.fibre_twin[stiff]
            keep = twin >= stiff
            stiff, k = stiff[keep], np.where(twin[keep] == stiff[keep], 1.0, 2.0) * k[keep]
        if len(stiff):
            cols.append(length_gradients(model.muscles, fs, stiff, model.n_nodes))
            ks.append(k)
    if planes is not None and active.any():
        nodes, n = planes.nodes[active], planes.n[active]
        v = np.zeros((model.n_nodes, 3, len(nodes)))
        v[nodes, :, np.arange(len(nodes))] = n
        on_jaw = planes.jaw[active]
        for c in np.flatnonzero(on_jaw):
            v[planes.jaw_nodes, :, c] -= n[c] / len(planes.jaw_nodes)
        cols.append(v.reshape(n3, -1))
        ks.append(np.full(len(nodes), model.contact.stiffness))
    if guard is not None:  # corners near inversion (from internal_forces)
        b, _, g, w = guard
        v = np.zeros((model.n_nodes, 3, len(b)))
        np.add.at(v, (model.bricks[b], slice(None), np.arange(len(b))[:, None]), g)
        cols.append(v.reshape(n3, -1))
        ks.append(w)
    stop = guide_stop(model.guide, x) if stop is None else stop
    if stop.any():
        gd = model.guide
        v = np.zeros((model.n_nodes, 3, int(stop.sum())))
        v[gd.nodes[stop], :, np.arange(int(stop.sum()))] = gd.path[stop]
        cols.append(v.reshape(n3, -1))
        _, slope = ramp(-((x[gd.nodes[stop]] - gd.origin[stop]) * gd.path[stop]).sum(axis=1), gd.onset)
        ks.append(gd.stiffness * slope)
    if not cols:
        return np.zeros((n3, 0)), np.zeros(0)
    return np.hstack(cols), np.concatenate(ks)


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


_REUSE_AFTER = 2  # Newton iterations of the last step up to which its matrix is reused
_MAX_HALVINGS = 4  # a step whose Newton stalls is retried as two half steps, down to dt / 16


class _Stalled(Exception):
    pass


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
    opt = model.options
    c_a, a_known, c_v, v_known, history = _coefficients(model, state, h)
    f_ext = control.node_force + model.node_mass[:, None] * model.gravity
    reduce, reduce_t = model.pattern.reduce, model.pattern.reduce_t
    x = _predict(state, h)
    x[model.fixed] = state.x[model.fixed]
    if model.carried is not None:
        model.carried.place(x)
    refactors = state.refactors
    frame = elements.damping_frame(model.springs, state.x)
    planes = None
    if model.contact is not None:
        cached = state.wall_cache is not None and state.wall_cache[0] is state.x
        planes = contact_planes(model.contact, state.x, state.wall_cache[1] if cached else None)
    ms = model.muscles
    act = total_muscle_force(model, control.muscle_force)
    key = (c_a, c_v)
    # the last step's matrix serves again only if that step converged within two iterations: in motion a
    # matrix 5 ms old contracts at theta ~ 1 and costs an iteration before the refactor anyway
    reuse = state.factor is not None and state.factor.key == key and state.iterations <= _REUSE_AFTER
    base = state.factor.base if reuse else None
    factor = state.factor if base is not None else None  # rank-one part too, while the contact set holds
    prev = None
    fresh = False
    fs = None
    last = None  # (update, residual norm before it) of the last Newton update
    halved = False
    for it in range(1, opt.max_iter + 1):
        a = c_a * x + a_known
        v = c_v * x + v_known
        f_int, cs, _, grad, guard = internal_forces(model, x, v, frame)
        stop = guide_stop(model.guide, x)
        f = f_int + guide_forces(model, x, stop)
        if ms is not None:
            fs = fibre_state(ms, x, act, state.sigma2, state.fibre_strain, h)
            f += muscle_forces(ms, fs)
        fc, active, _ = contact_forces(model, x, planes)
        f += fc
        active_key = (None if planes is None else tuple(planes.nodes[active]), tuple(stop),
                      () if guard is None else tuple(zip(guard[0].tolist(), guard[1].tolist())))
        if factor is not None and active_key != factor.terms_key:
            factor = None  # contact set changed: keep the band, redo the small Woodbury part
        resid = reduce_t @ (model.mass @ a - f - f_ext).ravel()
        norm = float(np.linalg.norm(resid))
        if last is not None and norm > last[1] and not halved:
            # the update raised the residual (the tangent leaves out the bricks' indefinite second derivatives):
            # go back to half of it, once
            x = x + 0.5 * last[0]
            halved = True
            continue
        halved = False
        if factor is None:
            try:
                kf = None if fs is None else _fibre_stiffness(model, fs, act, h)
                if base is None:
                    try:
                        base = factorize(tangent(model, cs, frame, grad, fs, act, h, c_a, c_v, kf=kf), key)
                    except np.linalg.LinAlgError:
                        base = factorize(tangent(model, cs, frame, grad, fs, act, h, c_a, c_v, False, kf), key)
                    refactors += 1
                vecs, ks = rank_one_terms(model, x, fs, act, h, planes, active, guard, stop, kf)
                factor = add_low_rank(base, np.asarray(reduce_t @ vecs), ks, active_key)
            except np.linalg.LinAlgError:
                raise SimulationDiverged(f"the tissue lost stability at t = {state.t * 1e3:.1f} ms (tangent not "
                                         "positive definite); lower the loads or --dt") from None
            fresh = True
        dx = factor.solve(resid)
        size = float(np.abs(dx).max()) if dx.size else 0.0
        if not np.isfinite(size):
            raise SimulationDiverged(f"simulation diverged at t = {state.t * 1e3:.1f} ms; try a smaller --dt")
        if size > _MAX_INCREMENT:  # damp wild iterates (stale factor, sudden loads)
            dx *= _MAX_INCREMENT / size
            if not fresh:
                factor = base = None
        last = ((reduce @ dx).reshape(-1, 3), norm)
        x -= last[0]
        # stop when the error left after this update is below tol: the increment itself, or, with a
        # contraction rate theta < 1 measured, the geometric tail theta / (1 - theta) * size (Hairer &
        # Wanner's stopping rule for simplified Newton)
        theta = size / prev if prev else None
        if size < opt.tol or (theta is not None and theta < 1.0 and theta / (1.0 - theta) * size < opt.tol):
            break
        if prev is not None and size > opt.refactor_rate * prev and not fresh:
            factor = base = None
        fresh = False
        prev = size
    else:
        raise _Stalled()
    v_new = c_v * x + v_known
    projected = 0
    wall_cache = None
    contact_nodes = np.zeros(0, dtype=np.int64)
    contact_force = np.zeros(0)
    if model.contact is not None:
        _, active, mag = contact_forces(model, x, planes)
        contact_nodes, contact_force = planes.nodes[active], mag[active]
        x, v_new, projected, query = enforce(model.contact, x, v_new)
        # a mirrored node has no dofs: a projection of its own (the wall's triangles are not mirror images) would
        # stay with it for good
        model.mirror(x)
        model.mirror(v_new)
        if query is not None:
            wall_cache = (x, query)
    sigma2, strain = state.sigma2, state.fibre_strain
    if ms is not None:
        fs = fibre_state(ms, x, act, state.sigma2, state.fibre_strain, h)
        sigma2, strain = fs.sigma2, fs.strain
    return replace(state, t=state.t + h, x=x, v=v_new, history=history, history_dt=h,
                   history_passed=_same_step(state, h), factor=factor,
                   iterations=it, refactors=refactors, sigma2=sigma2, fibre_strain=strain,
                   contact_nodes=contact_nodes, contact_force=contact_force, projected=projected,
                   wall_cache=wall_cache)
