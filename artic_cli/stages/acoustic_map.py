"""Stage ``acoustic-map``: the EP maps made acoustic, each EP's area function and formants.

Every EP of ``artic ep-map`` keeps its whole shape; this stage turns each shape into a vocal tract (the
config's lip tube and port defaults) and its formants F1-F4, net by net (a net's EPs are one batch of
frames).  The maps' reach in the F1-F2 plane is the model's vowel space.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..acoustics.tube import Tube
from ..config import load_config
from ..errors import ArticError
from ..io.store import atomic_h5, open_artifact, read_array, stored_content_hash
from ..parallel import Sweep, run_sweep
from . import acoustics as acoustics_stage
from . import epmap as epmap_stage
from . import mesh as mesh_stage
from . import vocal_tract as vt_stage
from .base import Stage, up_to_date

STAGE = Stage(name="acousticmaps", module=__name__, sections=("speaker", "vocal_tract", "acoustics"),
              reads=("mesh", "epmaps"), kind="acoustic-map", hint="rerun 'artic acoustic-map'")
FORMANTS = 4

# male Japanese vowel averages (F1, F2 Hz; ../shared/reference/acoustics.md, Jo Chul-Ho's thesis, Table 4.3)
JAPANESE_VOWELS = {"a": (753.0, 1385.0), "i": (315.0, 2172.0), "u": (367.0, 1332.0), "e": (500.0, 1947.0),
                   "o": (520.0, 997.0)}


@dataclass
class NetAcoustics:
    formants_hz: np.ndarray  # (*grid, 4)
    bandwidths_hz: np.ndarray  # (*grid, 4)
    area_cm2: np.ndarray  # (*grid, sections)
    length_cm: np.ndarray  # (*grid, sections)
    min_area_cm2: np.ndarray  # (*grid,)


@dataclass
class AcousticMaps:
    jaws: dict[str, dict[str, NetAcoustics]]  # jaw -> "rest" | "single/SG" | "pair/SG+HG" ... -> acoustics
    attrs: dict = field(default_factory=dict)
    # the config's other mapped lip tubes: (area cm^2, length cm) -> jaw -> net key -> formants (*grid, 4), Hz
    lips: dict[tuple[float, float], dict[str, dict[str, np.ndarray]]] = field(default_factory=dict)

    def formants_with(self, jaw: str, area_cm2: float, length_cm: float) -> dict[str, np.ndarray] | None:
        """Every EP's formants at ``jaw`` with that lip tube, if the maps hold it (None otherwise)."""
        held = self.lips.get(lip_key(area_cm2, length_cm))
        return None if held is None or jaw not in held else held[jaw]

    def points(self, jaw: str) -> np.ndarray:
        """(P, 4) every EP's formants at a jaw position (the rest first)."""
        return np.concatenate([n.formants_hz.reshape(-1, FORMANTS) for n in self.jaws[jaw].values()])

    def points_with_lips(self) -> dict[tuple[float, float], np.ndarray]:
        """(area cm^2, length cm) -> (P, 4) every EP's formants at every jaw position with that mapped lip tube."""
        return {key: np.concatenate([f.reshape(-1, FORMANTS) for nets in jaws.values() for f in nets.values()])
                for key, jaws in self.lips.items()}


def lip_key(area_cm2: float, length_cm: float) -> tuple[float, float]:
    """How a lip tube is looked up (cm^2, cm; rounded to 1e-6)."""
    return round(float(area_cm2), 6), round(float(length_cm), 6)


