"""Running the integrator over time: trajectories and equilibria."""

from __future__ import annotations

import gc
import time
from contextlib import contextmanager
from copy import deepcopy
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from threadpoolctl import threadpool_limits

from ..geometry.hexahedra import corner_jacobians, volumes
from .elements import strain_energy
from .integrator import SimulationDiverged, step
from .muscles import total_muscle_force
from .model import Control, Model, State, rest_state, with_options, zero_control
from .muscles import muscle_lengths, muscle_tensions
from .volume import volume_energy


@dataclass
class Trajectory:
    time: np.ndarray  # (T,) s
    x: np.ndarray  # (T,N,3) cm
    v: np.ndarray  # (T,N,3) cm/s
    volume: np.ndarray  # (T,) cm^3
    iterations: np.ndarray  # (T,) Newton iterations of the step ending there
    energy: np.ndarray  # (T,) kinetic + stored elastic, erg
    work: np.ndarray  # (T,) work done by external loads and gravity since t0, erg
    inverted: np.ndarray  # (T,) number of bricks turned inside out
    stats: dict = field(default_factory=dict)
    muscle_force: np.ndarray | None = None  # (T,M) dyn
    muscle_length: np.ndarray | None = None  # (T,M) cm
    contact_count: np.ndarray | None = None  # (T,) nodes in contact after the step
    contact_total: np.ndarray | None = None  # (T,) total contact force, dyn
    contact_nodes: list = field(default_factory=list)  # per frame: node ids
    contact_forces: list = field(default_factory=list)  # per frame: dyn
    projected: np.ndarray | None = None  # (T,) nodes projected back onto the wall
    snapshots: dict = field(default_factory=dict)  # step number -> the state after it (``run``'s snapshots_every)

    @property
    def volume_change(self) -> np.ndarray:
        return self.volume / self.volume[0] - 1.0


def mechanical_energy(model: Model, x: np.ndarray, v: np.ndarray) -> np.ndarray | float:
    """Kinetic + stored elastic energy (erg) of one state (N,3) or of frames (T,N,3)."""
    frames = np.asarray(x)
    single = frames.ndim == 2
    xs, vs = (frames[None], np.asarray(v)[None]) if single else (frames, np.asarray(v))
    t, n = xs.shape[:2]
    mv = (model.mass @ vs.transpose(1, 0, 2).reshape(n, -1)).reshape(n, t, 3).transpose(1, 0, 2)
    kinetic = 0.5 * (vs * mv).sum(axis=(1, 2))
    d = xs[:, model.springs.j] - xs[:, model.springs.i]
    strain = np.linalg.norm(d, axis=2) / model.springs.l0 - 1.0
    stored = np.array([strain_energy(model.springs, s).sum() for s in strain])
    if model.volume_constraint:
        stored = stored + np.array([volume_energy(xi, model.bricks, model.brick_v0, model.kappa) for xi in xs])
    total = kinetic + stored
    return float(total[0]) if single else total


