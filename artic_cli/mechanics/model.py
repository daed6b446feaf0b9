"""Model (static), State (changes every step) and Control (inputs over time).

As in MuJoCo's mjModel / mjData and Warp's Model / State / Control, the
static model holds topology, rest geometry, materials, muscle routing, the force
terms it sums (:mod:`.term`) and the solver's fixed layout (:class:`.assembly.Layout`);
the state holds positions, velocities, the
integrator's history, the muscles' internal (Maxwell) state and a scratch
factorisation; the control holds the external nodal forces and the muscle
forces of the current step.  Everything is CGS inside (cm, g, s, dyn).

Two bodies share this model: the tongue alone (``build_model``: bricks and
cylinders, some node sets held fixed) and the whole articulator
(``build_articulator``: tongue, jaw and hyoid as stiff links, the points the
mandible carries, muscles, condyle guide, wall contact).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .. import units
from ..config import Config, Simulation, TissueMaterial
from ..errors import ArticError
from ..geometry.anatomy import JAW_MUSCLES, LINK_KINDS, TONGUE_MUSCLES, Body, build_body, check_muscle_names
from ..geometry.hexahedra import corner_jacobians, volumes
from ..geometry.mesh import Mesh
from ..geometry.mirror import MIRROR, mirror_images
from ..geometry.wall import WallSurface
from .assembly import BandFactor, Layout, band_pattern, node_assembly
from .calibration import calibrate
from .contact import ContactModel, ContactTerm, contact_model
from .elements import CylinderSet, CylinderTerm
from .external import ExternalTerm
from .guide import Guide, GuideTerm, with_flat
from .isotropy import isotropic_areas
from .muscles import MuscleSet, MuscleTerm, fibre_twins, muscle_set
from .prestress import weight_carrying
from .term import ForceTerm
from .volume import VolumeTerm



CONTROL_POINTS = ("tip", "dorsum", "jaw")  # the names of the EMA-style control points, in this order
# the force terms a model sums, in this order (each where the model has its physics)
FORCE_TERMS: tuple[ForceTerm, ...] = (CylinderTerm(), VolumeTerm(), GuideTerm(), MuscleTerm(), ContactTerm(),
                                      ExternalTerm())

@dataclass(frozen=True)
class SolverOptions:
    dt: float = 5e-3  # s
    scheme: str = "houbolt"
    tol: float = 1e-5  # cm, Newton increment
    max_iter: int = 25
    refactor_rate: float = 0.25


@dataclass(frozen=True)
class Carried:
    """Points carried rigidly by a bone: each is a fixed affine combination of four of the bone's nodes.

    Four non-coplanar points determine a rigid motion, and an affine map keeps
    affine combinations, so x = sum_m w_m x_m holds exactly for any rigid
    motion of the four; the points have no degrees of freedom of their own.
    """

    nodes: np.ndarray  # (S,)
    masters: np.ndarray  # (S,4)
    weights: np.ndarray  # (S,4), each row sums to 1

    def place(self, x: np.ndarray) -> np.ndarray:
        """``x`` with the carried points put where their masters say (in place, returned)."""
        x[self.nodes] = np.einsum("sm,smi->si", self.weights, x[self.masters])
        return x


def carried_points(rest: np.ndarray, nodes: np.ndarray, frame: np.ndarray) -> Carried:
    """Barycentric weights of ``nodes`` in the tetrahedron of the four ``frame`` nodes, at ``rest``."""
    a = np.vstack([rest[frame].T, np.ones(4)])  # (4,4)
    if abs(np.linalg.det(a)) < 1e-9:
        raise ArticError("the mandible's carrying frame is flat; check the landmarks")
    w = np.linalg.solve(a, np.vstack([rest[nodes].T, np.ones(len(nodes))])).T  # (S,4)
    return Carried(nodes=np.asarray(nodes), masters=np.broadcast_to(frame, (len(nodes), 4)).copy(), weights=w)


@dataclass(frozen=True)
class Model:
    mesh: Mesh
    rest: np.ndarray  # (N,3) all nodes
    springs: CylinderSet  # every Voigt element: tongue cylinders, bone links, floor links and jaw springs
    bricks: np.ndarray
    brick_v0: np.ndarray
    kappa: np.ndarray  # (B,) bulk penalty, dyn/cm^2 (0 = constraint off)
    mass: sp.csr_matrix  # (N,N) consistent mass, node level, g
    node_mass: np.ndarray  # (N,)
    gravity: np.ndarray  # (3,) cm/s^2
    fixed: np.ndarray  # (N,3) bool
    layout: Layout  # the solver's fixed pattern, block placement, mass and scatter
    options: SolverOptions = field(default_factory=SolverOptions)
    force_terms: tuple[ForceTerm, ...] = FORCE_TERMS  # what step() sums (each present one)
    node_sets: dict = field(default_factory=dict)
    names: dict = field(default_factory=dict)
    muscles: MuscleSet | None = None
    groups: dict = field(default_factory=dict)  # group -> {muscle: share}
    guide: Guide | None = None
    contact: ContactModel | None = None
    wall: WallSurface | None = None
    tone: np.ndarray | None = None  # (M,) postural muscle forces, dyn, added to every control's
    corner_j0: np.ndarray | None = None  # (B,8) rest corner Jacobians (inversion guard)
    guard_weight: np.ndarray | None = None  # (B,) guard stiffness w = bulk x V0 / 8, erg
    carried: Carried | None = None  # points that move rigidly with the mandible
    image: np.ndarray | None = None  # (N,) each node's mirror image, when the right half is solved for both
    mirrored: np.ndarray | None = None  # (H,) the nodes that move as their image's mirror (no dofs of their own)
    fibre_twin: np.ndarray | None = None  # (F,) each fibre's mirror twin when mirrored (itself on the midline)

    @cached_property
    def terms(self) -> tuple[ForceTerm, ...]:
        """The force terms this model has (its wall, muscles, guide: when present); found once per model (a
        changed model, ``dataclasses.replace``, is a new one)."""
        return tuple(t for t in self.force_terms if t.present(self))

    def mirror(self, x: np.ndarray) -> np.ndarray:
        """``x`` (N,3) with each mirrored node put at its image's mirror place (in place, returned)."""
        if self.mirrored is not None:
            x[self.mirrored] = x[self.image[self.mirrored]] * MIRROR
        return x

    @property
    def n_nodes(self) -> int:
        return self.rest.shape[0]

    @property
    def n_tongue(self) -> int:
        return self.mesh.nodes.shape[0]

    @cached_property
    def volume_constraint(self) -> bool:
        return bool(np.any(self.kappa > 0))

    def node_set(self, name: str) -> np.ndarray:
        try:
            return self.node_sets[name]
        except KeyError:
            valid = ", ".join(sorted(self.node_sets))
            raise ArticError(f"unknown node set '{name}'; valid sets: {valid}") from None

    @property
    def muscle_names(self) -> tuple[str, ...]:
        return self.muscles.names if self.muscles is not None else ()

    def drivable(self) -> list[str]:
        """Every name a schedule may drive: muscles and groups."""
        return [*self.muscle_names, *self.groups]

    def control_points(self) -> dict[str, int]:
        """The EMA-style control points this model has: tongue tip, dorsum (fifth midsagittal surface node
        from the tip) and jaw (lower incisor), each a node index."""
        return {name: int(self.node_sets[name][0]) for name in CONTROL_POINTS if name in self.node_sets}


