"""Muscle function from scattered starts (the paper's section IV.A.1, Figs. 5 and 6).

Starting points: from the rest posture, a combination of three muscles (for
example GGp-GGm-GGa) held for 120 ms at every triple of six force levels
(4 combinations x 6^3 = 864 starts).  From each start all forces are released
and one muscle pulls at 4 N for 150 ms; the end points of the tip and the
dorsum show where each muscle drives them whatever the start.  As in the
paper the wall is left out (``muscle_function.contact``).

Each distinct start force set is one task (its 120-ms run and the ten 150-ms
drives; the combinations share muscles, so 864 starts are 726 distinct ones),
run in parallel through joblib and cached on disk like the EP maps, so an
interrupted run resumes.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .. import units
from ..config import Config, load_config, model_hash, parse_config
from ..control.epmap import canonical, control_for, parallel_backend, physics_code_hash, watch_nodes
from ..errors import ArticError
from ..io.store import atomic_h5, file_hash, load_mesh, open_artifact
from ..mechanics.model import Model, build_articulator
from ..mechanics.simulate import hold, settle

_CACHE: dict[str, tuple[Model, object]] = {}


def _model_and_rest(key: str, cfg_json: str, mesh_path: str) -> tuple[Model, object]:
    if key not in _CACHE:
        cfg = parse_config(json.loads(cfg_json), "<muscle-function config>")
        mesh, wall, _ = load_mesh(mesh_path, expect=cfg)
        model = build_articulator(cfg, mesh, wall, contact=cfg.muscle_function.contact)
        _CACHE.clear()
        _CACHE[key] = (model, settle(model))
    return _CACHE[key]


def starts(cfg: Config) -> list[tuple[int, tuple[float, ...]]]:
    spec = cfg.muscle_function
    return [(c, lv) for c in range(len(spec.start_combinations))
            for lv in itertools.product(spec.start_levels_n, repeat=len(spec.start_combinations[c]))]


def run_start(key: str, start_forces: tuple, start_ms: float, muscles: tuple[str, ...], drive_n: float,
              drive_ms: float, cfg_json: str, mesh_path: str) -> dict:
    """One start (``start_forces``: canonical (muscle, N) pairs) and every muscle's drive from it (cm)."""
    model, rest = _model_and_rest(key, cfg_json, mesh_path)
    watch = watch_nodes(model)
    forces = dict(start_forces)
    h = hold(model, rest, control_for(model, forces), units.ms_to_s(start_ms), watch, units.ms_to_s(start_ms))
    start = h.state
    ends = []
    for m in muscles:
        d = hold(model, start, control_for(model, {m: drive_n}), units.ms_to_s(drive_ms), watch,
                 units.ms_to_s(drive_ms))
        ends.append(d.state.x[watch])
    return {"start": start.x[watch].copy(), "ends": np.array(ends)}


@dataclass
class MuscleFunction:
    muscles: list[str]
    combinations: list[list[str]]
    combo: np.ndarray  # (S,) index of each start's combination
    start_forces: np.ndarray  # (S, 3) N
    starts: np.ndarray  # (S, 3, 3): tip, dorsum, jaw (cm)
    ends: np.ndarray  # (M, S, 3, 3)
    rest: np.ndarray  # (3, 3)
    drive_n: float
    drive_ms: float


