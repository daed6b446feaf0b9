"""Stage ``vocal-tract``: area functions from simulated shapes (the paper's section II.A).

For every frame of a simulation (or the rest posture, or one EP of an EP-map file) the tongue's
midsagittal surface and the mandible's rigid motion place the tract's contours
(:mod:`artic_cli.geometry.tract`); the grid lines read the distances and the power laws give the areas
(:mod:`artic_cli.acoustics.area_function`); the lip tube and the velopharyngeal port are control inputs
(the config's defaults, a schedule's ``tract`` entries, or options).  ``compute`` takes objects, ``write``
and ``read`` are the file, ``vocal_tract`` is what the CLI and ``make`` call.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from ..acoustics.area_function import AreaFunctions, area_functions, band_areas, segments
from ..config import Config, VocalTract, load_config
from ..errors import ArticError
from ..geometry.tract import Grid, inner_polylines, moving_parts, outer_at, outer_contour, tract_grid
from ..io.fingerprint import digest, sections_hash
from ..io.store import Provenance, atomic_h5, atomic_path, open_artifact
from ..mechanics.contact import rigid_motion
from ..mechanics.model import ARTICULATOR_SECTIONS
from ..schedule import Schedule, TractEntry, parse_schedule, tract_controls
from ..validation import check_number
from . import mesh as mesh_stage
from . import simulate as simulate_stage
from .base import Stage, up_to_date

STAGE = Stage(name="tracts", module=__name__, sections=(*ARTICULATOR_SECTIONS, "epmap", "vocal_tract"),
              reads=("mesh", "sims", "epmaps"), kind="vocal-tract", hint="rerun 'artic vocal-tract'")
TRACT_SECTIONS = ("speaker", "vocal_tract")  # what a simulation's tracts read of the config


def speaker_tract(cfg: Config) -> VocalTract:
    vt = STAGE.view(cfg).vocal_tract
    if vt is None:
        raise ArticError("the config has no 'vocal_tract' section; add one (see configs/default.yaml)")
    return vt


@dataclass
class Shapes:
    """What the tract needs of the articulators, frame by frame (cm)."""

    time_s: np.ndarray  # (F,)
    tongue_cm: np.ndarray  # (F, n, 2) the tongue's midsagittal surface, tip first
    jaw_rotation: np.ndarray  # (F, 3, 3) the mandible's rigid motion from its rest
    jaw_translation: np.ndarray  # (F, 3)
    tongue_lateral_cm: np.ndarray | None = None  # (F, n, 2) the surface in the parasagittal plane at +lateral_z_cm
    lateral_z_cm: float = 0.0
    root_shift_cm: np.ndarray | None = None  # (F, 2) the root's lowest surface node (the vallecula) from its rest


def surface_nodes(mesh) -> tuple[np.ndarray, np.ndarray]:
    """The tongue's surface nodes, tip first: in the midsagittal plane and in the left (+z) plane."""
    rows = np.asarray(mesh.node_sets["surface"]).reshape(-1, 3)  # (radial lines, planes -z / 0 / +z)
    return rows[:, 1], rows[:, 2]


def shapes_of(positions: np.ndarray, time_s: np.ndarray, mesh, rest: np.ndarray | None,
              mandible: np.ndarray | None) -> Shapes:
    """Shapes from node positions (F, N, 3): the surface nodes (tip first) in the midsagittal and the left
    plane, the root's lowest node and the mandible's nodes against their rest (no rest: the mesh's nodes;
    no mandible: the jaw stays at rest)."""
    mid, lateral = surface_nodes(mesh)
    f = len(positions)
    rot = np.broadcast_to(np.eye(3), (f, 3, 3)).copy()
    tr = np.zeros((f, 3))
    ref = np.asarray(mesh.nodes if rest is None else rest, float)
    if mandible is not None and len(mandible) >= 3 and rest is not None:
        for k in range(f):
            rot[k], tr[k] = rigid_motion(rest[mandible], positions[k, mandible])
    return Shapes(time_s=np.asarray(time_s, float), tongue_cm=positions[:, mid, :2].copy(), jaw_rotation=rot,
                  jaw_translation=tr, tongue_lateral_cm=positions[:, lateral, :2].copy(),
                  lateral_z_cm=float(np.mean(mesh.nodes[lateral, 2])),
                  root_shift_cm=positions[:, mid[-1], :2] - ref[mid[-1], :2])


@dataclass
class Tracts:
    """Area functions of F frames with what made them."""

    time_s: np.ndarray
    af: AreaFunctions
    controls: dict[str, np.ndarray]  # lip_area_cm2, lip_length_cm, velum_port_cm2: (F,)
    grid: Grid
    contours: dict[str, np.ndarray]  # moving parts (F, n, 2): tongue, lower_incisor, lower_lip
    fixed: dict[str, np.ndarray] = field(default_factory=dict)  # fixed parts (n, 2)
    band_area_cm2: np.ndarray | None = None  # (F, L) the central band |z| <= band_z_cm[-1] from the 3-D geometry
    band_z_cm: np.ndarray | None = None

    @property
    def n_frames(self) -> int:
        return len(self.time_s)