@dataclass
class State:
    t: float
    x: np.ndarray  # (N,3) cm
    v: np.ndarray  # (N,3) cm/s
    history: tuple[np.ndarray, ...] = ()  # previous positions, newest first
    history_dt: float = 0.0
    history_passed: bool = False  # every position in history is one the body passed through (none made up at a start)
    sigma2: np.ndarray | None = None  # (F,) Maxwell stress of each fibre, dyn/cm^2
    fibre_strain: np.ndarray | None = None  # (F,)
    factor: BandFactor | None = None  # scratch: reused factorisation
    iterations: int = 0  # Newton iterations of the last step
    refactors: int = 0  # factorisations so far
    contact_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    contact_force: np.ndarray = field(default_factory=lambda: np.zeros(0))  # dyn, per contact node
    projected: int = 0  # nodes put back on the wall after the last step
    wall_cache: tuple | None = None  # scratch: (x, wall query at x) for the next step's contact planes


@dataclass(frozen=True)
class Control:
    """What drives one step: external nodal forces and the muscles' forces, both in dyn (1 N = 1e5 dyn).

    Build one from newtons with :func:`artic_cli.mechanics.loads.control_from_newtons`."""

    node_force: np.ndarray  # (N, 3) external force on each node, dyn
    muscle_force: np.ndarray | None = None  # (M,) force of each muscle unit (model.muscle_names), dyn


