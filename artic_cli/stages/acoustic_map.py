"""Stage ``acoustic-map``: the EP maps made acoustic, each EP's area function and formants.

Every EP of ``artic ep-map`` keeps its whole shape; this stage turns each shape into a vocal tract (the
config's lip tube and port defaults) and its formants F1-F4, net by net (a net's EPs are one batch of
frames).  The maps' reach in the F1-F2 plane is the model's vowel space.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..config import load_config
from ..control.acoustic_map import AcousticMaps, acoustic_maps, lip_key
from ..errors import ArticError
from ..io.store import atomic_h5, open_artifact, read_array, stored_content_hash
from ..tract.formants import NetAcoustics
from . import epmap as epmap_stage
from . import mesh as mesh_stage
from . import paths
from .base import Stage, up_to_date

STAGE = Stage(name="acousticmaps", module=__name__, sections=("speaker", "vocal_tract", "acoustics"),
              reads=("mesh", "epmaps"), kind="acoustic-map", hint="rerun 'artic acoustic-map'")


def compute(cfg, mesh, maps, progress: Callable[[int, int], None] | None = None, jaws: list[str] | None = None,
            overrides: dict | None = None, mapped_lips: bool = False, jobs: int = 1,
            bandwidths: bool = True) -> AcousticMaps:
    """The acoustic maps of ``maps`` (:func:`artic_cli.control.acoustic_map.acoustic_maps`)."""
    return acoustic_maps(cfg, mesh, maps, progress, jaws, overrides, mapped_lips, jobs, bandwidths)


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


def acoustic_map(maps: Path | str = paths.EPMAPS, mesh: Path | str = paths.MESH,
                 config: Path | str | None = None, out: Path | str = paths.ACOUSTIC_MAPS,
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
