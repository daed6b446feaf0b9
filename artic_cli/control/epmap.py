"""Equilibrium-position (EP) maps: the paper's section IV.B.

An EP is where the tongue tip, the dorsum and the jaw come to rest when a set
of muscle forces is held (300 ms from the rest posture of a jaw position, the
jaw force held throughout).  A map is a family of EPs:

* single-muscle EP vectors: one muscle (or group such as T-SL) at increasing
  force levels, at every jaw position;
* two-muscle contour nets: a grid of force pairs (Fig. 8, right);
* three-muscle co-contraction groups: an independent muscle at a few
  co-contraction levels, each with a two-muscle net (section V.A).

Every EP is one task: (jaw position, muscle forces).  Tasks run in parallel
through joblib (loky on one machine, dask.distributed on a cluster) and each
result is cached on disk by ``joblib.Memory`` under a key made of the model
hash (config without the map spec, the mesh file's hash and a hash of the
physics source code) and the forces,
so an interrupted build resumes, an unchanged one does nothing, and a changed
map spec recomputes only the EPs it adds.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from .. import __version__, units
from ..config import Config, EPMapSpec, config_hash, load_config, model_hash, parse_config
from ..errors import ArticError
from ..geometry.anatomy import JAW_MUSCLES, TONGUE_MUSCLES
from ..io.store import atomic_h5, file_hash, load_mesh, open_artifact
from ..mechanics.loads import muscle_force_vector
from ..mechanics.model import Control, Model, State, build_articulator
from ..mechanics.simulate import equilibrate, hold, settle

CONTROL_POINTS = ("tip", "dorsum", "jaw")
Forces = tuple[tuple[str, float], ...]


def canonical(forces: dict[str, float]) -> Forces:
    """A hashable, order-free form of a force set; zero forces dropped."""
    return tuple(sorted((str(k), float(v)) for k, v in forces.items() if float(v) > 0.0))


@dataclass(frozen=True)
class Task:
    jaw: str
    forces: Forces  # tongue muscles (N), the jaw position's forces not included


@dataclass
class EP:
    x: np.ndarray  # (3, 3): tip, dorsum, jaw (cm)
    drift_cm: float  # largest control-point move over the last window
    converged: bool
    stopped_ms: float


# --- the specification -----------------------------------------------------------------------------

def drivable_names(cfg: Config) -> list[str]:
    return [*TONGUE_MUSCLES, *JAW_MUSCLES, *cfg.muscles.groups]


def pairs(spec: EPMapSpec) -> list[tuple[str, str]]:
    """The two-muscle nets, tip and dorsum lists merged (a net gives both control points)."""
    seen, out = set(), []
    for a, b in [*spec.pairs_tip, *spec.pairs_dorsum]:
        if frozenset((a, b)) not in seen:
            seen.add(frozenset((a, b)))
            out.append((a, b))
    return out


def check_spec(cfg: Config) -> None:
    """Every name in the map spec exists: one ArticError naming the first that does not."""
    spec = cfg.epmap
    valid = drivable_names(cfg)
    where = [("epmap.muscles", spec.muscles)]
    where += [("epmap.pairs_tip", p) for p in spec.pairs_tip] + [("epmap.pairs_dorsum", p) for p in spec.pairs_dorsum]
    where += [("epmap.groups", [g.independent, *g.pair]) for g in spec.groups]
    for key, names in where:
        for name in names:
            if name not in valid:
                raise ArticError(f"config: {key} names unknown muscle '{name}'; valid: {', '.join(valid)}")
    for key, names in (("epmap.typical_jaw", [spec.typical_jaw]), ("epmap.net_jaw_positions", spec.net_jaw_positions)):
        for name in names:
            if name not in spec.jaw_positions:
                raise ArticError(f"config: {key} names unknown jaw position '{name}'; "
                                 f"valid: {', '.join(spec.jaw_positions)}")
    for name, forces in spec.jaw_positions.items():
        for m in forces:
            if m not in valid:
                raise ArticError(f"config: epmap.jaw_positions.{name} names unknown muscle '{m}'; "
                                 f"valid: {', '.join(valid)}")
    if 0.0 not in spec.levels_n:
        raise ArticError("config: epmap.levels_n must include 0.0 (the rest of each vector)")


def plan(spec: EPMapSpec) -> list[Task]:
    """Every EP the spec needs, each once (a pair net's axes are single-muscle EPs, and so on)."""
    tasks: dict[Task, None] = {}

    def add(jaw: str, forces: dict[str, float]) -> None:
        key = canonical(forces)
        if key:  # all zero: the jaw position's rest, computed separately
            tasks[Task(jaw, key)] = None

    for jaw in spec.jaw_positions:
        for m in spec.muscles:
            for f in spec.levels_n:
                add(jaw, {m: f})
    grid = [0.0, *spec.pair_levels_n]
    for jaw in spec.net_jaw_positions:
        for a, b in pairs(spec):
            for fa in grid:
                for fb in grid:
                    add(jaw, add_forces({a: fa}, {b: fb}))
        for g in spec.groups:
            for fi in [0.0, *spec.group_levels_n]:
                for fa in grid:
                    for fb in grid:
                        add(jaw, add_forces({g.independent: fi}, {g.pair[0]: fa}, {g.pair[1]: fb}))
    return list(tasks)


def add_forces(*parts: dict[str, float]) -> dict[str, float]:
    out: dict[str, float] = {}
    for p in parts:
        for k, v in p.items():
            out[k] = out.get(k, 0.0) + v
    return out


# --- one equilibrium (physics; usable without maps) ------------------------------------------------

def control_for(model: Model, forces_n: dict[str, float]) -> Control:
    return Control(node_force=np.zeros((model.n_nodes, 3)), muscle_force=muscle_force_vector(model, forces_n))


def watch_nodes(model: Model) -> np.ndarray:
    return np.array([int(model.node_sets[k][0]) for k in CONTROL_POINTS])


def jaw_rest(model: Model, jaw_forces: dict[str, float]) -> State:
    """The rest posture of a jaw position: equilibrium with the jaw forces held (t = 0)."""
    rest = settle(model)
    if not canonical(jaw_forces):
        return rest
    state, _ = equilibrate(model, rest, control_for(model, jaw_forces), dt=0.01, tol=1e-2)
    return State(t=0.0, x=state.x, v=np.zeros_like(state.v), sigma2=state.sigma2, fibre_strain=state.fibre_strain)


def equilibrium_point(model: Model, start: State, forces_n: dict[str, float], spec: EPMapSpec,
                      fast: bool = False) -> EP:
    """Hold the forces for ``spec.duration_ms`` (``fast``: stop once settled) and read the control points."""
    h = hold(model, start, control_for(model, forces_n), units.ms_to_s(spec.duration_ms), watch_nodes(model),
             units.ms_to_s(spec.convergence_window_ms), stop_below=spec.early_stop_tol_cm if fast else None)
    return EP(x=h.state.x[watch_nodes(model)].copy(), drift_cm=h.drift,
              converged=bool(h.drift < spec.convergence_tol_cm), stopped_ms=units.s_to_ms(h.stopped))


# --- workers (top level: they travel to loky / dask processes) --------------------------------------

_MODELS: dict[str, Model] = {}
_RESTS: dict[tuple, State] = {}


def worker_model(key: str, cfg_json: str, mesh_path: str) -> Model:
    if key not in _MODELS:
        cfg = parse_config(json.loads(cfg_json), "<ep-map config>")
        mesh, wall, _ = load_mesh(mesh_path, expect=cfg)
        _MODELS.clear()
        _MODELS[key] = build_articulator(cfg, mesh, wall)
    return _MODELS[key]


def worker_rest(key: str, jaw_forces: Forces, cfg_json: str, mesh_path: str) -> State:
    if (key, jaw_forces) not in _RESTS:
        _RESTS[(key, jaw_forces)] = jaw_rest(worker_model(key, cfg_json, mesh_path), dict(jaw_forces))
    return _RESTS[(key, jaw_forces)]


def compute_ep(key: str, jaw_forces: Forces, forces: Forces, spec_json: str, fast: bool, cfg_json: str,
               mesh_path: str) -> dict:
    """One EP as plain arrays (cached by joblib.Memory on everything but the last two arguments)."""
    model = worker_model(key, cfg_json, mesh_path)
    spec = EPMapSpec.model_validate(json.loads(spec_json))
    start = worker_rest(key, jaw_forces, cfg_json, mesh_path)
    ep = equilibrium_point(model, start, add_forces(dict(jaw_forces), dict(forces)), spec, fast)
    return {"x": ep.x, "drift_cm": ep.drift_cm, "converged": ep.converged, "stopped_ms": ep.stopped_ms}


def compute_rest(key: str, jaw_forces: Forces, cfg_json: str, mesh_path: str) -> dict:
    model = worker_model(key, cfg_json, mesh_path)
    st = worker_rest(key, jaw_forces, cfg_json, mesh_path)
    return {"x": st.x[watch_nodes(model)].copy(), "mandible": st.x[model.node_sets["mandible"]].copy()}


def physics_code_hash() -> str:
    """Hash of the source an EP depends on (geometry, mechanics, config, this module): a cached EP from older
    physics code is never reused."""
    root = Path(__file__).resolve().parent.parent
    files = sorted([*root.glob("geometry/*.py"), *root.glob("mechanics/*.py"), root / "config.py", root / "units.py",
                    Path(__file__).resolve()])
    h = hashlib.sha256()
    for f in files:
        h.update(f.read_bytes())
    return h.hexdigest()


def _spec_key(spec: EPMapSpec) -> str:
    """The parts of the spec an EP depends on (not the lists of what to compute)."""
    keep = {k: getattr(spec, k) for k in ("duration_ms", "convergence_window_ms", "convergence_tol_cm",
                                          "early_stop_tol_cm")}
    return json.dumps(keep, sort_keys=True)


# --- parallel execution -----------------------------------------------------------------------------

@contextlib.contextmanager
def parallel_backend(backend: str, jobs: int, scheduler: str | None) -> Iterator[None]:
    from joblib import parallel_config

    if backend == "loky":
        if scheduler:
            raise ArticError("--scheduler needs --backend dask")
        with parallel_config(backend="loky", n_jobs=jobs):
            yield
        return
    if backend != "dask":
        raise ArticError(f"unknown --backend '{backend}'; valid: loky, dask")
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - distributed is a dependency
        raise ArticError("--backend dask needs dask.distributed; pip install distributed") from None
    cluster = None
    try:
        if scheduler:
            client = Client(scheduler, timeout="10s")
        else:
            cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, host="127.0.0.1",
                                   dashboard_address=None)
            client = Client(cluster)
    except (OSError, TimeoutError) as err:
        raise ArticError(f"cannot reach the dask scheduler at {scheduler}: {type(err).__name__}; start one "
                         "('dask scheduler') or use --backend loky") from None
    try:
        with parallel_config(backend="dask", n_jobs=-1):
            yield
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@dataclass
class BuildResult:
    path: Path
    up_to_date: bool
    computed: int = 0
    cached: int = 0
    total: int = 0
    unconverged: list[str] = field(default_factory=list)
    wall_time_s: float = 0.0
    contribution: dict | None = None
    not_monotonic: list[str] = field(default_factory=list)


