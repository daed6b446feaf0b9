"""One equilibrium position (EP): hold a set of muscle forces from a jaw position's rest and read where the
tongue tip, the dorsum and the jaw come to rest (the paper's section IV.B), and the whole shape.

Pure physics over a model: no maps, no files.  The worker functions at the bottom build the model once per
process (they travel to loky or dask workers) and are what the EP-map sweep caches.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from .. import units
from ..config import ConfigView, EPMapSpec, parse_config
from ..errors import ArticError
from ..geometry.mesh import Mesh
from ..geometry.wall import WallSurface
from ..mechanics.jaw_hold import fresh_start, hold_jaw
from ..mechanics.loads import muscle_force_vector
from ..mechanics.model import ARTICULATOR_SECTIONS, Control, Model, State, build_articulator
from ..mechanics.simulate import Hold, equilibrate, hold, settle

Forces = tuple[tuple[str, float], ...]


def canonical(forces: dict[str, float]) -> Forces:
    """A hashable, order-free form of a force set; zero forces dropped."""
    return tuple(sorted((str(k), float(v)) for k, v in forces.items() if float(v) > 0.0))


def add_forces(*parts: dict[str, float]) -> dict[str, float]:
    out: dict[str, float] = {}
    for p in parts:
        for k, v in p.items():
            out[k] = out.get(k, 0.0) + v
    return out


@dataclass
class EP:
    x: np.ndarray  # (3, 3): tip, dorsum, jaw (cm)
    drift_cm: float  # largest control-point move over the last window
    converged: bool
    stopped_ms: float



def control_for(model: Model, forces_n: dict[str, float]) -> Control:
    return Control(node_force=np.zeros((model.n_nodes, 3)), muscle_force=muscle_force_vector(model, forces_n))


def watch_nodes(model: Model) -> np.ndarray:
    return np.array(list(model.control_points().values()))


def jaw_rest(model: Model, jaw_forces: dict[str, float]) -> State:
    """The rest posture of a jaw position: equilibrium with the jaw forces held (t = 0)."""
    rest = settle(model)
    if not canonical(jaw_forces):
        return rest
    state, _ = equilibrate(model, rest, control_for(model, jaw_forces), dt=0.01, tol=1e-2)
    return State(t=0.0, x=state.x, v=np.zeros_like(state.v), sigma2=state.sigma2, fibre_strain=state.fibre_strain)


def equilibrium_state(model: Model, start: State, forces_n: dict[str, float], spec: EPMapSpec,
                      fast: bool = False) -> tuple[State, EP]:
    """Hold the forces for ``spec.duration_ms`` (``fast``: stop once settled; still moving then: up to
    ``spec.extend_ms`` more, stopping once settled): the whole final state and the EP read from it."""
    if spec.hold_jaw:  # the jaw position's mandible stays where the start has it
        model, start = hold_jaw(model, start.x), fresh_start(start)
    control, watch = control_for(model, forces_n), watch_nodes(model)
    window = units.ms_to_s(spec.convergence_window_ms)
    h = hold(model, start, control, units.ms_to_s(spec.duration_ms), watch, window,
             stop_below=spec.early_stop_tol_cm if fast else None)
    if spec.extend_ms > 0 and not h.drift < spec.convergence_tol_cm:  # still moving: hold on until settled
        more = hold(model, h.state, control, units.ms_to_s(spec.extend_ms), watch, window,
                    stop_below=spec.convergence_tol_cm)
        h = Hold(state=more.state, drift=more.drift, stopped=h.stopped + more.stopped)
    return h.state, EP(x=h.state.x[watch].copy(), drift_cm=h.drift,
                       converged=bool(h.drift < spec.convergence_tol_cm), stopped_ms=units.s_to_ms(h.stopped))


def equilibrium_point(model: Model, start: State, forces_n: dict[str, float], spec: EPMapSpec,
                      fast: bool = False) -> EP:
    """Hold the forces for ``spec.duration_ms`` (``fast``: stop once settled) and read the control points."""
    return equilibrium_state(model, start, forces_n, spec, fast)[1]


# --- workers (top level: they travel to loky / dask processes) --------------------------------------

_MODELS: dict[str, Model] = {}
_RESTS: dict[tuple, State] = {}


def worker_model(key: str, cfg_json: str, mesh: Mesh, wall: WallSurface) -> Model:
    """The articulator for ``key`` (the hash of its config sections, mesh content and code), built once per
    process."""
    if key not in _MODELS:
        cfg = ConfigView(parse_config(json.loads(cfg_json), "<worker config>"), ARTICULATOR_SECTIONS)
        _MODELS.clear()
        _MODELS[key] = build_articulator(cfg, mesh, wall)
    return _MODELS[key]


def worker_rest(key: str, jaw_forces: Forces, cfg_json: str, mesh: Mesh, wall: WallSurface) -> State:
    if (key, jaw_forces) not in _RESTS:
        _RESTS[(key, jaw_forces)] = jaw_rest(worker_model(key, cfg_json, mesh, wall), dict(jaw_forces))
    return _RESTS[(key, jaw_forces)]


def compute_ep(key: str, jaw_forces: Forces, forces: Forces, spec_json: str, fast: bool, cfg_json: str,
               mesh: Mesh, wall: WallSurface) -> dict:
    """One EP as plain arrays (cached on everything but the last three arguments: ``key`` stands for them)."""
    model = worker_model(key, cfg_json, mesh, wall)
    spec = EPMapSpec.model_validate(json.loads(spec_json))
    start = worker_rest(key, jaw_forces, cfg_json, mesh, wall)
    state, ep = equilibrium_state(model, start, add_forces(dict(jaw_forces), dict(forces)), spec, fast)
    return {"x": ep.x, "drift_cm": ep.drift_cm, "converged": ep.converged, "stopped_ms": ep.stopped_ms,
            "shape": state.x.astype(np.float32)}


def compute_rest(key: str, jaw_forces: Forces, cfg_json: str, mesh: Mesh, wall: WallSurface) -> dict:
    model = worker_model(key, cfg_json, mesh, wall)
    st = worker_rest(key, jaw_forces, cfg_json, mesh, wall)
    return {"x": st.x[watch_nodes(model)].copy(), "mandible": st.x[model.node_sets["mandible"]].copy(),
            "shape": st.x.astype(np.float32), "model_rest": model.rest.copy(),
            "mandible_nodes": np.asarray(model.node_sets["mandible"])}


def spec_key(spec: EPMapSpec) -> str:
    """The parts of the spec an EP depends on (not the lists of what to compute)."""
    keep = {k: getattr(spec, k) for k in ("duration_ms", "convergence_window_ms", "convergence_tol_cm",
                                          "early_stop_tol_cm")}
    if spec.hold_jaw:
        keep["hold_jaw"] = True
    if spec.extend_ms > 0:
        keep["extend_ms"] = spec.extend_ms
    return json.dumps(keep, sort_keys=True)


def parse_ep(spec: str) -> tuple[str, dict[str, float]]:
    """``JAW:MUSCLE=N[,MUSCLE=N]`` -> (jaw position, tongue forces in N)."""
    jaw, sep, rest = spec.partition(":")
    forces = {}
    try:
        for part in filter(None, rest.split(",")):
            name, eq, value = part.partition("=")
            if not eq:
                raise ValueError
            forces[name.strip()] = float(value)
    except ValueError:
        forces = None
    if not sep or not jaw or forces is None or not forces or any(not np.isfinite(v) or v < 0 for v in forces.values()):
        raise ArticError(f"--ep '{spec}' is not JAW:MUSCLE=N[,MUSCLE=N] (e.g. JO_0.5:SG=2.5) with forces >= 0 N; fix it")
    return jaw, forces


def map_ep_state(model: Model, maps, spec: str, options: EPMapSpec) -> tuple[State, dict[str, float]]:
    """The whole state of one EP of the maps (``spec`` as :func:`parse_ep`), recomputed by holding its forces
    as the map did; with the forces held (jaw and tongue, N)."""
    jaw, forces = parse_ep(spec)
    if jaw not in maps.jaws:
        raise ArticError(f"--ep: the maps have no jaw position '{jaw}'; they have {', '.join(maps.jaws)}")
    jm = maps.jaws[jaw]
    nets = [n for fam in (jm.single, jm.pair, jm.group) for n in fam.values() if set(n.muscles) == set(forces)]
    found = any(all(np.isclose(n.levels[n.muscles.index(k)], v).any() for k, v in forces.items()) for n in nets)
    if not found:
        have = ", ".join(f"{'+'.join(n.muscles)} at {'/'.join(f'{x:g}' for x in n.levels[0])} N"
                         for n in list(jm.single.values())[:4])
        raise ArticError(f"--ep '{spec}' is not an EP of the maps at {jaw} (e.g. {have}); give a muscle set and "
                         "levels the maps hold")
    start = jaw_rest(model, jm.forces)
    state, _ = equilibrium_state(model, start, add_forces(jm.forces, forces), options)
    return state, add_forces(jm.forces, forces)