def frame_volumes(model: Model, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tongue volume and number of inverted bricks of every frame (T,N,3)."""
    t, n = x.shape[:2]
    bricks = (model.bricks[None] + n * np.arange(t)[:, None, None]).reshape(-1, 8)
    flat = x.reshape(-1, 3)
    vol = volumes(flat, bricks).reshape(t, -1).sum(axis=1)
    bad = (corner_jacobians(flat, bricks) <= 0).any(axis=1).reshape(t, -1).sum(axis=1)
    return vol, bad


@contextmanager
def gc_paused():
    """Pause Python's cyclic garbage collector over a stepping loop.

    Steps make no reference cycles (a test checks that a run leaves nothing for the collector), so pausing
    loses nothing; a full collection pass over every live object of the process (numpy, scipy, numba)
    took about 40 ms, in one of every five 300 ms runs."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


# The systems are small (a band of ~700 x 78): BLAS threads only add wake-up latency (measured: 300 ms of
# the articulator took 1.19 s with OpenBLAS's default threads, 0.48 s with one).  Parallel work is done
# by running whole simulations side by side instead.
single_threaded = threadpool_limits.wrap(limits=1, user_api="blas")


@single_threaded
def run(model: Model, state: State, control_at: Callable[[float], Control], duration: float,
        dt: float | None = None, record_every: int = 1,
        progress: Callable[[int, int], None] | None = None,
        keep_partial: bool = False, snapshots_every: int = 0) -> tuple[Trajectory, State]:
    """Integrate for ``duration`` seconds; record every ``record_every`` steps.  A step that fails
    (:class:`SimulationDiverged`) raises, or with ``keep_partial`` ends the run there: the trajectory up to the
    last good step is returned with the failure in ``stats["failure"]``.  ``snapshots_every`` (a multiple of
    ``record_every``): keep a copy of the whole state every so many steps, the start included, to resume from
    (:mod:`.resume`)."""
    h = float(model.options.dt if dt is None else dt)
    n_steps = max(1, int(round(duration / h)))
    times, xs, vs, its = [state.t], [state.x.copy()], [state.v.copy()], [0]
    work = [0.0]
    ms = model.muscles
    m_force, m_len = [], []
    c_nodes, c_forces, proj = [state.contact_nodes], [state.contact_force], [0]

    def record_muscles(st: State, act) -> None:
        if ms is not None:
            m_force.append(muscle_tensions(ms, st.x, total_muscle_force(model, act), st.sigma2))
            m_len.append(muscle_lengths(ms, st.x))

    record_muscles(state, control_at(state.t).muscle_force if ms is not None else None)
    w = 0.0
    gravity = model.node_mass[:, None] * model.gravity
    t0, c0 = time.perf_counter(), time.process_time()
    failure, done = None, 0
    snapshots = {0: deepcopy(state)} if snapshots_every > 0 else {}
    with gc_paused():
        for k in range(1, n_steps + 1):
            ctl = control_at(state.t + 0.5 * h)  # inputs held over the step, sampled at its middle
            try:
                new = step(model, state, ctl, h)
            except SimulationDiverged as err:
                if not keep_partial:
                    raise
                failure = str(err)
                break
            done = k
            if snapshots_every > 0 and k % snapshots_every == 0:
                snapshots[k] = deepcopy(new)
            # work of the external forces (held over the step) and gravity
            w += float(np.einsum("ij,ij->", ctl.node_force + gravity, new.x - state.x))
            state = new
            if k % record_every == 0 or k == n_steps:
                times.append(state.t)
                xs.append(state.x.copy())
                vs.append(state.v.copy())
                its.append(state.iterations)
                work.append(w)
                record_muscles(state, ctl.muscle_force)
                c_nodes.append(state.contact_nodes)
                c_forces.append(state.contact_force)
                proj.append(state.projected)
            if progress is not None:
                progress(k, n_steps)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    x = np.array(xs)
    v = np.array(vs)
    vol, inv = frame_volumes(model, x)
    energy = mechanical_energy(model, x, v)
    traj = Trajectory(time=np.array(times), x=x, v=v, volume=vol, iterations=np.array(its),
                      energy=energy - energy[0], work=np.array(work), inverted=inv,
                      stats={"steps": done, "dt": h, "wall_time_s": wall, "cpu_time_s": cpu,
                             "refactors": state.refactors,
                             "newton_iterations": int(np.sum(its)),
                             "diagnostics_time_s": time.perf_counter() - t0 - wall, "failure": failure},
                      contact_count=np.array([len(c) for c in c_nodes]),
                      contact_total=np.array([float(np.sum(c)) for c in c_forces]),
                      contact_nodes=c_nodes, contact_forces=c_forces, projected=np.array(proj), snapshots=snapshots)
    if ms is not None:
        traj.muscle_force = np.array(m_force)
        traj.muscle_length = np.array(m_len)
    return traj, state


@single_threaded
def equilibrate(model: Model, state: State, control: Control, dt: float = 0.01, tol: float = 1e-3,
                max_time: float = 5.0) -> tuple[State, bool]:
    """Step under constant ``control`` until every speed is below ``tol`` cm/s.

    Newton is tightened to 1e-7 cm here so that its own residual motion
    (tolerance / dt) stays far below ``tol``."""
    model = with_options(model, tol=min(model.options.tol, 1e-7))
    n = int(np.ceil(max_time / dt))
    with gc_paused():
        for _ in range(n):
            state = step(model, state, control, dt)
            if np.abs(state.v).max() < tol:
                return state, True
    return state, False


def settle(model: Model, max_time: float = 5.0) -> State:
    """The rest posture: equilibrium under gravity with every muscle at zero force (t = 0)."""
    state, _ = equilibrate(model, rest_state(model), zero_control(model), dt=0.01, tol=1e-2, max_time=max_time)
    return State(t=0.0, x=state.x, v=np.zeros_like(state.v), sigma2=state.sigma2, fibre_strain=state.fibre_strain)


@dataclass
class Hold:
    """The end of holding a constant control: the state, how far the watched nodes moved over the last
    window (cm) and when it stopped (s after the start)."""

    state: State
    drift: float
    stopped: float


@single_threaded
def hold(model: Model, state: State, control: Control, duration: float, watch: np.ndarray, window: float,
         stop_below: float | None = None, dt: float | None = None) -> Hold:
    """Step under a constant ``control`` for ``duration`` s, or (``stop_below``) until the ``watch`` nodes
    have moved less than ``stop_below`` cm over the last ``window`` s."""
    h = float(model.options.dt if dt is None else dt)
    n_steps = max(1, int(round(duration / h)))
    lag = max(1, int(round(window / h)))
    t0 = state.t
    past = [state.x[watch].copy()]
    drift = np.inf
    with gc_paused():
        for k in range(1, n_steps + 1):
            state = step(model, state, control, h)
            past.append(state.x[watch].copy())
            if len(past) > lag + 1:
                past.pop(0)
            if k >= lag:
                drift = float(np.linalg.norm(past[-1] - past[0], axis=1).max())
                if stop_below is not None and drift < stop_below:
                    break
    return Hold(state=state, drift=drift, stopped=state.t - t0)


VOLUME_LIMIT = 0.01  # a run with the volume constraint on that changes the tongue's volume more than this is not physical


def problems(traj: Trajectory, volume_constraint: bool) -> list[str]:
    """Why a trajectory is not physical (empty when it is): NaN, inverted bricks, a failed step, or (with the
    volume constraint on) a volume change above 1 %."""
    out = []
    if traj.stats.get("failure"):
        out.append(traj.stats["failure"])
    if not np.isfinite(traj.x).all():
        out.append("positions are not finite (NaN)")
    if int(traj.inverted.max()) > 0:
        k = int(np.argmax(traj.inverted > 0))
        out.append(f"{int(traj.inverted.max())} inverted bricks (first at {traj.time[k] * 1e3:.0f} ms)")
    vol = float(np.nanmax(np.abs(traj.volume_change)))
    if volume_constraint and not vol <= VOLUME_LIMIT:
        out.append(f"tongue volume changed by {100 * vol:.2f} % (limit {100 * VOLUME_LIMIT:g} %)")
    return out
