"""Stage ``dynamic``: the map of any jaw position from the typical one (section IV.B.3, Table IV)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..control.dynamic import DynamicMap, fit_dynamic_map
from ..control.epmap import EPMaps
from ..errors import ArticError
from ..io.store import atomic_h5, content_hash_of, open_artifact
from . import epmap as epmap_stage
from . import paths
from .base import Stage, up_to_date

STAGE = Stage(name="dynamic", module=__name__, sections=(), reads=("epmaps",), kind="dynamic-map",
              hint="rebuild it with 'artic dynamic-map'")


def compute(maps: EPMaps) -> DynamicMap:
    return fit_dynamic_map(maps)


def write(path: Path | str, dm: DynamicMap, prov=None) -> None:
    with atomic_h5(path, STAGE.kind, prov) as f:
        f.attrs.update({"typical_jaw": dm.typical, "jaw_forces_n": json.dumps(dm.jaw_forces),
                        "rest_height_cm": dm.rest_height,
                        "model": "x' = R(theta) (x - centre) + centre + shift per control point; theta and shift "
                                 "piecewise linear in the jaw's incisor height"})
        f.create_dataset("jaw_positions", data=np.array(dm.jaws, dtype="S"))
        for name, data, unit in (("incisor_height", dm.height, "cm"), ("jaw_angle", np.degrees(dm.angle), "deg"),
                                 ("theta", np.degrees(dm.theta), "deg, columns tip, dorsum"),
                                 ("shift", dm.shift, "cm, (jaw, control point, xy)"),
                                 ("centre", dm.centre, "cm, (control point, xy)"),
                                 ("error_mean", dm.error_mean, "cm"), ("error_max", dm.error_max, "cm"),
                                 ("loo_error_mean", dm.loo_error_mean, "cm, leave-one-out"),
                                 ("points", dm.points, "EPs compared")):
            f.create_dataset(name, data=data).attrs["units"] = unit


def read(path: Path | str, maps_path: Path | str | None = None) -> DynamicMap:
    """The dynamic map; with ``maps_path``, checks it was derived from those maps' content."""
    hint = STAGE.hint
    maps_sha = None if maps_path is None else content_hash_of(maps_path, "epmap", epmap_stage.STAGE.hint)
    with open_artifact(path, STAGE.kind, hint) as f:
        try:
            if maps_sha is not None and json.loads(f.attrs["inputs_json"]).get("epmaps") != maps_sha:
                raise ArticError(f"{path} was derived from other EP maps than {maps_path}; {hint}")
            return DynamicMap(typical=str(f.attrs["typical_jaw"]),
                              jaws=[j.decode() for j in f["jaw_positions"][()]],
                              jaw_forces=json.loads(f.attrs["jaw_forces_n"]), height=f["incisor_height"][()],
                              angle=np.radians(f["jaw_angle"][()]), theta=np.radians(f["theta"][()]),
                              shift=f["shift"][()], centre=f["centre"][()], error_mean=f["error_mean"][()],
                              error_max=f["error_max"][()], loo_error_mean=f["loo_error_mean"][()],
                              points=f["points"][()], rest_height=float(f.attrs["rest_height_cm"]))
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {hint}") from None


def _provenance(maps: Path | str):
    return STAGE.provenance(None, inputs={"epmaps": content_hash_of(maps, "epmap", epmap_stage.STAGE.hint)})


def fresh_recipe(maps: Path | str, out: Path | str) -> bool:
    """Whether ``out`` already holds the dynamic map of ``maps``."""
    return up_to_date(out, _provenance(maps))


def build_dynamic_map(maps: Path | str = paths.EPMAPS, out: Path | str = paths.DYNAMIC) -> DynamicMap:
    """Fit the dynamic map to an EP-map file; ``out`` is left alone when it already holds this recipe."""
    prov = _provenance(maps)
    if up_to_date(out, prov):
        return read(out)
    dm = compute(epmap_stage.read(maps))
    write(out, dm, prov)
    return dm


load_dynamic_map = read