def net_acoustics(vt, cfg, mesh, model_rest: np.ndarray, mandible_nodes: np.ndarray, shapes: np.ndarray,
                  overrides: dict | None = None, bandwidths: bool = True) -> NetAcoustics:
    """Tracts and formants of a grid of shapes (*grid, N, 3); ``overrides``: lip tube and port controls;
    ``bandwidths=False``: NaN bandwidths (the formants in two thirds of the time)."""
    grid = shapes.shape[:-2]
    flat = shapes.reshape(-1, *shapes.shape[-2:]).astype(float)
    sh = vt_stage.shapes_of(flat, np.zeros(len(flat)), mesh, model_rest, mandible_nodes)
    t = vt_stage.compute(vt, cfg.speaker.wall, sh, vt_stage.controls_for(vt, sh.time_s, overrides=overrides))
    tubes = [Tube(t.af.length_cm[k], t.af.area_cm2[k]) for k in range(t.n_frames)]
    ports = acoustics_stage.port_positions(t)
    ac = acoustics_stage.compute(tubes, cfg, velum_area_cm2=t.controls["velum_port_cm2"], port_from_glottis_cm=ports,
                                 spectra=False, bandwidths=bandwidths)
    return NetAcoustics(formants_hz=ac.formants_hz[:, :FORMANTS].reshape(*grid, FORMANTS),
                        bandwidths_hz=ac.bandwidths_hz[:, :FORMANTS].reshape(*grid, FORMANTS),
                        area_cm2=t.af.area_cm2.reshape(*grid, -1), length_cm=t.af.length_cm.reshape(*grid, -1),
                        min_area_cm2=t.af.area_cm2.min(axis=1).reshape(grid))


def _net_task(cfg, mesh, model_rest: np.ndarray, mandible_nodes: np.ndarray, shapes: np.ndarray,
              settings: list[dict | None], bandwidths: bool = True) -> list[NetAcoustics]:
    """One net's acoustics with each lip and port setting (one task: its shapes travel once); bandwidths with
    the first setting only (the mapped lip tubes keep their formants)."""
    vt = vt_stage.speaker_tract(cfg)
    return [net_acoustics(vt, cfg, mesh, model_rest, mandible_nodes, shapes, over, bandwidths=bandwidths and k == 0)
            for k, over in enumerate(settings)]


def compute(cfg, mesh, maps, progress: Callable[[int, int], None] | None = None, jaws: list[str] | None = None,
            overrides: dict | None = None, mapped_lips: bool = False, jobs: int = 1,
            bandwidths: bool = True) -> AcousticMaps:
    """Every EP's acoustics (``jaws``: those jaw positions only; ``overrides``: lip tube and port;
    ``mapped_lips``: also the formants with each of ``vocal_tract.mapped_lips``, the config's port), net by
    net on ``jobs`` workers (``progress``: nets done); ``bandwidths=False``: formants only."""
    vt = vt_stage.speaker_tract(cfg)
    if maps.model_rest is None or any(jm.rest_shape is None for jm in maps.jaws.values()):
        raise ArticError("the EP maps keep no shapes (an older artic built them); rerun 'artic ep-map'")
    chosen = {j: jm for j, jm in maps.jaws.items() if jaws is None or j in jaws}
    nets = [(jname, "rest", jm.rest_shape[None]) for jname, jm in chosen.items()]
    for jname, jm in chosen.items():
        for fam in ("single", "pair", "group"):
            for name, net in getattr(jm, fam).items():
                nets.append((jname, f"{fam}/{name}", net.shapes))
    settings = [(None, overrides)] + [
        (lip_key(lp.area_cm2, lp.length_cm), {"lip_area_cm2": float(lp.area_cm2), "lip_length_cm": float(lp.length_cm),
                                              "velum_port_cm2": float(vt.velum_port_cm2)})
        for lp in (vt.mapped_lips if mapped_lips else [])]
    overs = [over for _, over in settings]
    calls = [(cfg, mesh, maps.model_rest, maps.mandible_nodes, shapes, overs, bandwidths) for _, _, shapes in nets]
    if jobs > 1:
        done = run_sweep(_net_task, calls, Sweep(jobs=jobs, progress=progress)).results
    else:
        done = []
        for k, call in enumerate(calls):
            if progress is not None:
                progress(k, len(calls))
            done.append(_net_task(*call))
        if progress is not None:
            progress(len(calls), len(calls))
    out: dict[str, dict[str, NetAcoustics]] = {j: {} for j in chosen}
    held: dict[tuple[float, float], dict[str, dict[str, np.ndarray]]] = {}
    for (jname, key, _), results in zip(nets, done):
        for (lips, _), res in zip(settings, results):
            if lips is None:
                out[jname][key] = res
            else:
                held.setdefault(lips, {j: {} for j in chosen})[jname][key] = res.formants_hz
    return AcousticMaps(jaws=out, lips=held)


