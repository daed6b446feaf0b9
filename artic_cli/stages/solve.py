"""Stage ``solve``: a target file in, the force set out (section V), checked by simulation on request."""

from __future__ import annotations

from pathlib import Path

from ..config import load_config
from ..control.solver import TargetSpec
from ..control.targets import Context, load_target, solve
from ..control.verify import Simulator
from ..errors import UnreachableTarget
from ..io.fingerprint import digest
from ..io.store import content_hash_of, read_doc, write_doc
from ..mechanics.model import ARTICULATOR_SECTIONS
from . import dynamic as dynamic_stage
from . import epmap as epmap_stage
from . import mesh as mesh_stage
from .base import Stage, up_to_date

STAGE = Stage(name="solve", module=__name__, sections=(*ARTICULATOR_SECTIONS, "epmap"), reads=("epmaps", "dynamic"),
              kind="solution", hint="rerun 'artic solve-target TARGET.yaml'")


def load_context(maps: Path | str = "data/epmaps.h5", dynamic: Path | str | None = "data/dynamic.h5",
                 mesh: Path | str | None = None) -> Context:
    """The maps (checked against ``mesh``'s content when given) and the dynamic map (checked against the
    maps) a target is solved on."""
    m = epmap_stage.read(maps, mesh=mesh)
    dm = None
    if dynamic is not None and Path(dynamic).is_file():
        dm = dynamic_stage.read(dynamic, maps_path=maps)
    return Context(maps=m, dm=dm, maps_sha256=str(m.attrs.get("content_sha256", "")),
                   dynamic_sha256=None if dm is None else content_hash_of(dynamic, "dynamic-map",
                                                                           dynamic_stage.STAGE.hint))


def simulator(mesh: Path | str, config: Path | str | None = None) -> Simulator:
    cfg = load_config(config)
    m = mesh_stage.read(mesh, cfg)
    return Simulator(STAGE.view(cfg).full, m.mesh, m.wall, m.content_sha256)


def write(path: Path | str, doc: dict, prov=None) -> Path:
    return write_doc(path, doc, prov)


def read(path: Path | str) -> dict:
    return read_doc(path, "solution", STAGE.hint)


def solve_target(target: Path | str | TargetSpec, ctx: Context, out: Path | str | None = None,
                 sim: Simulator | None = None, verify: bool = False, refine: bool = False, budget: int = 8,
                 config: Path | str | None = None, mesh_sha256: str = "") -> tuple[dict, Path, bool]:
    """Solve one target; write the answer (also when it is unreachable: then UnreachableTarget is raised
    after writing).  Returns the document, its path and whether it was already up to date."""
    t = load_target(target) if not isinstance(target, TargetSpec) else target
    path = Path(out) if out is not None else Path("data/solutions") / f"{t.name}.yaml"
    cfg = load_config(config) if (verify or refine) else None
    inputs = {"epmaps": ctx.maps_sha256, "dynamic": ctx.dynamic_sha256, "target": digest(t.model_dump(mode="json"))}
    if verify or refine:
        inputs["mesh"] = mesh_sha256
    prov = STAGE.provenance(cfg, inputs=inputs, params={"verify": verify, "refine": refine, "budget": budget})
    if up_to_date(path, prov):
        doc = read(path)
        if "unreachable" in doc:
            raise UnreachableTarget(doc["unreachable"])
        return doc, path, True
    try:
        doc = solve(ctx, t, sim, verify, refine, budget)
    except UnreachableTarget as err:  # the answer is written too (make and scripts can report it)
        write(path, {"target": t.name, "unreachable": str(err)}, prov)
        raise
    write(path, doc, prov)
    return read(path), path, False
