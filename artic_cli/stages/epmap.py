"""Stage ``epmaps``: equilibrium-position maps at every jaw position (the paper's section IV.B).

Every EP (jaw position, muscle forces) is one call of :func:`artic_cli.control.equilibrium.compute_ep` in
one cached parallel sweep (:mod:`artic_cli.parallel`).  Its cache key is the hash of the config sections the
model reads, the mesh's content hash and the hash of the equilibrium code (syntax trees, so a comment or
docstring edit keeps every EP), plus the forces and the EP-relevant part of the spec: an interrupted build
resumes, a rebuilt but identical mesh reuses every EP, and a changed map spec computes only what it adds.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..config import Config, load_config
from ..control.epmap import (CONTROL_POINTS, EPMaps, JawMaps, Net, assemble, canonical, check_spec,
                             contribution_factors, monotonic_exceptions, plan)
from ..control.equilibrium import compute_ep, compute_rest, spec_key
from ..errors import ArticError
from ..io.fingerprint import code_hash, digest, sections_hash
from ..io.store import atomic_h5, open_artifact, read_array
from ..mechanics.model import ARTICULATOR_SECTIONS
from ..parallel import Sweep, run_sweep
from ..validation import check_number
from . import mesh as mesh_stage
from . import paths
from .base import Stage, up_to_date

STAGE = Stage(name="epmaps", module=__name__, sections=(*ARTICULATOR_SECTIONS, "epmap"), reads=("mesh",),
              kind="epmap", hint="rebuild it with 'artic ep-map'")
EQUILIBRIUM = "artic_cli.control.equilibrium"


def ep_key(cfg: Config, mesh_sha: str) -> str:
    """What every EP of a model depends on besides its forces: the model's config sections, the mesh's
    content and the equilibrium code."""
    return digest({"sections": sections_hash(cfg, ARTICULATOR_SECTIONS), "mesh": mesh_sha,
                   "code": code_hash(EQUILIBRIUM)})


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


def compute(cfg: Config, mesh, wall, mesh_sha: str, sweep: Sweep, fast: bool = False) -> tuple[EPMaps, int]:
    """Every map of the config's ``epmap`` spec, and how many EPs came from the sweep's cache."""
    view = STAGE.view(cfg)
    check_spec(view)
    spec = view.epmap
    key = ep_key(view, mesh_sha)
    cfg_json = json.dumps(view.full.model_dump(mode="json"))
    spec_json = spec_key(spec)
    tasks = plan(spec)
    jaws = list(spec.jaw_positions)
    jaw_forces = {j: canonical(f) for j, f in spec.jaw_positions.items()}
    # one function for both kinds of call keeps one cache and one sweep: rests first, then the EPs
    calls = [("rest", key, jaw_forces[j], (), "", False, cfg_json, mesh, wall) for j in jaws]
    calls += [("ep", key, jaw_forces[t.jaw], t.forces, spec_json, fast, cfg_json, mesh, wall) for t in tasks]
    res = run_sweep(_call, calls, sweep, ignore=["cfg_json", "mesh", "wall"],
                    phases=[range(len(jaws)), range(len(jaws), len(calls))])
    rests = {j: res.results[k]["x"] for k, j in enumerate(jaws)}
    mandibles = {j: res.results[k]["mandible"] for k, j in enumerate(jaws)}
    eps = {(t.jaw, t.forces): res.results[len(jaws) + k] for k, t in enumerate(tasks)}
    maps = assemble(spec, rests, eps, mandibles, {j: res.results[k]["shape"] for k, j in enumerate(jaws)})
    maps.model_rest = res.results[0]["model_rest"]
    maps.mandible_nodes = res.results[0]["mandible_nodes"]
    return maps, res.cached


def _call(what: str, key: str, jaw_forces, forces, spec_json: str, fast: bool, cfg_json: str, mesh, wall) -> dict:
    if what == "rest":
        return compute_rest(key, jaw_forces, cfg_json, mesh, wall)
    return compute_ep(key, jaw_forces, forces, spec_json, fast, cfg_json, mesh, wall)


def build_ep_maps(mesh: Path | str = paths.MESH, config: Path | str | None = None,
                  out: Path | str = paths.EPMAPS, jobs: int = 1, backend: str = "loky",
                  scheduler: str | None = None, fast: bool = False, cache: Path | str | None = None,
                  progress: Callable[[int, int], None] | None = None, force: bool = False) -> BuildResult:
    """Compute (or bring up to date) every EP map of the config's ``epmap`` spec; write ``out`` (HDF5)."""
    cfg = load_config(config)
    check_spec(STAGE.view(cfg))
    m = mesh_stage.read(mesh, cfg)  # a stale or foreign mesh fails here, in one line
    check_number("--jobs", jobs, ge=1)
    out = Path(out)
    prov = STAGE.provenance(cfg, inputs={"mesh": m.content_sha256}, params={"fast": fast},
                            code_roots=(EQUILIBRIUM,))
    if not force and up_to_date(out, prov):
        return BuildResult(path=out, up_to_date=True)
    sweep = Sweep(jobs=jobs, backend=backend, scheduler=scheduler,
                  cache=Path(cache) if cache is not None else out.parent / "cache", progress=progress)
    t0 = time.perf_counter()
    maps, cached = compute(cfg, m.mesh, m.wall, m.content_sha256, sweep, fast)
    wall = time.perf_counter() - t0
    total = len(cfg.epmap.jaw_positions) + len(plan(cfg.epmap))
    write(out, maps, cfg, prov, fast)
    return BuildResult(path=out, up_to_date=False, computed=total - cached, cached=cached, total=total,
                       unconverged=maps.unconverged(), wall_time_s=wall,
                       contribution=contribution_factors(maps, "rest" if "rest" in maps.jaws else maps.typical_jaw),
                       not_monotonic=monotonic_exceptions(maps))


