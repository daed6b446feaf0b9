"""Stage ``solve``: a target file in, the force set out (section V), checked by simulation on request."""

from __future__ import annotations

from pathlib import Path

from ..config import load_config
from ..control.solver import TargetSpec
from ..control.targets import Context, load_target, solve
from ..control.verify import Simulator
from ..errors import ArticError, UnreachableTarget
from ..io.fingerprint import digest
from ..io.store import content_hash_of, read_doc, write_doc
from ..mechanics.model import ARTICULATOR_SECTIONS
from . import dynamic as dynamic_stage
from . import epmap as epmap_stage
from . import mesh as mesh_stage
from .base import Stage, up_to_date

SPATIAL_SECTIONS = (*ARTICULATOR_SECTIONS, "epmap")
STAGE = Stage(name="solve", module=__name__, sections=(*SPATIAL_SECTIONS, "vocal_tract", "acoustics"),
              reads=("epmaps", "dynamic"),
              kind="solution", hint="rerun 'artic solve-target TARGET.yaml'")


def load_context(maps: Path | str = "data/epmaps.h5", dynamic: Path | str | None = "data/dynamic.h5",
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
    """Give the context the formants of every EP (for acoustic targets): the acoustic maps (checked fresh) for
    the config's lips and port and for its mapped lip tubes (``vocal_tract.mapped_lips``, the config's port),
    and for other lips or ports the same computed from the EPs' shapes, one jaw position at a time (0.4 s for
    a jaw position's vectors, 4.5 s with its nets)."""
    from . import acoustic_map as am_stage
    from . import vocal_tract as vt_stage
    from ..io.store import stored_content_hash

    cfg = load_config(config)
    m = mesh_stage.read(mesh, cfg)
    vt = vt_stage.speaker_tract(cfg)
    defaults = (float(vt.lips.area_cm2), float(vt.lips.length_cm), float(vt.velum_port_cm2))
    stored = None
    if acoustic_maps is not None and Path(acoustic_maps).is_file():
        prov = am_stage.STAGE.provenance(cfg, inputs={"mesh": m.content_sha256,
                                                      "epmaps": str(stored_content_hash(maps))})
        if not up_to_date(acoustic_maps, prov):
            raise ArticError(f"{acoustic_maps} was made from other EP maps, mesh, config or code; "
                             "rerun 'artic acoustic-map' (or leave --acoustic-maps out)")
        stored = am_stage.read(acoustic_maps, formants_only=True)
        ctx.acoustic_sha256 = str(stored_content_hash(acoustic_maps))
    cache: dict = {}
    whole: list = []  # the maps with the EPs' shapes, read once when other lips or ports need them

    def formants(jaw: str, area: float, length: float, port: float) -> dict:
        key = (jaw, *am_stage.lip_key(area, length), round(port, 6))
        if key not in cache:
            mapped = stored is not None and key[3] == round(defaults[2], 6)  # the acoustic maps hold the config's port
            held = stored.formants_with(jaw, area, length) if mapped else None  # one of its mapped lip tubes
            if mapped and jaw in stored.jaws and key[1:3] == am_stage.lip_key(*defaults[:2]):
                cache[key] = {k: n.formants_hz for k, n in stored.jaws[jaw].items()}
            elif held is not None:
                cache[key] = held
            else:
                if not whole:
                    whole.append(epmap_stage.read(maps))
                nets = am_stage.compute(cfg, m.mesh, whole[0], jaws=[jaw], overrides={
                    "lip_area_cm2": area, "lip_length_cm": length, "velum_port_cm2": port}, bandwidths=False).jaws[jaw]
                cache[key] = {k: n.formants_hz for k, n in nets.items()}
        return cache[key]

    ctx.formants, ctx.lips_default, ctx.port_default = formants, defaults[:2], defaults[2]
    return ctx


class Voicer:
    """A simulator that also gives the vocal tract and formants of the force set it holds."""

    def __init__(self, sim: Simulator, cfg):
        from . import vocal_tract as vt_stage

        self.sim, self.cfg = sim, cfg
        self.vt = vt_stage.speaker_tract(cfg)
        self.mesh_sha256 = sim.mesh_sha256

    def reach(self, jaw_forces: dict[str, float], forces: dict[str, float]):
        return self.sim.reach(jaw_forces, forces)

    def voice(self, jaw_forces: dict[str, float], forces: dict[str, float], lips: tuple[float, float],
              port: float) -> dict:
        from .acoustic_map import net_acoustics

        x, cp = self.sim.shape(jaw_forces, forces)
        rest, mandible = self.sim.model_rest()
        n = net_acoustics(self.vt, self.cfg, self.sim.mesh, rest, mandible, x[None], {
            "lip_area_cm2": lips[0], "lip_length_cm": lips[1], "velum_port_cm2": port})
        r = lambda v: [round(float(a), 4) for a in v]  # noqa: E731
        return {"formants_hz": [float(v) for v in n.formants_hz[0]],
                "reached_cm": {"tip": r(cp[0, :2]), "dorsum": r(cp[1, :2])},
                "area_function": {"length_cm": r(n.length_cm[0]), "area_cm2": r(n.area_cm2[0]),
                                  "order": "glottis to lips, the lip tube last"}}


def simulator(mesh: Path | str, config: Path | str | None = None, voiced: bool = False) -> Simulator | Voicer:
    cfg = load_config(config)
    m = mesh_stage.read(mesh, cfg)
    sim = Simulator(STAGE.view(cfg).full, m.mesh, m.wall, m.content_sha256)
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
    path = Path(out) if out is not None else Path("data/solutions") / f"{t.name}.yaml"
    cfg = load_config(config) if (verify or refine) else None
    inputs = {"epmaps": ctx.maps_sha256, "dynamic": ctx.dynamic_sha256, "target": digest(t.model_dump(mode="json"))}
    if verify or refine or t.acoustic is not None:
        inputs["mesh"] = mesh_sha256
    sections = SPATIAL_SECTIONS
    if t.acoustic is not None:  # the lips, the tract and its acoustics matter too
        cfg = load_config(config)
        inputs["acoustic_maps"] = ctx.acoustic_sha256
        sections = STAGE.sections
    prov = STAGE.provenance(cfg, inputs=inputs, params={"verify": verify, "refine": refine, "budget": budget},
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
    except UnreachableTarget as err:  # the answer is written too (make and scripts can report it)
        near = {key: getattr(err, attr) for attr, key in _NEAREST.items() if getattr(err, attr, None) is not None}
        write(path, {"target": t.name, "unreachable": str(err), **near, **getattr(err, "answer", {})}, prov)
        raise
    write(path, doc, prov)
    return read(path), path, False
