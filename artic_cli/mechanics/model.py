"""Model (static), State (changes every step) and Control (inputs over time).

As in MuJoCo's mjModel / mjData and Warp's Model / State / Control, the
static model holds topology, rest geometry, materials and the solver's fixed
sparsity pattern; the state holds positions, velocities, the integrator's
history and a scratch factorisation; the control holds the external nodal
forces of the current step.  Everything is CGS inside (cm, g, s, dyn).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from .. import units
from ..config import Simulation, TissueMaterial
from ..errors import ArticError
from ..geometry.hexahedra import volume_gradients, volumes
from ..geometry.mesh import Mesh
from .assembly import BandFactor, BandPattern, band_pattern
from .calibration import calibrate
from .elements import CylinderSet
from .isotropy import isotropic_areas


@dataclass(frozen=True)
class SolverOptions:
    dt: float = 5e-3  # s
    scheme: str = "houbolt"
    tol: float = 1e-5  # cm, Newton increment
    max_iter: int = 25
    refactor_rate: float = 0.25


@dataclass(frozen=True)
class Model:
    mesh: Mesh
    cyl: CylinderSet
    bricks: np.ndarray
    brick_v0: np.ndarray
    kappa: np.ndarray  # (B,) bulk penalty, dyn/cm^2 (0 = constraint off)
    mass: sp.csr_matrix  # (N,N) consistent mass, node level, g
    node_mass: np.ndarray  # (N,)
    gravity: np.ndarray  # (3,) cm/s^2
    fixed: np.ndarray  # (N,3) bool
    pattern: BandPattern
    cyl_index: np.ndarray  # (C,6,6) band indices
    brick_index: np.ndarray  # (B,24,24)
    mass_band: np.ndarray  # (u+1, n_free)
    scatter: sp.csr_matrix  # (N, C): node force = scatter @ (T n)
    options: SolverOptions = field(default_factory=SolverOptions)

    @property
    def n_nodes(self) -> int:
        return self.mesh.nodes.shape[0]

    @property
    def volume_constraint(self) -> bool:
        return bool(np.any(self.kappa > 0))

    def node_set(self, name: str) -> np.ndarray:
        try:
            return self.mesh.node_sets[name]
        except KeyError:
            valid = ", ".join(sorted(self.mesh.node_sets))
            raise ArticError(f"unknown node set '{name}'; valid sets: {valid}") from None


@dataclass
class State:
    t: float
    x: np.ndarray  # (N,3) cm
    v: np.ndarray  # (N,3) cm/s
    history: tuple[np.ndarray, ...] = ()  # previous positions, newest first
    history_dt: float = 0.0
    factor: BandFactor | None = None  # scratch: reused factorisation
    iterations: int = 0  # Newton iterations of the last step
    refactors: int = 0  # factorisations so far


@dataclass(frozen=True)
class Control:
    force: np.ndarray  # (N,3) external nodal force, dyn


def rest_state(model: Model) -> State:
    x = model.mesh.nodes.copy()
    return State(t=0.0, x=x, v=np.zeros_like(x))


def zero_control(model: Model) -> Control:
    return Control(force=np.zeros((model.n_nodes, 3)))


def solver_options(sim: Simulation) -> SolverOptions:
    return SolverOptions(dt=units.ms_to_s(sim.dt_ms), scheme=sim.scheme, tol=sim.newton_tol_cm,
                         max_iter=sim.newton_max_iter, refactor_rate=sim.refactor_rate)


def build_model(mesh: Mesh, tissue: TissueMaterial, sim: Simulation, *,
                volume_constraint: bool | None = None, fixed_sets: list[str] | None = None,
                fixed_dofs: np.ndarray | None = None, gravity: float | None = None) -> Model:
    """Assemble the static model of a brick-and-cylinder body."""
    scale, bulk_ratio = calibrate(tissue.poisson_ratio, tissue.isotropic_truss, tissue.volume_constraint_gain)
    stiff_area = isotropic_areas(mesh.nodes, mesh.bricks)[0] if tissue.isotropic_truss else mesh.areas.copy()
    e0 = units.kpa_to_cgs(tissue.youngs_modulus_kpa)
    eta0 = units.kpa_to_cgs(tissue.viscosity_kpa_s)
    ncyl = len(mesh.cylinders)
    ci, cj = mesh.cylinders[:, 0], mesh.cylinders[:, 1]
    full = lambda val: np.full(ncyl, float(val))  # noqa: E731
    cyl = CylinderSet(i=ci, j=cj, l0=mesh.rest_lengths, area0=stiff_area,
                      youngs=full(scale * e0), viscosity=full(scale * eta0),
                      poisson=full(tissue.poisson_ratio), knee=full(tissue.stiffening_strain),
                      rate=full(tissue.stiffening_rate), n_nodes=len(mesh.nodes))
    on = sim.volume_constraint if volume_constraint is None else volume_constraint
    v0 = volumes(mesh.nodes, mesh.bricks)
    kappa = np.full(len(v0), bulk_ratio * scale * e0 if on else 0.0)

    n = len(mesh.nodes)
    m = tissue.density_g_cm3 * mesh.areas * cyl.l0  # the paper's volumes carry the mass
    rows = np.concatenate([ci, cj, ci, cj])
    cols = np.concatenate([ci, cj, cj, ci])
    vals = np.concatenate([m / 3, m / 3, m / 6, m / 6])
    mass = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    node_mass = np.asarray(mass.sum(axis=1)).ravel()

    if fixed_dofs is None:
        fixed_dofs = np.zeros((n, 3), dtype=bool)
        for name in (sim.fixed_node_sets if fixed_sets is None else fixed_sets):
            if name not in mesh.node_sets:
                valid = ", ".join(sorted(mesh.node_sets))
                raise ArticError(f"unknown fixed node set '{name}'; valid sets: {valid}")
            fixed_dofs[mesh.node_sets[name]] = True
    pattern = band_pattern(n, mesh.cylinders, fixed_dofs)
    cyl_index = pattern.block_index(mesh.cylinders)
    brick_index = pattern.block_index(mesh.bricks)
    mblock = np.kron(np.array([[2.0, 1.0], [1.0, 2.0]]), np.eye(3))[None] * (m / 6.0)[:, None, None]
    mass_band = pattern.assemble(cyl_index, mblock)
    scatter = sp.csr_matrix((np.concatenate([np.ones(ncyl), -np.ones(ncyl)]),
                             (np.concatenate([ci, cj]), np.concatenate([np.arange(ncyl)] * 2))),
                            shape=(n, ncyl))
    g = sim.gravity_cm_s2 if gravity is None else gravity
    return Model(mesh=mesh, cyl=cyl, bricks=mesh.bricks, brick_v0=v0, kappa=kappa, mass=mass,
                 node_mass=node_mass, gravity=np.array([0.0, -g, 0.0]), fixed=fixed_dofs,
                 pattern=pattern, cyl_index=cyl_index, brick_index=brick_index, mass_band=mass_band,
                 scatter=scatter, options=solver_options(sim))


def with_options(model: Model, **changes) -> Model:
    return replace(model, options=replace(model.options, **changes))


def tongue_volume(model: Model, x: np.ndarray) -> float:
    return float(volumes(x, model.bricks).sum())


__all__ = ["Model", "State", "Control", "SolverOptions", "build_model", "rest_state", "zero_control",
           "with_options", "tongue_volume", "volume_gradients"]
