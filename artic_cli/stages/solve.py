"""Stage ``solve``: a target file in, the force set out (section V), checked by simulation on request."""

from __future__ import annotations

from pathlib import Path


from ..config import load_config
from ..control.acoustic_map import EPFormants
from ..control.solver import TargetSpec
from ..control.targets import Context, load_target, solve
from ..control.tongue_tops import TongueTops
from ..control.verify import Simulator
from ..control.voicing import Voicer
from ..errors import ArticError, UnreachableTarget
from ..io.fingerprint import digest
from ..io.store import content_hash_of, read_doc, stored_content_hash, write_doc
from ..mechanics.model import ARTICULATOR_SECTIONS
from ..tract.places import section_places
from ..tract.speaker import speaker_tract
from . import acoustic_map as am_stage
from . import dynamic as dynamic_stage
from . import epmap as epmap_stage
from . import mesh as mesh_stage
from . import paths
from .base import Stage, up_to_date

SPATIAL_SECTIONS = (*ARTICULATOR_SECTIONS, "epmap", "solver")
STAGE = Stage(name="solve", module=__name__, sections=(*SPATIAL_SECTIONS, "vocal_tract", "acoustics"),
              reads=("epmaps", "dynamic"),
              kind="solution", hint="rerun 'artic solve-target TARGET.yaml'")


def load_context(maps: Path | str = paths.EPMAPS, dynamic: Path | str | None = paths.DYNAMIC,
                 mesh: Path | str | None = None) -> Context:
    """The maps (checked against ``mesh``'s content when given) and the dynamic map (checked against the
    maps) a target is solved on; the EPs' control points, not their whole shapes (``add_formants`` reads those
    when it needs them)."""
    m = epmap_stage.read(maps, mesh=mesh, shapes=False)
    dm = None
    if dynamic is not None and Path(dynamic).is_file():
        dm = dynamic_stage.read(dynamic, maps_path=maps)
    return Context(maps=m, dm=dm, maps_sha256=str(m.attrs.get("content_sha256", "")),
                   dynamic_sha256=None if dm is None else content_hash_of(dynamic, "dynamic-map",
                                                                           dynamic_stage.STAGE.hint))


def add_formants(ctx: Context, maps: Path | str, mesh: Path | str, config: Path | str | None = None,
                 acoustic_maps: Path | str | None = None) -> Context:
    """Give the context the formants of every EP (for acoustic targets, :class:`EPFormants`): the acoustic
    maps, checked fresh, and for other lips or ports the same computed from the EPs' shapes."""
    cfg = load_config(config)
    m = mesh_stage.read(mesh, cfg)
    stored = None
    if acoustic_maps is not None and Path(acoustic_maps).is_file():
        prov = am_stage.STAGE.provenance(cfg, inputs={"mesh": m.content_sha256,
                                                      "epmaps": str(stored_content_hash(maps))})
        if not up_to_date(acoustic_maps, prov):
            raise ArticError(f"{acoustic_maps} was made from other EP maps, mesh, config or code; "
                             "rerun 'artic acoustic-map' (or leave --acoustic-maps out)")
        stored = am_stage.read(acoustic_maps, formants_only=True)
        ctx.acoustic_sha256 = str(stored_content_hash(acoustic_maps))
    read_areas = (lambda: am_stage.read(acoustic_maps)) if stored is not None else None  # constriction targets
    oracle = EPFormants(cfg, m.mesh, lambda: epmap_stage.read(maps), stored, read_areas)
    ctx.formants, ctx.lips_default, ctx.port_default = oracle, oracle.defaults[:2], oracle.defaults[2]
    ctx.areas, ctx.places = oracle.areas, section_places(speaker_tract(cfg))
    ctx.tops = TongueTops(m.mesh, oracle.whole_maps)
    return ctx


def simulator(mesh: Path | str, config: Path | str | None = None, voiced: bool = False,
              hold_jaw: bool | None = None) -> Simulator | Voicer:
    """What checks answers: the forces run as ``artic simulate`` runs them (``hold_jaw``: the maps' held jaw;
    None: the config's ``solver.verify_hold_jaw``); ``voiced``: with the tract's formants too."""
    cfg = load_config(config)
    m = mesh_stage.read(mesh, cfg)
    sim = Simulator(STAGE.view(cfg).full, m.mesh, m.wall, m.content_sha256, hold_jaw)
    return Voicer(sim, cfg) if voiced else sim


def write(path: Path | str, doc: dict, prov=None) -> Path:
    return write_doc(path, doc, prov)


def read(path: Path | str) -> dict:
    return read_doc(path, "solution", STAGE.hint)


# what an unreachable spatial answer records of the nearest reachable point: the error's attribute -> the key
_NEAREST = {"nearest_cm": "nearest_distance_cm", "nearest_point_cm": "nearest_point_cm"}


def solve_target(target: Path | str | TargetSpec, ctx: Context, out: Path | str | None = None,
                 sim: Simulator | None = None, verify: bool = False, refine: bool = False, budget: int = 8,
                 config: Path | str | None = None, mesh_sha256: str = "") -> tuple[dict, Path, bool]:
    """Solve one target; write the answer (also when it is unreachable: then UnreachableTarget is raised
    after writing).  Returns the document, its path and whether it was already up to date."""
    t = load_target(target) if not isinstance(target, TargetSpec) else target
    path = Path(out) if out is not None else paths.SOLUTIONS / f"{t.name}.yaml"
    cfg = load_config(config) if (verify or refine) else None
    inputs = {"epmaps": ctx.maps_sha256, "dynamic": ctx.dynamic_sha256, "target": digest(t.model_dump(mode="json"))}
    if verify or refine or t.needs_tract:
        inputs["mesh"] = mesh_sha256
    sections = SPATIAL_SECTIONS
    if t.needs_tract:  # the lips, the tract and its acoustics matter too
        cfg = load_config(config)
        inputs["acoustic_maps"] = ctx.acoustic_sha256
        sections = STAGE.sections
    checked = None if sim is None else sim.simulation
    held = bool(checked.hold_jaw) if (verify or refine) and checked is not None else None
    prov = STAGE.provenance(cfg, inputs=inputs, params={"verify": verify, "refine": refine, "budget": budget,
                                                        "hold_jaw": held},
                            sections=sections)
    if up_to_date(path, prov):
        doc = read(path)
        if "unreachable" in doc:
            err = UnreachableTarget(doc["unreachable"])
            for attr, key in _NEAREST.items():
                if key in doc:
                    setattr(err, attr, doc[key])
            raise err
        return doc, path, True
    try:
        doc = solve(ctx, t, sim, verify, refine, budget)
        if held is not None:  # how the answer was checked: what 'artic simulate --solution' replays
            doc["verification"] = checked.conditions()
    except UnreachableTarget as err:  # the answer is written too (make and scripts can report it)
        near = {key: getattr(err, attr) for attr, key in _NEAREST.items() if getattr(err, attr, None) is not None}
        write(path, {"target": t.name, "unreachable": str(err), **near, **getattr(err, "answer", {})}, prov)
        raise
    write(path, doc, prov)
    return read(path), path, False