def rest_state(model: Model) -> State:
    x = model.rest.copy()
    nf = model.muscles.n_fibres if model.muscles is not None else 0
    return State(t=0.0, x=x, v=np.zeros_like(x), sigma2=np.zeros(nf), fibre_strain=np.zeros(nf))


def zero_control(model: Model) -> Control:
    return Control(node_force=np.zeros((model.n_nodes, 3)), muscle_force=np.zeros(len(model.muscle_names)))


def solver_options(sim: Simulation) -> SolverOptions:
    return SolverOptions(dt=units.ms_to_s(sim.dt_ms), scheme=sim.scheme, tol=sim.newton_tol_cm,
                         max_iter=sim.newton_max_iter, refactor_rate=sim.refactor_rate)


def with_options(model: Model, **changes) -> Model:
    return replace(model, options=replace(model.options, **changes))


def tongue_volume(model: Model, x: np.ndarray) -> float:
    return float(volumes(x, model.bricks).sum())


def tongue_cylinders(mesh: Mesh, tissue: TissueMaterial, n_nodes: int) -> tuple[CylinderSet, float, float]:
    """Cylinders of the tongue (calibrated), the modulus scale and the bulk ratio."""
    scale, bulk_ratio = calibrate(tissue.poisson_ratio, tissue.isotropic_truss, tissue.volume_constraint_gain)
    stiff_area = isotropic_areas(mesh.nodes, mesh.bricks)[0] if tissue.isotropic_truss else mesh.areas.copy()
    e0 = units.kpa_to_cgs(tissue.youngs_modulus_kpa)
    eta0 = units.kpa_to_cgs(tissue.viscosity_kpa_s)
    c = len(mesh.cylinders)
    full = lambda val: np.full(c, float(val))  # noqa: E731
    cyl = CylinderSet(i=mesh.cylinders[:, 0], j=mesh.cylinders[:, 1], l0=mesh.rest_lengths, area0=stiff_area,
                      youngs=full(scale * e0), viscosity=full(scale * eta0), poisson=full(tissue.poisson_ratio),
                      knee=full(tissue.stiffening_strain), rate=full(tissue.stiffening_rate), n_nodes=n_nodes)
    return cyl, scale, bulk_ratio


def _carrying_weight(cyl: CylinderSet, x: np.ndarray, tissue: TissueMaterial, link_mass: np.ndarray,
                     gravity: float, free: np.ndarray, carriers: np.ndarray) -> CylinderSet:
    """The cylinders as they are, or (``tissue.rest_under_gravity``) with the rest lengths of the
    ``carriers`` (the tongue's cylinders, and the floor's links in the articulator) set to carry the weight
    of the ``free`` tongue nodes (the consistent mass's row sums) at their drawn positions ``x``."""
    if not tissue.rest_under_gravity or gravity == 0.0:
        return cyl
    node_mass = np.asarray(_consistent_mass(cyl.i, cyl.j, link_mass, cyl.n_nodes).sum(axis=1)).ravel()
    return weight_carrying(cyl, x, node_mass, np.array([0.0, -gravity, 0.0]), free, carriers)


