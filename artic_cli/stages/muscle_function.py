"""Stage ``musclefunction``: each muscle from scattered starts (section IV.A.1, Figs. 5 and 6).

Each distinct start force set is one call of :func:`artic_cli.experiments.muscle_function.run_start` in the
cached parallel sweep, keyed like the EP maps by config sections, mesh content and code.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..config import Config, load_config
from ..control.epmap import canonical, drivable_names
from ..control.equilibrium import watch_nodes
from ..errors import ArticError
from ..experiments.muscle_function import MuscleFunction, model_and_rest, run_start, starts
from ..geometry.anatomy import check_muscle_names
from ..io.fingerprint import code_hash, digest, sections_hash
from ..io.store import atomic_h5, open_artifact
from ..mechanics.model import ARTICULATOR_SECTIONS
from ..parallel import Sweep, run_sweep
from ..validation import check_number
from . import mesh as mesh_stage
from . import paths
from .base import Stage, up_to_date

STAGE = Stage(name="musclefunction", module=__name__, sections=(*ARTICULATOR_SECTIONS, "muscle_function"),
              reads=("mesh",), kind="muscle-function", hint="rebuild it with 'artic muscle-function'")
PHYSICS = "artic_cli.experiments.muscle_function"


def check_spec(cfg: Config) -> None:
    spec = cfg.muscle_function
    valid = drivable_names(cfg)
    for key_name, names in [("muscle_function.muscles", spec.muscles),
                            *[("muscle_function.start_combinations", c) for c in spec.start_combinations]]:
        check_muscle_names(names, valid, key_name)


def compute(cfg: Config, mesh, wall, mesh_sha: str, sweep: Sweep) -> tuple[MuscleFunction, int, int]:
    """The study, how many distinct starts came from the cache, and how many distinct starts there are."""
    view = STAGE.view(cfg)
    check_spec(view)
    spec = view.muscle_function
    key = digest({"sections": sections_hash(view, ARTICULATOR_SECTIONS), "mesh": mesh_sha,
                  "code": code_hash(PHYSICS), "contact": spec.contact,
                  "hold_jaw": spec.hold_jaw})
    cfg_json = json.dumps(view.full.model_dump(mode="json"))
    todo = starts(view)
    # combinations share muscles: a start whose other muscles are at zero recurs; each distinct one runs once
    keys = [canonical(dict(zip(spec.start_combinations[c], lv))) for c, lv in todo]
    unique = list(dict.fromkeys(keys))
    calls = [(key, forces, spec.start_ms, tuple(spec.muscles), spec.drive_force_n, spec.drive_ms, cfg_json,
              mesh, wall) for forces in unique]
    res = run_sweep(run_start, calls, sweep, ignore=["cfg_json", "mesh", "wall"])
    where = {forces: i for i, forces in enumerate(unique)}
    results = [res.results[where[k]] for k in keys]
    model, rest = model_and_rest(key, cfg_json, mesh, wall)
    mf = MuscleFunction(muscles=list(spec.muscles), combinations=[list(c) for c in spec.start_combinations],
                        combo=np.array([c for c, _ in todo]),
                        start_forces=np.array([lv for _, lv in todo], dtype=float),
                        starts=np.array([r["start"] for r in results]),
                        ends=np.array([r["ends"] for r in results]).transpose(1, 0, 2, 3),
                        rest=rest.x[watch_nodes(model)].copy(), drive_n=spec.drive_force_n, drive_ms=spec.drive_ms)
    return mf, res.cached, len(unique)


def write(path: Path | str, mf: MuscleFunction, cfg: Config, prov=None) -> None:
    spec = cfg.muscle_function
    with atomic_h5(path, STAGE.kind, prov) as f:
        f.attrs.update({"muscles": mf.muscles, "combinations": json.dumps(mf.combinations),
                        "drive_force_n": mf.drive_n, "drive_ms": mf.drive_ms, "start_ms": spec.start_ms,
                        "contact": spec.contact, "hold_jaw": spec.hold_jaw,
                        "control_points": ["tip", "dorsum", "jaw"],
                        "layout": "starts (S, point, xyz) cm; ends (muscle, S, point, xyz) cm; rest (point, xyz)"})
        for name, data, unit in (("combination", mf.combo, "index into attribute combinations"),
                                 ("start_forces", mf.start_forces, "N"), ("starts", mf.starts, "cm"),
                                 ("ends", mf.ends, "cm"), ("rest", mf.rest, "cm")):
            f.create_dataset(name, data=data).attrs["units"] = unit


def read(path: Path | str) -> MuscleFunction:
    hint = STAGE.hint
    with open_artifact(path, STAGE.kind, hint) as f:
        try:
            return MuscleFunction(muscles=list(f.attrs["muscles"]), combinations=json.loads(f.attrs["combinations"]),
                                  combo=f["combination"][()], start_forces=f["start_forces"][()],
                                  starts=f["starts"][()], ends=f["ends"][()], rest=f["rest"][()],
                                  drive_n=float(f.attrs["drive_force_n"]), drive_ms=float(f.attrs["drive_ms"]))
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {hint}") from None


def build_muscle_function(mesh: Path | str = paths.MESH, config: Path | str | None = None,
                          out: Path | str = paths.MUSCLE_FUNCTION, jobs: int = 2, cache: Path | str | None = None,
                          progress: Callable[[int, int], None] | None = None
                          ) -> tuple[MuscleFunction, float, int, int, bool]:
    """Run (or bring up to date) the study into ``out``: the study, wall time (s), distinct starts from the
    cache, distinct starts, and whether ``out`` was already up to date."""
    cfg = load_config(config)
    check_spec(cfg)
    m = mesh_stage.read(mesh, cfg)
    check_number("--jobs", jobs, ge=1)
    out = Path(out)
    prov = STAGE.provenance(cfg, inputs={"mesh": m.content_sha256})
    if up_to_date(out, prov):
        mf = read(out)
        return mf, 0.0, 0, 0, True
    sweep = Sweep(jobs=jobs, cache=Path(cache) if cache is not None else out.parent / "cache", progress=progress)
    t0 = time.perf_counter()
    mf, cached, distinct = compute(cfg, m.mesh, m.wall, m.content_sha256, sweep)
    wall = time.perf_counter() - t0
    write(out, mf, cfg, prov)
    return mf, wall, cached, distinct, False


load_muscle_function = read