MAP_FORMAT = 3  # bump when the file layout changes: an old file is then rebuilt (from the cache)


def inputs_hash(cfg: Config, mesh_sha: str, fast: bool) -> str:
    blob = json.dumps({"model": model_hash(cfg), "mesh": mesh_sha, "spec": cfg.epmap.model_dump(mode="json"),
                       "fast": fast, "version": __version__, "format": MAP_FORMAT, "code": physics_code_hash()},
                      sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def build_ep_maps(mesh: Path | str = "data/mesh.h5", config: Path | str | None = None,
                  out: Path | str = "data/epmaps.h5", jobs: int = 1, backend: str = "loky",
                  scheduler: str | None = None, fast: bool = False, cache: Path | str | None = None,
                  progress: Callable[[int, int], None] | None = None, force: bool = False) -> BuildResult:
    """Compute (or bring up to date) every EP map of the config's ``epmap`` spec; write ``out`` (HDF5)."""
    from joblib import Memory, Parallel, delayed

    cfg = load_config(config)
    check_spec(cfg)
    load_mesh(mesh, expect=cfg)  # a stale or foreign mesh fails here, in one line
    if jobs < 1:
        raise ArticError(f"--jobs must be at least 1, got {jobs}")
    out = Path(out)
    mesh_sha = file_hash(mesh)
    wanted = inputs_hash(cfg, mesh_sha, fast)
    if not force and _stored_inputs(out) == wanted:
        return BuildResult(path=out, up_to_date=True)
    spec = cfg.epmap
    key = hashlib.sha256((model_hash(cfg) + mesh_sha + physics_code_hash()).encode()).hexdigest()
    cfg_json = json.dumps(cfg.model_dump(mode="json"))
    spec_json = _spec_key(spec)
    memory = Memory(Path(cache) if cache is not None else out.parent / "cache", verbose=0)
    ep_fn = memory.cache(compute_ep, ignore=["cfg_json", "mesh_path"])
    rest_fn = memory.cache(compute_rest, ignore=["cfg_json", "mesh_path"])
    tasks = plan(spec)
    jaw_forces = {j: canonical(f) for j, f in spec.jaw_positions.items()}
    calls = [(rest_fn, (key, jaw_forces[j], cfg_json, str(mesh))) for j in spec.jaw_positions]
    calls += [(ep_fn, (key, jaw_forces[t.jaw], t.forces, spec_json, fast, cfg_json, str(mesh))) for t in tasks]
    cached = sum(fn.check_call_in_cache(*args) for fn, args in calls)
    t0 = time.perf_counter()
    results = [None] * len(calls)
    done = 0
    if progress is not None:
        progress(0, len(calls))
    # rests first (every EP of a jaw position starts from it), then the EPs, longest families last
    order = list(range(len(spec.jaw_positions))) + list(range(len(spec.jaw_positions), len(calls)))
    with parallel_backend(backend, jobs, scheduler):
        for phase in (order[: len(spec.jaw_positions)], order[len(spec.jaw_positions):]):
            gen = Parallel(return_as="generator_unordered")(
                delayed(_indexed)(i, calls[i][0], calls[i][1]) for i in phase)
            for i, res in gen:
                results[i] = res
                done += 1
                if progress is not None:
                    progress(done, len(calls))
    wall = time.perf_counter() - t0
    rests = {j: results[k]["x"] for k, j in enumerate(spec.jaw_positions)}
    mandibles = {j: results[k]["mandible"] for k, j in enumerate(spec.jaw_positions)}
    eps = {(t.jaw, t.forces): results[len(spec.jaw_positions) + k] for k, t in enumerate(tasks)}
    maps = assemble(spec, rests, eps, mandibles)
    write_ep_maps(out, maps, cfg, mesh_sha, wanted, fast)
    return BuildResult(path=out, up_to_date=False, computed=len(calls) - cached, cached=cached, total=len(calls),
                       unconverged=maps.unconverged(), wall_time_s=wall,
                       contribution=contribution_factors(maps, "rest" if "rest" in maps.jaws else spec.typical_jaw),
                       not_monotonic=monotonic_exceptions(maps))


def _indexed(i: int, fn, args: tuple):
    return i, fn(*args)


def _stored_inputs(path: Path) -> str | None:
    if not path.is_file():
        return None
    try:
        import h5py

        with h5py.File(path, "r") as f:
            return str(f.attrs.get("inputs_hash", ""))
    except OSError:
        return None  # unreadable: rebuilt and replaced


# --- the maps in memory -----------------------------------------------------------------------------

@dataclass
class Net:
    """EPs over a grid of forces: ``x[..., c, :]`` is control point c (tip, dorsum, jaw) in cm."""

    muscles: tuple[str, ...]
    levels: tuple[np.ndarray, ...]  # force levels (N) of each muscle, axis by axis
    x: np.ndarray  # (*grid, 3, 3)
    converged: np.ndarray  # (*grid,)
    drift_cm: np.ndarray  # (*grid,)


@dataclass
class JawMaps:
    forces: dict[str, float]
    rest: np.ndarray  # (3, 3)
    single: dict[str, Net]
    pair: dict[str, Net] = field(default_factory=dict)
    group: dict[str, Net] = field(default_factory=dict)
    mandible: np.ndarray | None = None  # (K, 3) the mandible's nodes at this jaw position's rest, cm


@dataclass
class EPMaps:
    jaws: dict[str, JawMaps]
    typical_jaw: str
    attrs: dict = field(default_factory=dict)

    def unconverged(self) -> list[str]:
        out = []
        for jname, jm in self.jaws.items():
            for fam in ("single", "pair", "group"):
                for name, net in getattr(jm, fam).items():
                    n = int((~net.converged).sum())
                    if n:
                        out.append(f"{jname}/{fam}/{name}: {n} of {net.converged.size}")
        return out


def assemble(spec: EPMapSpec, rests: dict[str, np.ndarray], eps: dict,
             mandibles: dict[str, np.ndarray] | None = None) -> EPMaps:
    def get(jaw: str, forces: dict[str, float]):
        key = canonical(forces)
        if not key:
            return rests[jaw], 0.0, True
        r = eps[(jaw, key)]
        return r["x"], r["drift_cm"], r["converged"]

    def net(jaw: str, muscles: tuple[str, ...], levels: tuple) -> Net:
        shape = tuple(len(lv) for lv in levels)
        x = np.zeros(shape + (3, 3))
        conv = np.zeros(shape, dtype=bool)
        drift = np.zeros(shape)
        for idx in np.ndindex(*shape):
            xi, d, c = get(jaw, add_forces(*({m: lv[i]} for m, lv, i in zip(muscles, levels, idx))))
            x[idx], drift[idx], conv[idx] = xi, d, c
        return Net(muscles=muscles, levels=tuple(np.asarray(lv, dtype=float) for lv in levels), x=x,
                   converged=conv, drift_cm=drift)

    jaws = {}
    grid = [0.0, *spec.pair_levels_n]
    for jaw, jf in spec.jaw_positions.items():
        jm = JawMaps(forces=dict(jf), rest=rests[jaw],
                     single={m: net(jaw, (m,), (spec.levels_n,)) for m in spec.muscles},
                     mandible=None if mandibles is None else mandibles[jaw])
        if jaw in spec.net_jaw_positions:
            for a, b in pairs(spec):
                jm.pair[f"{a}+{b}"] = net(jaw, (a, b), (grid, grid))
            for g in spec.groups:
                jm.group[f"{g.independent}+{g.pair[0]}+{g.pair[1]}"] = net(
                    jaw, (g.independent, *g.pair), ([0.0, *spec.group_levels_n], grid, grid))
        jaws[jaw] = jm
    return EPMaps(jaws=jaws, typical_jaw=spec.typical_jaw)


def contribution_factors(maps: EPMaps, jaw: str) -> dict:
    """Table III: EP-vector amplitude from 0 to the top force, normalised by the largest, per control point."""
    jm = maps.jaws[jaw]
    amp = {m: [float(np.linalg.norm(n.x[-1, c] - n.x[0, c])) for c in (0, 1)] for m, n in jm.single.items()}
    top = [max(a[c] for a in amp.values()) or 1.0 for c in (0, 1)]
    return {"jaw": jaw, "amplitude_cm": amp,
            "factor": {m: [a[0] / top[0], a[1] / top[1]] for m, a in amp.items()}}


MONOTONIC_TOL_CM = 0.005


def monotonic_exceptions(maps: EPMaps) -> list[str]:
    """EP vectors whose distance from rest ever falls as the force rises (beyond 0.005 cm)."""
    out = []
    for jname, jm in maps.jaws.items():
        for m, n in jm.single.items():
            for c, cp in enumerate(("tip", "dorsum")):
                dist = np.linalg.norm(n.x[:, c] - n.x[0, c], axis=1)
                drop = np.flatnonzero(np.diff(dist) < -MONOTONIC_TOL_CM)
                for k in drop:
                    out.append(f"{jname} {m} {cp}: {dist[k]:.3f} -> {dist[k + 1]:.3f} cm from rest between "
                               f"{n.levels[0][k]:g} and {n.levels[0][k + 1]:g} N")
    return out


# --- HDF5 ---------------------------------------------------------------------------------------------

def write_ep_maps(path: Path, maps: EPMaps, cfg: Config, mesh_sha: str, inputs: str, fast: bool) -> None:
    with atomic_h5(path, "epmap", config_hash(cfg)) as f:
        f.attrs.update({"model_hash": model_hash(cfg), "mesh_sha256": mesh_sha, "inputs_hash": inputs,
                        "method": "dynamic, stopped once settled" if fast else "dynamic, full duration",
                        "duration_ms": cfg.epmap.duration_ms, "typical_jaw": maps.typical_jaw,
                        "control_points": list(CONTROL_POINTS), "spec_yaml": json.dumps(cfg.epmap.model_dump(mode="json")),
                        "units": "positions in cm (x anterior, y superior, z left), forces in N",
                        "layout": "jaw_positions/<jaw>/{rest, single/<muscle>, pair/<a+b>, group/<i+a+b>}: "
                                  "force_<k>_n per axis; tip, dorsum, jaw (*grid, 3) in cm; converged; drift_cm"})
        f.attrs["jaw_order"] = list(maps.jaws)
        for jname, jm in maps.jaws.items():
            g = f.create_group(f"jaw_positions/{jname}")
            g.attrs["jaw_forces_n"] = json.dumps(jm.forces)
            for fam in ("single", "pair", "group"):
                g.attrs[f"{fam}_order"] = list(getattr(jm, fam))
            r = g.create_group("rest")
            for c, cp in enumerate(CONTROL_POINTS):
                r.create_dataset(cp, data=jm.rest[c]).attrs["units"] = "cm"
            if jm.mandible is not None:
                r.create_dataset("mandible", data=jm.mandible).attrs["units"] = "cm (the mandible's nodes)"
            for fam in ("single", "pair", "group"):
                for name, net in getattr(jm, fam).items():
                    n = g.create_group(f"{fam}/{name}")
                    n.attrs["muscles"] = list(net.muscles)
                    for k, (m, lv) in enumerate(zip(net.muscles, net.levels)):
                        ds = n.create_dataset(f"force_{k}_n", data=lv)
                        ds.attrs.update({"units": "N", "muscle": m})
                    for c, cp in enumerate(CONTROL_POINTS):
                        n.create_dataset(cp, data=net.x[..., c, :]).attrs["units"] = "cm"
                    n.create_dataset("converged", data=net.converged)
                    n.create_dataset("drift_cm", data=net.drift_cm).attrs["units"] = (
                        f"cm moved over the last {cfg.epmap.convergence_window_ms:g} ms")


def load_ep_maps(path: Path | str = "data/epmaps.h5", mesh: Path | str | None = None) -> EPMaps:
    """Read maps written by :func:`build_ep_maps`; a corrupted file or one built from another mesh is an
    ArticError naming the fix."""
    path = Path(path)
    hint = "rebuild it with 'artic ep-map'"
    with open_artifact(path, "epmap", hint) as f:
        try:
            if mesh is not None and f.attrs["mesh_sha256"] != file_hash(mesh):
                raise ArticError(f"{path} was built from another mesh than {mesh}; {hint}")
            jaws = {}
            for jname in f.attrs["jaw_order"]:
                g = f["jaw_positions"][jname]
                rest = np.array([g["rest"][cp][()] for cp in CONTROL_POINTS])
                jm = JawMaps(forces=json.loads(g.attrs["jaw_forces_n"]), rest=rest, single={},
                             mandible=g["rest"]["mandible"][()] if "mandible" in g["rest"] else None)
                for fam in ("single", "pair", "group"):
                    for name in g.attrs[f"{fam}_order"]:
                        n = g[fam][name]
                        muscles = tuple(n.attrs["muscles"])
                        levels = tuple(n[f"force_{k}_n"][()] for k in range(len(muscles)))
                        x = np.stack([n[cp][()] for cp in CONTROL_POINTS], axis=-2)
                        getattr(jm, fam)[name] = Net(muscles=muscles, levels=levels, x=x,
                                                     converged=n["converged"][()], drift_cm=n["drift_cm"][()])
                jaws[jname] = jm
            attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
            return EPMaps(jaws=jaws, typical_jaw=str(f.attrs["typical_jaw"]), attrs=attrs)
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {hint}") from None