def _consistent_mass(i, j, m, n):
    rows = np.concatenate([i, j, i, j])
    cols = np.concatenate([i, j, j, i])
    vals = np.concatenate([m / 3, m / 3, m / 6, m / 6])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))


def _finish(mesh: Mesh, rest: np.ndarray, cyl: CylinderSet, link_mass: np.ndarray, kappa: np.ndarray,
            fixed: np.ndarray, sim: Simulation, gravity: float, n_core: int, bulk: float,
            mirror: tuple[np.ndarray, np.ndarray] | None = None, **extra) -> Model:
    n = len(rest)
    v0 = volumes(mesh.nodes, mesh.bricks)
    extra["corner_j0"] = corner_jacobians(mesh.nodes, mesh.bricks)
    extra["guard_weight"] = bulk * v0 / 8.0
    mass = _consistent_mass(cyl.i, cyl.j, link_mass, n)
    node_mass = np.asarray(mass.sum(axis=1)).ravel()
    pairs = [cyl.i[:, None], cyl.j[:, None]]
    all_pairs = np.hstack(pairs)
    ms = extra.get("muscles")
    if ms is not None:
        all_pairs = np.vstack([all_pairs, np.column_stack([ms.seg_i, ms.seg_j])])
    carried = extra.get("carried")
    slaves = None if carried is None else (carried.nodes, carried.masters, carried.weights)
    pattern = band_pattern(n, all_pairs, fixed, n_core, slaves, mirror)
    cyl_edges = np.column_stack([cyl.i, cyl.j])
    seg_edges = np.column_stack([ms.seg_i, ms.seg_j]) if ms is not None else np.zeros((0, 2), dtype=np.int64)
    asm = node_assembly(pattern, n, cyl_edges, mesh.bricks, seg_edges)
    eye = np.broadcast_to(np.eye(3), (len(cyl.i), 3, 3))
    mblocks = np.zeros((asm.n_pairs + n, 3, 3))
    asm.add_pairs(mblocks, cyl.i, cyl.j, asm.cyl_pair, (link_mass / 3.0)[:, None, None] * eye)
    mblocks[: asm.n_pairs] *= -0.5  # consistent mass: m/3 on the diagonal, m/6 between the two nodes
    ncyl = len(cyl.i)
    scatter = sp.csr_matrix((np.concatenate([np.ones(ncyl), -np.ones(ncyl)]),
                             (np.concatenate([cyl.i, cyl.j]), np.concatenate([np.arange(ncyl)] * 2))), shape=(n, ncyl))
    guide = extra.pop("guide_spec", None)
    if guide is not None:
        nodes, origin, normals, k, path, onset = guide
        extra["guide"] = with_flat(Guide(nodes=nodes, origin=origin, normals=normals, stiffness=k, path=path,
                                         onset=onset), pattern)
    layout = Layout(pattern=pattern, assembly=asm, mass_flat=asm.operator @ mblocks.ravel(), scatter=scatter)
    return Model(mesh=mesh, rest=rest, springs=cyl, bricks=mesh.bricks, brick_v0=v0,
                 kappa=kappa, mass=mass, node_mass=node_mass, gravity=np.array([0.0, -gravity, 0.0]), fixed=fixed,
                 layout=layout, options=solver_options(sim), **extra)