@dataclass(frozen=True)
class Fixed:
    """What does not move: the grid and the outer contour's segments in each plane (cm)."""

    grid: Grid
    outer: dict[float, np.ndarray]  # z -> (S, 2, 2)
    drawn: dict[str, np.ndarray]


_FIXED: dict[tuple, tuple] = {}


def fixed_geometry(vt: VocalTract, cfg_wall, planes_z: tuple[float, ...] = (0.0,)) -> Fixed:
    """The fixed geometry, built once per tract, wall and set of planes (the config objects are kept with
    it, so their ids stay theirs)."""
    key = (id(vt), id(cfg_wall), tuple(planes_z))
    if key not in _FIXED:
        fixed = outer_contour(vt, cfg_wall)
        drawn = dict(fixed, upper_lip=np.asarray(vt.upper_lip_cm, float),
                     velum_nasal=np.asarray(vt.velum_nasal_surface_cm, float))
        outer = {float(z): segments(list(outer_at(vt, cfg_wall, float(z)))) for z in planes_z}
        if len(_FIXED) > 8:
            _FIXED.clear()
        _FIXED[key] = (Fixed(grid=tract_grid(vt), outer=outer, drawn=drawn), vt, cfg_wall)
    return _FIXED[key][0]


def band_planes(shapes: Shapes) -> tuple[float, ...]:
    """The planes the band is integrated over: midsagittal, half-way, the tongue's lateral plane (cm)."""
    w = shapes.lateral_z_cm
    return (0.0, 0.5 * w, w) if shapes.tongue_lateral_cm is not None and w > 0 else (0.0,)


def compute(vt: VocalTract, cfg_wall, shapes: Shapes, controls: dict[str, np.ndarray]) -> Tracts:
    """The tracts of every frame; a line that misses the tract's contours is an error naming the frame."""
    geo = fixed_geometry(vt, cfg_wall, band_planes(shapes))
    grid = geo.grid
    back = geo.drawn["pharynx"]
    moving = moving_parts(vt, shapes.tongue_cm, shapes.jaw_rotation, shapes.jaw_translation, shapes.root_shift_cm,
                          back)
    inner = segments(inner_polylines(vt, moving))
    outer = geo.outer[0.0]
    law = vt.area_law
    af = area_functions(grid, inner, outer, np.array([r.alpha for r in law]), np.array([r.beta for r in law]),
                        tuple(r.name for r in law), controls["lip_length_cm"], controls["lip_area_cm2"],
                        vt.lip_sections, vt.grid.penetration_cm, moving["tongue"], vt.grid.touch_cm)
    missing_wall = np.flatnonzero(np.isnan(af.wall_s_cm))
    if len(missing_wall):
        k = int(missing_wall[0])
        raise ArticError(f"grid line {k} ({grid.arc_cm[k]:.2f} cm from the glottis) misses the tract's wall; "
                         "move vocal_tract.grid.spine_cm inside the rest tract or raise grid.reach_cm")
    bad = np.argwhere(np.isnan(af.distance_cm))
    if len(bad):
        fr, k = (int(v) for v in bad[0])
        raise ArticError(f"frame {fr} (t = {shapes.time_s[fr]:.3f} s): the midline cannot be traced, grid line {k} "
                         f"({grid.arc_cm[k]:.2f} cm from the glottis) meets no tongue or larynx within "
                         f"{grid.reach_cm:g} cm; the shape left the grid (raise vocal_tract.grid.reach_cm)")
    band, z = None, None
    if len(geo.outer) > 1:
        band, z = band_area(vt, geo, shapes, af, inner)
    return Tracts(time_s=shapes.time_s, af=af, controls=controls, grid=grid, contours=moving, fixed=dict(geo.drawn),
                  band_area_cm2=band, band_z_cm=z)


def band_area(vt: VocalTract, geo: Fixed, shapes: Shapes, af: AreaFunctions, inner_mid: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """The cross-section of the band the tongue mesh spans (|z| <= its lateral planes) from the 3-D geometry:
    distances in the midsagittal plane (``inner_mid``: its inner segments, already built), half-way and in the
    lateral plane, integrated across."""
    z = np.array(list(geo.outer))
    side = [0.5 * (shapes.tongue_cm + shapes.tongue_lateral_cm), shapes.tongue_lateral_cm]
    inners = [inner_mid] + [segments(inner_polylines(vt, moving_parts(vt, tongue, shapes.jaw_rotation,
                                                                      shapes.jaw_translation, shapes.root_shift_cm,
                                                                      geo.drawn["pharynx"])))
                            for tongue in side]
    return band_areas(geo.grid, inners, list(geo.outer.values()), z, af.inner_s_cm, af.wall_s_cm), z


def default_controls(vt: VocalTract) -> dict[str, float]:
    return {"lip_area_cm2": vt.lips.area_cm2, "lip_length_cm": vt.lips.length_cm, "velum_port_cm2": vt.velum_port_cm2}


def controls_for(vt: VocalTract, time_s: np.ndarray, entries: list[TractEntry] | None = None,
                 overrides: dict[str, float | None] | None = None) -> dict[str, np.ndarray]:
    """The tract controls per frame: the config's defaults, overridden by options, then a schedule's entries."""
    start = default_controls(vt)
    for k, v in (overrides or {}).items():
        if v is not None:
            start[k] = float(v)
    return tract_controls(entries or [], start, time_s)


def check_overrides(lip_area: float | None, lip_length: float | None, velum_port: float | None) -> dict:
    check_number("--lip-area", lip_area, ge=0, le=10, unit="cm^2")
    check_number("--lip-length", lip_length, gt=0, le=3, unit="cm")
    check_number("--velum-port", velum_port, ge=0, le=10, unit="cm^2")
    return {"lip_area_cm2": lip_area, "lip_length_cm": lip_length, "velum_port_cm2": velum_port}


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
                        "lip_length_cm": f["lips/length_cm"][()]}
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


