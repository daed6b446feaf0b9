"""Stage ``vocal-tract``: area functions from simulated shapes (the paper's section II.A).

For every frame of a simulation (or the rest posture, or one EP of an EP-map file) the tongue's
midsagittal surface and the mandible's rigid motion place the tract's contours
(:mod:`artic_cli.tract`); the grid lines read the distances and the power laws give the areas; the lip tube
and the velopharyngeal port are control inputs (the config's defaults, a schedule's ``tract`` entries, or
options).  ``write`` and ``read`` are the file, ``vocal_tract`` is what the CLI and ``make`` call.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..config import Config, load_config
from ..control.equilibrium import map_ep_state, parse_ep
from ..errors import ArticError
from ..io.fingerprint import digest, sections_hash
from ..io.store import Provenance, atomic_h5, atomic_path, open_artifact
from ..mechanics.model import ARTICULATOR_SECTIONS
from ..schedule import Schedule, TractEntry, parse_schedule
from ..tract.area_function import AreaFunctions
from ..tract.areas import Tracts, tracts_of
from ..tract.controls import check_overrides, controls_for
from ..tract.outline import Grid
from ..tract.shapes import rest_shapes, shapes_of_model, shapes_of_simulation
from ..tract.speaker import TRACT_SECTIONS, speaker_tract
from ..validation import load_yaml
from . import mesh as mesh_stage
from . import paths
from . import simulate as simulate_stage
from .base import Stage, up_to_date

STAGE = Stage(name="tracts", module=__name__, sections=(*ARTICULATOR_SECTIONS, "epmap", "vocal_tract"),
              reads=("mesh", "sims", "epmaps"), kind="vocal-tract", hint="rerun 'artic vocal-tract'")


# --- the file ---------------------------------------------------------------------------------------------

def write(path: Path | str, t: Tracts, prov: Provenance | None = None, extra: dict | None = None) -> None:
    """Every dataset with its unit; frames x sections, glottis first, the lip tube last."""
    af = t.af
    area, pos, reg = af.constriction()
    with atomic_h5(path, "vocal-tract", prov) as f:
        f.attrs.update(extra or {})
        f.attrs["region_names"] = list(af.region_names)
        f.attrs["layout"] = "frames x sections, glottis first; the last sections are the lip tube"
        for name, data, unit in [("time", t.time_s, "s"), ("length_cm", af.length_cm, "cm"),
                                 ("area_cm2", af.area_cm2, "cm^2"), ("tract_length_cm", af.tract_length_cm, "cm"),
                                 ("velum_port_cm2", t.controls["velum_port_cm2"], "cm^2"),
                                 ("glottis_cm2", t.controls["glottis_cm2"], "cm^2"),
                                 ("lips/area_cm2", t.controls["lip_area_cm2"], "cm^2"),
                                 ("lips/length_cm", t.controls["lip_length_cm"], "cm"),
                                 ("section_region", af.region, "index into region_names"),
                                 ("constriction/area_cm2", area, "cm^2"),
                                 ("constriction/position_cm", pos, "cm from the glottis"),
                                 ("constriction/region", reg, "index into region_names"),
                                 ("grid/origin_cm", t.grid.origin, "cm"), ("grid/normal", t.grid.normal, "unit vector"),
                                 ("grid/arc_cm", t.grid.arc_cm, "cm along the spine from the glottis"),
                                 ("grid/distance_cm", af.distance_cm, "cm (inner contour to wall)"),
                                 ("grid/inner_s_cm", af.inner_s_cm, "cm along each line"),
                                 ("grid/wall_s_cm", af.wall_s_cm, "cm along each line"),
                                 ("midline_cm", af.midline_cm, "cm")]:
            f.create_dataset(name, data=data, compression="gzip" if np.ndim(data) > 1 else None).attrs["units"] = unit
        if t.band_area_cm2 is not None:
            f.create_dataset("band/area_cm2", data=t.band_area_cm2, compression="gzip").attrs["units"] = (
                "cm^2 (frames x grid lines): the band |z| <= band/z_cm[-1] from the 3-D geometry")
            f.create_dataset("band/z_cm", data=t.band_z_cm).attrs["units"] = "cm"
        for name, data in t.contours.items():
            f.create_dataset(f"contours/{name}", data=data, compression="gzip").attrs["units"] = "cm (frames x points x 2)"
        for name, data in t.fixed.items():
            f.create_dataset(f"contours/fixed/{name}", data=data).attrs["units"] = "cm"


def read(path: Path | str) -> Tracts:
    with open_artifact(path, "vocal-tract", STAGE.hint) as f:
        try:
            names = tuple(str(n) for n in f.attrs["region_names"])
            af = AreaFunctions(length_cm=f["length_cm"][()], area_cm2=f["area_cm2"][()],
                               region=f["section_region"][()], region_names=names,
                               distance_cm=f["grid/distance_cm"][()], inner_s_cm=f["grid/inner_s_cm"][()],
                               wall_s_cm=f["grid/wall_s_cm"][()], midline_cm=f["midline_cm"][()])
            grid = Grid(origin=f["grid/origin_cm"][()], normal=f["grid/normal"][()], arc_cm=f["grid/arc_cm"][()],
                        region=af.region[:f["grid/origin_cm"].shape[0]], reach_cm=float("nan"))
            controls = {"velum_port_cm2": f["velum_port_cm2"][()], "lip_area_cm2": f["lips/area_cm2"][()],
                        "lip_length_cm": f["lips/length_cm"][()], "glottis_cm2": f["glottis_cm2"][()]}
            contours = {k: v[()] for k, v in f["contours"].items() if k != "fixed"}
            fixed = {k: v[()] for k, v in f["contours/fixed"].items()}
            band = f["band/area_cm2"][()] if "band" in f else None
            band_z = f["band/z_cm"][()] if "band" in f else None
            return Tracts(time_s=f["time"][()], af=af, controls=controls, grid=grid, contours=contours, fixed=fixed,
                          band_area_cm2=band, band_z_cm=band_z)
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {STAGE.hint}") from None


def write_csv(path: Path | str, t: Tracts, frame: int) -> Path:
    """One frame as the tube format: ``length_cm,area_cm2`` rows from the glottis."""
    rows = "\n".join(f"{length:.6g},{area:.6g}" for length, area in zip(t.af.length_cm[frame], t.af.area_cm2[frame]))
    with atomic_path(path) as tmp:
        Path(tmp).write_text("length_cm,area_cm2\n" + rows + "\n")
    return Path(path)


def pick_frame(t: Tracts | int, frame: int | None) -> int:
    """``frame`` (negative counts from the end; None: the last), checked against the tracts (or a count)."""
    n = t if isinstance(t, int) else t.n_frames
    k = n - 1 if frame is None else int(frame)
    if not -n <= k < n:
        raise ArticError(f"--frame {frame} is out of range: the file has {n} frames (0 to {n - 1}); give one of them")
    return k % n


# --- the sources of shapes ------------------------------------------------------------------------------

def _check_simulation(sim, sim_path, mesh_sha: str, cfg: Config) -> None:
    inputs = json.loads(sim.attrs.get("inputs_json", "{}") or "{}")
    if inputs.get("mesh") != mesh_sha:
        raise ArticError(f"{sim_path} was simulated on another mesh than the one given (hash mismatch); rerun "
                         "'artic simulate' on this mesh, or give the mesh it was made from with --mesh")
    sections = simulate_stage.TONGUE_SECTIONS if sim.attrs.get("tongue_only") else ARTICULATOR_SECTIONS
    if sim.attrs.get("config_sections_sha256") != sections_hash(cfg, sections):
        raise ArticError(f"{sim_path} was simulated with another config (its {', '.join(sections)} sections differ); "
                         "rerun 'artic simulate' with this config, or give its config with --config")


@dataclass
class TractResult:
    path: Path
    tracts: Tracts
    up_to_date: bool = False


def vocal_tract(sim: Path | str | None = None, rest: bool = False, ep: str | None = None,
                epmaps: Path | str = paths.EPMAPS, mesh: Path | str = paths.MESH,
                config: Path | str | None = None, out: Path | str | None = None,
                lip_area: float | None = None, lip_length: float | None = None, velum_port: float | None = None,
                force: bool = False, frame: int | None = None) -> TractResult:
    """The tracts of a simulation's frames (``sim``), of the rest posture (``rest``) or of one EP (``ep``);
    written to ``out`` (HDF5).  A file that already holds this recipe is read back, not recomputed.
    ``frame``: the frame the caller will use, checked before anything is written."""
    if sum(x is not None and x is not False for x in (sim, ep)) + bool(rest) != 1:
        raise ArticError("give exactly one of --sim FILE, --rest or --ep JAW:MUSCLE=N")
    overrides = check_overrides(lip_area, lip_length, velum_port)
    cfg = load_config(config)
    vt = speaker_tract(STAGE.view(cfg))
    m = mesh_stage.read(mesh, cfg)
    params = {"controls": {k: v for k, v in overrides.items() if v is not None}}
    entries: list[TractEntry] = []
    if sim is not None:
        s = simulate_stage.read(sim)
        _check_simulation(s, sim, m.content_sha256, cfg)
        text = str(s.attrs.get("schedule_yaml", "") or "")
        sched: Schedule = parse_schedule(load_yaml(text) if text else {}, f"{sim} (its schedule)",
                                         cfg.muscles.max_force_n)
        entries = sched.tract
        out = Path(out) if out is not None else paths.TRACTS / f"{Path(sim).stem}.h5"
        prov = STAGE.provenance(cfg, sections=TRACT_SECTIONS, params=params,
                                inputs={"simulation": str(s.attrs.get("content_sha256", "")), "mesh": m.content_sha256,
                                        "tract_controls": digest([e.model_dump(mode="json") for e in entries])})
    elif rest:
        out = Path(out) if out is not None else paths.TRACT_REST
        prov = STAGE.provenance(cfg, sections=(*ARTICULATOR_SECTIONS, "vocal_tract"), params=params,
                                inputs={"mesh": m.content_sha256})
    else:
        from . import epmap as epmap_stage

        maps = epmap_stage.read(epmaps, mesh)
        parse_ep(ep)
        stem = ep.replace(":", "_").replace("=", "").replace(",", "_")
        out = Path(out) if out is not None else paths.TRACTS / f"ep_{stem}.h5"
        prov = STAGE.provenance(cfg, params=dict(params, ep=ep), inputs={"mesh": m.content_sha256, "epmaps":
                                                                        str(maps.attrs.get("content_sha256", ""))})
    if not force and up_to_date(out, prov):
        done = read(out)
        pick_frame(done, frame)
        return TractResult(Path(out), done, up_to_date=True)
    if sim is not None:
        pick_frame(len(s.time_s), frame)
    else:
        pick_frame(1, frame)
    extra = {}
    if sim is not None:
        shapes = shapes_of_simulation(s, m.mesh)
        extra["source"] = f"simulation {sim}"
    elif rest:
        shapes = rest_shapes(simulate_stage.build(cfg, m.mesh, m.wall))
        extra["source"] = "rest posture"
    else:
        model = simulate_stage.build(cfg, m.mesh, m.wall)
        state, forces = map_ep_state(model, maps, ep, STAGE.view(cfg).epmap)
        shapes = shapes_of_model(model, state.x[None], np.zeros(1))
        extra["source"] = f"EP {ep}"
        extra["forces_json"] = json.dumps(forces, sort_keys=True)
    tracts = tracts_of(vt, STAGE.view(cfg).speaker.wall, shapes, controls_for(vt, shapes.time_s, entries, overrides))
    extra["area_law_source"] = vt.area_law_source
    write(out, tracts, prov, extra)
    return TractResult(Path(out), tracts)


__all__ = ["STAGE", "Tracts", "read", "vocal_tract", "write", "write_csv", "pick_frame"]