def build_model(mesh: Mesh, tissue: TissueMaterial, sim: Simulation, *,
                volume_constraint: bool | None = None, fixed_sets: list[str] | None = None,
                fixed_dofs: np.ndarray | None = None, gravity: float | None = None) -> Model:
    """The tongue alone: bricks and cylinders, with node sets held fixed."""
    n = len(mesh.nodes)
    cyl, scale, bulk_ratio = tongue_cylinders(mesh, tissue, n)
    on = sim.volume_constraint if volume_constraint is None else volume_constraint
    e0 = units.kpa_to_cgs(tissue.youngs_modulus_kpa)
    kappa = np.full(len(mesh.bricks), bulk_ratio * scale * e0 if on else 0.0)
    if fixed_dofs is None:
        fixed_dofs = np.zeros((n, 3), dtype=bool)
        for name in (sim.fixed_node_sets if fixed_sets is None else fixed_sets):
            if name not in mesh.node_sets:
                valid = ", ".join(sorted(mesh.node_sets))
                raise ArticError(f"unknown fixed node set '{name}'; valid sets: {valid}")
            fixed_dofs[mesh.node_sets[name]] = True
        if sim.midsagittal_symmetry:  # the midsagittal nodes stay in their plane (no sideways buckling)
            fixed_dofs[mesh.node_sets["midsagittal"], 2] = True
    link_mass = tissue.density_g_cm3 * mesh.areas * cyl.l0  # the paper's volumes carry the mass
    g = sim.gravity_cm_s2 if gravity is None else gravity
    cyl = _carrying_weight(cyl, mesh.nodes, tissue, link_mass, g, np.where(~fixed_dofs.all(axis=1))[0],
                           np.ones(len(cyl), dtype=bool))
    return _finish(mesh, mesh.nodes.copy(), cyl, link_mass, kappa, fixed_dofs, sim, g, n,
                   bulk_ratio * scale * e0, node_sets=dict(mesh.node_sets))


TISSUE_LINKS = ("floor", "sling")  # the tongue floor's links to the hyoid and to the mandible's mylohyoid lines


def _of_kind(kinds: np.ndarray, *names: str) -> np.ndarray:
    """(L,) bool: the links whose kind is one of ``names`` (LINK_KINDS)."""
    return np.isin(kinds, [LINK_KINDS.index(k) for k in names])


def _links(body: Body, cfg: Config, tissue_scale: float) -> tuple[CylinderSet, np.ndarray, np.ndarray]:
    """Passive links of the articulator: bones, floor, straps, jaw muscles' passive springs; their masses
    and kinds (an index of LINK_KINDS, -1 for the jaw muscles' springs)."""
    jaw = cfg.jaw
    bone = cfg.materials.bone
    tissue = cfg.materials.tongue
    x = body.nodes
    pairs = [body.links]
    kinds = [body.link_kind]
    passive = np.array([f[:2] for m in JAW_MUSCLES for f in body.fibres[m]], dtype=np.int64)  # the moving segment
    pairs.append(passive)
    kinds.append(np.full(len(passive), -1))
    pairs = np.vstack(pairs)
    kinds = np.concatenate(kinds)
    i, j = pairs[:, 0], pairs[:, 1]
    l0 = np.linalg.norm(x[j] - x[i], axis=1)
    area = np.full(len(i), jaw.link_area_cm2)
    e = np.zeros(len(i))
    eta = np.zeros(len(i))
    stiff = _of_kind(kinds, "mandible", "hyoid")
    e[stiff] = units.kpa_to_cgs(bone.youngs_modulus_kpa)
    eta[stiff] = units.kpa_to_cgs(bone.viscosity_kpa_s)
    floor, sling, tissue_links = _of_kind(kinds, "floor"), _of_kind(kinds, "sling"), _of_kind(kinds, *TISSUE_LINKS)
    area[floor] = jaw.floor_link_area_cm2
    area[sling] = jaw.floor_link_area_cm2 if jaw.sling_link_area_cm2 is None else jaw.sling_link_area_cm2
    e[tissue_links] = tissue_scale * units.kpa_to_cgs(tissue.youngs_modulus_kpa)
    eta[tissue_links] = tissue_scale * units.kpa_to_cgs(tissue.viscosity_kpa_s)
    relax = units.ms_to_s(jaw.passive_relaxation_ms)  # dashpot = relaxation time x spring
    strap = _of_kind(kinds, "strap")
    for mask, k_n_cm in ((strap, jaw.strap_stiffness_n_per_cm),
                         (kinds == -1, jaw.passive_stiffness_n_per_cm)):
        k = units.newton_to_dyn(k_n_cm)  # dyn/cm
        area[mask] = 1.0
        e[mask] = k * l0[mask]
        eta[mask] = relax * e[mask]
    mass = np.zeros(len(i))
    for kind, total in (("mandible", bone.mandible_mass_g), ("hyoid", bone.hyoid_mass_g)):
        m = _of_kind(kinds, kind)
        mass[m] = total * l0[m] / l0[m].sum()  # spread uniformly over the bone's links
    n = len(i)
    slack = np.full(n, np.inf)
    if jaw.floor_slack_strain is not None:  # the floor rests on the hyoid: compression only
        slack[floor] = jaw.floor_slack_strain
    if jaw.strap_slack_strain is not None:  # the straps pull only: their slack on the shortening side
        slack[strap] = -jaw.strap_slack_strain
    cyl = CylinderSet(i=i, j=j, l0=l0, area0=area, youngs=e, viscosity=eta, poisson=np.zeros(n),
                      knee=np.full(n, np.inf), rate=np.zeros(n), n_nodes=len(x), slack=slack)
    return cyl, mass, kinds