def shapes_of_simulation(sim, mesh) -> Shapes:
    mandible = sim.parts.get("mandible")
    if mandible is not None and sim.rest_cm is None:
        raise ArticError("the simulation file records no rest positions (an older artic wrote it); rerun "
                         "'artic simulate'")
    return shapes_of(sim.positions_cm, sim.time_s, mesh, sim.rest_cm, mandible)


def rest_shapes(cfg: Config, m) -> Shapes:
    """The rest posture: the articulator settled under gravity (what every simulation starts from)."""
    from ..mechanics.simulate import settle

    model = simulate_stage.build(cfg, m.mesh, m.wall)
    st = settle(model)
    return shapes_of(st.x[None], np.zeros(1), m.mesh, model.rest, np.asarray(model.node_sets["mandible"]))


def parse_ep(spec: str) -> tuple[str, dict[str, float]]:
    """``JAW:MUSCLE=N[,MUSCLE=N]`` -> (jaw position, tongue forces)."""
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


def ep_shapes(cfg: Config, m, maps, spec: str) -> tuple[Shapes, dict[str, float]]:
    """The whole shape of one EP of the maps, recomputed by holding its forces (as the map did)."""
    from ..control.equilibrium import add_forces, equilibrium_state, jaw_rest

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
    model = simulate_stage.build(cfg, m.mesh, m.wall)
    start = jaw_rest(model, jm.forces)
    state, _ = equilibrium_state(model, start, add_forces(jm.forces, forces), STAGE.view(cfg).epmap)
    return shapes_of(state.x[None], np.zeros(1), m.mesh, model.rest,
                     np.asarray(model.node_sets["mandible"])), add_forces(jm.forces, forces)


@dataclass
class TractResult:
    path: Path
    tracts: Tracts
    up_to_date: bool = False


def vocal_tract(sim: Path | str | None = None, rest: bool = False, ep: str | None = None,
                epmaps: Path | str = "data/epmaps.h5", mesh: Path | str = "data/mesh.h5",
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
    vt = speaker_tract(cfg)
    m = mesh_stage.read(mesh, cfg)
    params = {"controls": {k: v for k, v in overrides.items() if v is not None}}
    entries: list[TractEntry] = []
    if sim is not None:
        s = simulate_stage.read(sim)
        _check_simulation(s, sim, m.content_sha256, cfg)
        text = str(s.attrs.get("schedule_yaml", "") or "")
        sched: Schedule = parse_schedule(yaml.safe_load(text) if text else {}, f"{sim} (its schedule)",
                                         cfg.muscles.max_force_n)
        entries = sched.tract
        out = Path(out) if out is not None else Path("data/tracts") / f"{Path(sim).stem}.h5"
        prov = STAGE.provenance(cfg, sections=TRACT_SECTIONS, params=params,
                                inputs={"simulation": str(s.attrs.get("content_sha256", "")), "mesh": m.content_sha256,
                                        "tract_controls": digest([e.model_dump(mode="json") for e in entries])})
    elif rest:
        out = Path(out) if out is not None else Path("data/tracts/rest.h5")
        prov = STAGE.provenance(cfg, sections=(*ARTICULATOR_SECTIONS, "vocal_tract"), params=params,
                                inputs={"mesh": m.content_sha256})
    else:
        from . import epmap as epmap_stage

        maps = epmap_stage.read(epmaps, mesh)
        parse_ep(ep)
        stem = ep.replace(":", "_").replace("=", "").replace(",", "_")
        out = Path(out) if out is not None else Path("data/tracts") / f"ep_{stem}.h5"
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
        shapes = rest_shapes(cfg, m)
        extra["source"] = "rest posture"
    else:
        shapes, forces = ep_shapes(cfg, m, maps, ep)
        extra["source"] = f"EP {ep}"
        extra["forces_json"] = json.dumps(forces, sort_keys=True)
    tracts = compute(vt, STAGE.view(cfg).speaker.wall, shapes, controls_for(vt, shapes.time_s, entries, overrides))
    extra["area_law_source"] = vt.area_law_source
    write(out, tracts, prov, extra)
    return TractResult(Path(out), tracts)


__all__ = ["STAGE", "Shapes", "Tracts", "compute", "controls_for", "outer_contour", "read", "vocal_tract", "write",
           "write_csv", "pick_frame"]