def build_muscle_function(mesh: Path | str = "data/mesh.h5", config: Path | str | None = None,
                          out: Path | str = "data/muscle_function.h5", jobs: int = 2, cache: Path | str | None = None,
                          progress: Callable[[int, int], None] | None = None) -> tuple[MuscleFunction, float, int]:
    from joblib import Memory, Parallel, delayed

    cfg = load_config(config)
    spec = cfg.muscle_function
    from ..control.epmap import drivable_names

    valid = drivable_names(cfg)
    for key_name, names in [("muscle_function.muscles", spec.muscles),
                            *[("muscle_function.start_combinations", c) for c in spec.start_combinations]]:
        for n in names:
            if n not in valid:
                raise ArticError(f"config: {key_name} names unknown muscle '{n}'; valid: {', '.join(valid)}")
    load_mesh(mesh, expect=cfg)
    if jobs < 1:
        raise ArticError(f"--jobs must be at least 1, got {jobs}")
    out = Path(out)
    mesh_sha = file_hash(mesh)
    key = hashlib.sha256((model_hash(cfg) + mesh_sha + physics_code_hash() + str(spec.contact)).encode()).hexdigest()
    cfg_json = json.dumps(cfg.model_dump(mode="json"))
    memory = Memory(Path(cache) if cache is not None else out.parent / "cache", verbose=0)
    fn = memory.cache(run_start, ignore=["cfg_json", "mesh_path"])
    todo = starts(cfg)
    # combinations share muscles: a start whose other muscles are at zero recurs; each distinct one runs once
    keys = [canonical(dict(zip(spec.start_combinations[c], lv))) for c, lv in todo]
    unique = list(dict.fromkeys(keys))
    calls = [(key, forces, spec.start_ms, tuple(spec.muscles), spec.drive_force_n, spec.drive_ms, cfg_json,
              str(mesh)) for forces in unique]
    cached = sum(fn.check_call_in_cache(*a) for a in calls)
    results = [None] * len(calls)
    t0 = time.perf_counter()
    with parallel_backend("loky", jobs, None):
        gen = Parallel(return_as="generator_unordered")(delayed(_indexed)(i, fn, a) for i, a in enumerate(calls))
        for n, (i, r) in enumerate(gen, start=1):
            results[i] = r
            if progress is not None:
                progress(n, len(calls))
    wall = time.perf_counter() - t0
    where = {forces: i for i, forces in enumerate(unique)}
    results = [results[where[k]] for k in keys]
    model, rest = _model_and_rest(key, cfg_json, str(mesh))
    mf = MuscleFunction(muscles=list(spec.muscles), combinations=[list(c) for c in spec.start_combinations],
                        combo=np.array([c for c, _ in todo]),
                        start_forces=np.array([lv for _, lv in todo], dtype=float),
                        starts=np.array([r["start"] for r in results]),
                        ends=np.array([r["ends"] for r in results]).transpose(1, 0, 2, 3),
                        rest=rest.x[watch_nodes(model)].copy(), drive_n=spec.drive_force_n, drive_ms=spec.drive_ms)
    with atomic_h5(out, "muscle-function") as f:
        f.attrs.update({"mesh_sha256": mesh_sha, "model_hash": model_hash(cfg), "muscles": mf.muscles,
                        "combinations": json.dumps(mf.combinations), "drive_force_n": mf.drive_n,
                        "drive_ms": mf.drive_ms, "start_ms": spec.start_ms, "contact": spec.contact,
                        "control_points": ["tip", "dorsum", "jaw"],
                        "layout": "starts (S, point, xyz) cm; ends (muscle, S, point, xyz) cm; rest (point, xyz)"})
        for name, data, unit in (("combination", mf.combo, "index into attribute combinations"),
                                 ("start_forces", mf.start_forces, "N"), ("starts", mf.starts, "cm"),
                                 ("ends", mf.ends, "cm"), ("rest", mf.rest, "cm")):
            f.create_dataset(name, data=data).attrs["units"] = unit
    return mf, wall, cached, len(unique)


def _indexed(i, fn, args):
    return i, fn(*args)


def load_muscle_function(path: Path | str) -> MuscleFunction:
    hint = "rebuild it with 'artic muscle-function'"
    with open_artifact(path, "muscle-function", hint) as f:
        try:
            return MuscleFunction(muscles=list(f.attrs["muscles"]), combinations=json.loads(f.attrs["combinations"]),
                                  combo=f["combination"][()], start_forces=f["start_forces"][()],
                                  starts=f["starts"][()], ends=f["ends"][()], rest=f["rest"][()],
                                  drive_n=float(f.attrs["drive_force_n"]), drive_ms=float(f.attrs["drive_ms"]))
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {hint}") from None


def convergence(mf: MuscleFunction) -> list[dict]:
    """Per muscle and control point: start spread, end spread (cm) and the mean end displacement from rest."""
    rows = []
    for k, m in enumerate(mf.muscles):
        for c, cp in enumerate(("tip", "dorsum")):
            s = mf.starts[:, c, :2]
            e = mf.ends[k, :, c, :2]
            rows.append({"muscle": m, "point": cp, "start_spread_cm": float(np.sqrt(s.var(axis=0).sum())),
                         "end_spread_cm": float(np.sqrt(e.var(axis=0).sum())),
                         "mean_end_from_rest_cm": [float(v) for v in e.mean(axis=0) - mf.rest[c, :2]]})
    return rows