def _concat(a: CylinderSet, b: CylinderSet) -> CylinderSet:
    return CylinderSet(**{f: np.concatenate([getattr(a, f), getattr(b, f)]) for f in
                          ("i", "j", "l0", "area0", "youngs", "viscosity", "poisson", "knee", "rate")},
                       slack=np.concatenate([a.slack_strain, b.slack_strain]), n_nodes=a.n_nodes)


# the config sections building the articulator reads (build_articulator is handed a view of just these)
ARTICULATOR_SECTIONS = ("speaker", "materials", "simulation", "muscles", "jaw", "contact")


def build_articulator(cfg: Config, mesh: Mesh, wall: WallSurface | None = None, *,
                      volume_constraint: bool | None = None, contact: bool | None = None,
                      gravity: float | None = None) -> Model:
    """Tongue, jaw and hyoid with all muscles, the condyle guide and (optionally) wall contact."""
    body = build_body(cfg, mesh, digastric_through_sling=cfg.jaw.digastric_through_sling,
                      digastric_sling=cfg.jaw.digastric_sling,
                      verticalis_sections=cfg.muscles.verticalis_sections,
                      verticalis_to_level=cfg.muscles.verticalis_to_level, il_midsagittal=cfg.muscles.il_midsagittal,
                      il_route=cfg.muscles.inferior_longitudinalis,
                      gg_tendon=cfg.jaw.gg_tendon, floor_on_mylohyoid=cfg.jaw.floor_on_mylohyoid,
                      sg_routes=cfg.muscles.styloglossus)
    n = len(body.nodes)
    tissue = cfg.materials.tongue
    tcyl, scale, bulk_ratio = tongue_cylinders(mesh, tissue, n)
    lcyl, lmass, lkind = _links(body, cfg, scale)
    link_mass = np.concatenate([tissue.density_g_cm3 * mesh.areas * tcyl.l0, lmass])
    grav = cfg.simulation.gravity_cm_s2 if gravity is None else gravity
    free = np.setdiff1d(np.arange(len(mesh.nodes)), body.carried)  # the tongue but its GG tendon on the mandible
    carriers = np.r_[np.ones(len(tcyl), dtype=bool), _of_kind(lkind, *TISSUE_LINKS)]
    cyl = _carrying_weight(_concat(tcyl, lcyl), body.nodes, tissue, link_mass, grav, free, carriers)
    on = cfg.simulation.volume_constraint if volume_constraint is None else volume_constraint
    e0 = units.kpa_to_cgs(tissue.youngs_modulus_kpa)
    kappa = np.full(len(mesh.bricks), bulk_ratio * scale * e0 if on else 0.0)
    fixed = np.zeros((n, 3), dtype=bool)
    fixed[body.fixed] = True
    if cfg.simulation.midsagittal_symmetry:  # the midsagittal nodes stay in their plane (carried ones follow the jaw)
        fixed[np.setdiff1d(mesh.node_sets["midsagittal"], body.carried), 2] = True
    mirror = None
    if cfg.simulation.mirror_symmetry:  # one half is solved, the other (z < 0) moves as its mirror image
        image = mirror_images(body.nodes, body.names)
        own = ~np.isin(np.arange(n), body.carried)
        fixed[own & (image == np.arange(n)), 2] = True
        halves = np.flatnonzero(own & (body.nodes[:, 2] < 0.0))
        mirror = (halves, image[halves])

    mc = cfg.muscles
    names = list(TONGUE_MUSCLES + JAW_MUSCLES)
    missing = [m for m in names if m not in mc.thickness_cm2]
    if missing:
        raise ArticError(f"config: muscles.thickness_cm2 lacks {', '.join(missing)}; add a thickness for each")
    check_muscle_names(mc.thickness_cm2, names, "muscles.thickness_cm2")
    for g, members in mc.groups.items():
        check_muscle_names(members, names, f"muscles.groups.{g}")
    ms = muscle_set(names, body.fibres, body.fibre_weight, mc.thickness_cm2, body.nodes,
                    k1=mc.passive_k1_ratio * e0, k2=mc.maxwell_k2_ratio * e0,
                    b2=mc.maxwell_b2_ratio * units.kpa_to_cgs(tissue.viscosity_kpa_s),
                    fl_width=mc.force_length_width)

    cond = np.array([body.names["condyle_l"], body.names["condyle_r"]])
    a = np.deg2rad(cfg.jaw.eminence_slope_deg)
    path = np.array([np.cos(a), np.sin(a), 0.0])
    normals = np.array([[-path[1], path[0], 0.0], [0.0, 0.0, 1.0]])
    guide = (cond, body.nodes[cond], np.broadcast_to(normals, (2, 2, 3)).copy(),
             units.newton_to_dyn(cfg.jaw.guide_stiffness_n_per_cm),
             np.broadcast_to(path, (2, 3)).copy() if cfg.jaw.fossa_stop else None, cfg.jaw.fossa_stop_onset_cm)

    cm = None
    use_contact = cfg.contact.enabled if contact is None else contact
    if use_contact and wall is not None:
        sets = mesh.node_sets
        nodes = np.unique(sets["surface"])  # the dorsal surface and the tip (the underside rests on the floor)
        jaw_frame = np.array([body.names[k] for k in ("symphysis_l", "symphysis_r", "coronoid_l", "gonion_r",
                                                      "condyle_l")])
        cm = contact_model(wall, nodes, mesh.nodes[nodes], jaw_frame, body.nodes[jaw_frame],
                           units.newton_to_dyn(cfg.contact.stiffness_n_per_cm), cfg.contact.tolerance_cm)
    tone = np.zeros(len(names))
    for name, fn in mc.postural_tone_n.items():
        members = mc.groups.get(name, {name: 1.0})
        check_muscle_names(members, names, "muscles.postural_tone_n")
        for m, w in members.items():
            tone[names.index(m)] += units.newton_to_dyn(fn) * w
    return _finish(mesh, body.nodes.copy(), cyl, link_mass, kappa, fixed, cfg.simulation, grav, len(mesh.nodes),
                   bulk_ratio * scale * e0,
                   node_sets=dict(body.node_sets), names=dict(body.names), muscles=ms,
                   groups={k: dict(v) for k, v in mc.groups.items()}, guide_spec=guide, contact=cm, wall=wall,
                   tone=tone, carried=carried_points(body.nodes, body.carried, body.carrier), mirror=mirror,
                   image=None if mirror is None else image, mirrored=None if mirror is None else halves,
                   fibre_twin=None if mirror is None else fibre_twins(ms, image))