def write(path: Path | str, maps: EPMaps, cfg: Config, prov=None, fast: bool = False) -> None:
    with atomic_h5(path, "epmap", prov) as f:
        f.attrs.update({"method": "dynamic, stopped once settled" if fast else "dynamic, full duration",
                        "duration_ms": cfg.epmap.duration_ms, "extend_ms": cfg.epmap.extend_ms,
                        "typical_jaw": maps.typical_jaw,
                        "control_points": list(CONTROL_POINTS), "spec_json": json.dumps(cfg.epmap.model_dump(mode="json")),
                        "units": "positions in cm (x anterior, y superior, z left), forces in N",
                        "layout": "jaw_positions/<jaw>/{rest, single/<muscle>, pair/<a+b>, group/<i+a+b>}: "
                                  "force_<k>_n per axis; tip, dorsum, jaw (*grid, 3) in cm; converged; drift_cm"})
        f.attrs["jaw_order"] = list(maps.jaws)
        if maps.model_rest is not None:
            f.create_dataset("nodes/rest", data=maps.model_rest).attrs["units"] = "cm (the model's rest)"
            f.create_dataset("nodes/mandible", data=maps.mandible_nodes).attrs["units"] = "node indices"
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
            if jm.rest_shape is not None:
                r.create_dataset("shape", data=jm.rest_shape, compression="gzip").attrs["units"] = "cm (every node)"
            for fam in ("single", "pair", "group"):
                for name, net in getattr(jm, fam).items():
                    n = g.create_group(f"{fam}/{name}")
                    n.attrs["muscles"] = list(net.muscles)
                    for k, (mu, lv) in enumerate(zip(net.muscles, net.levels)):
                        ds = n.create_dataset(f"force_{k}_n", data=lv)
                        ds.attrs.update({"units": "N", "muscle": mu})
                    for c, cp in enumerate(CONTROL_POINTS):
                        n.create_dataset(cp, data=net.x[..., c, :]).attrs["units"] = "cm"
                    n.create_dataset("converged", data=net.converged)
                    if net.shapes is not None:
                        n.create_dataset("shape", data=net.shapes, compression="gzip", shuffle=True).attrs["units"] = (
                            "cm (*grid x nodes x 3: every node at each EP)")
                    n.create_dataset("drift_cm", data=net.drift_cm).attrs["units"] = (
                        f"cm moved over the last {cfg.epmap.convergence_window_ms:g} ms")


def read(path: Path | str = paths.EPMAPS, mesh: Path | str | None = None, shapes: bool = True) -> EPMaps:
    """Maps written by :func:`build_ep_maps` (``attrs`` holds the root attributes, ``content_sha256`` among
    them); with ``mesh``, checks they were built from that mesh's content.  ``shapes=False`` leaves the EPs'
    whole shapes out (the control points are what a spatial target is solved on; the shapes are most of the
    file)."""
    path = Path(path)
    hint = STAGE.hint
    mesh_sha = None if mesh is None else mesh_stage.read(mesh).content_sha256
    with open_artifact(path, "epmap", hint) as f:
        try:
            if mesh_sha is not None and json.loads(f.attrs["inputs_json"]).get("mesh") != mesh_sha:
                raise ArticError(f"{path} was built from another mesh than {mesh}; {hint}")
            jaws = {}
            for jname in f.attrs["jaw_order"]:
                g = f["jaw_positions"][jname]
                r = g["rest"]
                rest = np.array([read_array(r, cp) for cp in CONTROL_POINTS])
                jm = JawMaps(forces=json.loads(g.attrs["jaw_forces_n"]), rest=rest, single={},
                             mandible=read_array(r, "mandible") if "mandible" in r else None,
                             rest_shape=read_array(r, "shape") if shapes and "shape" in r else None)
                for fam in ("single", "pair", "group"):
                    for name in g.attrs[f"{fam}_order"]:
                        n = g[fam][name]
                        muscles = tuple(n.attrs["muscles"])
                        levels = tuple(read_array(n, f"force_{k}_n") for k in range(len(muscles)))
                        x = np.stack([read_array(n, cp) for cp in CONTROL_POINTS], axis=-2)
                        getattr(jm, fam)[name] = Net(muscles=muscles, levels=levels, x=x,
                                                     converged=read_array(n, "converged"), drift_cm=read_array(n, "drift_cm"),
                                                     shapes=read_array(n, "shape") if shapes and "shape" in n else None)
                jaws[jname] = jm
            attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
            return EPMaps(jaws=jaws, typical_jaw=str(f.attrs["typical_jaw"]), attrs=attrs,
                          model_rest=f["nodes/rest"][()] if "nodes" in f else None,
                          mandible_nodes=f["nodes/mandible"][()] if "nodes" in f else None)
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {hint}") from None


load_ep_maps = read