def write(path: Path | str, result: AcousticMaps, prov=None) -> None:
    with atomic_h5(path, STAGE.kind, prov) as f:
        f.attrs["layout"] = ("jaw_positions/<jaw>/<rest | single/M | pair/A+B | group/I+A+B>/{formants_hz, "
                             "bandwidths_hz (*grid x 4), area_cm2, length_cm (*grid x sections, glottis first), "
                             "min_area_cm2}: the grids of the EP maps' nets")
        f.attrs["jaw_order"] = list(result.jaws)
        f.attrs["lips_layout"] = ("lips/<k>/<jaw>/<net key>/formants_hz: the formants with lip tube k (its attrs: "
                                  "area_cm2, length_cm; the config's port)")
        for k, ((area, length), jaws) in enumerate(result.lips.items()):
            lg = f.create_group(f"lips/{k}")
            lg.attrs["area_cm2"], lg.attrs["length_cm"] = area, length
            for jname, nets in jaws.items():
                for key, fm in nets.items():
                    lg.create_dataset(f"{jname}/{key}/formants_hz", data=fm).attrs["units"] = "Hz"
        for jname, nets in result.jaws.items():
            g = f.create_group(f"jaw_positions/{jname}")
            g.attrs["order"] = list(nets)
            for key, n in nets.items():
                h = g.create_group(key)
                for name, data, unit in (("formants_hz", n.formants_hz, "Hz"), ("bandwidths_hz", n.bandwidths_hz, "Hz"),
                                         ("area_cm2", n.area_cm2, "cm^2"), ("length_cm", n.length_cm, "cm"),
                                         ("min_area_cm2", n.min_area_cm2, "cm^2")):
                    h.create_dataset(name, data=data, compression="gzip").attrs["units"] = unit


def read(path: Path | str, formants_only: bool = False) -> AcousticMaps:
    """The acoustic maps; ``formants_only``: each EP's formants, the rest of a net's record left empty (what
    a formant target is solved on, in a fifth of the time)."""
    keep = ("formants_hz",) if formants_only else ("formants_hz", "bandwidths_hz", "area_cm2", "length_cm",
                                                   "min_area_cm2")
    empty = np.zeros(0)
    with open_artifact(path, STAGE.kind, STAGE.hint) as f:
        try:
            jaws = {}
            for jname in f.attrs["jaw_order"]:
                g = f["jaw_positions"][jname]
                jaws[str(jname)] = {}
                for k in g.attrs["order"]:
                    h = g[k]
                    got = {d: read_array(h, d) if d in keep else empty for d in (
                        "formants_hz", "bandwidths_hz", "area_cm2", "length_cm", "min_area_cm2")}
                    jaws[str(jname)][str(k)] = NetAcoustics(**got)
            lips = {}
            for lg in (f["lips"].values() if "lips" in f else ()):
                lips[lip_key(lg.attrs["area_cm2"], lg.attrs["length_cm"])] = {
                    str(j): {k: read_array(lg, f"{j}/{k}/formants_hz") for k in jaws[str(j)]} for j in lg}
            return AcousticMaps(jaws=jaws, attrs={k: v for k, v in f.attrs.items()}, lips=lips)
        except (KeyError, ValueError, OSError, TypeError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {STAGE.hint}") from None


@dataclass
class AcousticMapResult:
    path: Path
    maps: AcousticMaps
    up_to_date: bool = False


def acoustic_map(maps: Path | str = "data/epmaps.h5", mesh: Path | str = "data/mesh.h5",
                 config: Path | str | None = None, out: Path | str = "data/acoustic_maps.h5",
                 progress: Callable[[int, int], None] | None = None, force: bool = False,
                 jobs: int = 2) -> AcousticMapResult:
    """The formants of every EP of the maps (left alone when ``out`` holds this recipe), on ``jobs`` workers."""
    cfg = load_config(config)
    m = mesh_stage.read(mesh, cfg)
    ep = epmap_stage.read(maps, mesh)
    out = Path(out)
    prov = STAGE.provenance(cfg, inputs={"mesh": m.content_sha256, "epmaps": str(stored_content_hash(maps))})
    if not force and up_to_date(out, prov):
        return AcousticMapResult(out, read(out), up_to_date=True)
    result = compute(cfg, m.mesh, ep, progress, mapped_lips=True, jobs=jobs)
    write(out, result, prov)
    return AcousticMapResult(out, result)
