"""The paper's cuboid test (section II.B.3): Poisson ratio under an axial pull.

A 6 x 3 x 2 cm block of 5 x 3 x 2 bricks, built from the same cylinders,
volume constraint and materials as the tongue, rests on rollers at x = 0
(free to narrow, as in a uniaxial test) and is pulled along x by a uniform
traction on x = 6 cm.  At equilibrium we measure the axial strain, the
lateral strains of the mid-length cross-section, the apparent Poisson ratio
of Eq. (4), nu = -lateral / axial, and the volume change.

Eq. (4) is linear in strain.  At finite strain it is only consistent with
volume loss: a body whose volume does not shrink under tension has
nu_Eq4 <= (1 - lambda^-1/2) / (lambda - 1), which is 0.41 at 30 %
elongation.  So we also report Eq. (4) taken incrementally,
dr / r = -nu dl / l, i.e. nu_log = -ln(r/r0) / ln(l/l0) (Hencky strains),
which stays at the material's 0.49 for a nearly incompressible body at any
strain.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .. import units
from ..config import Config
from ..geometry.mesh import cuboid_mesh, face_weights
from ..mechanics.model import Control, build_model, rest_state
from ..mechanics.simulate import equilibrate
from ..mechanics.model import tongue_volume


@dataclass
class CuboidRow:
    force_n: float
    axial_strain: float
    lateral_strain: float
    poisson_ratio: float  # Eq. (4), engineering strains
    poisson_ratio_log: float  # Eq. (4) integrated: Hencky strains
    volume_change: float
    elongation_cm: float
    linear_elongation_cm: float  # F L / (E A)
    converged: bool


def run_cuboid(cfg: Config, forces_n=None, volume_constraint: bool | None = None) -> list[CuboidRow]:
    size = cfg.cuboid.size_cm
    mesh = cuboid_mesh(size, cfg.cuboid.bricks)
    x0 = mesh.nodes
    fixed = np.zeros_like(x0, dtype=bool)
    held = mesh.node_sets["fixed_end"]
    fixed[held, 0] = True  # rollers: the held face may narrow
    corner = held[np.argmin(np.abs(x0[held, 1]) + np.abs(x0[held, 2]))]
    top = held[np.argmin(np.abs(x0[held, 1]) + np.abs(x0[held, 2] - size[2]))]
    fixed[corner, 1:] = True  # no rigid translation in y, z
    fixed[top, 1] = True  # no rigid rotation about x
    model = build_model(mesh, cfg.materials.tongue, cfg.simulation, fixed_dofs=fixed, gravity=0.0,
                        volume_constraint=volume_constraint)
    face = mesh.node_sets["pulled_end"]
    weights = face_weights(x0, face)
    xs = np.unique(np.round(x0[:, 0], 9))
    mid = xs[np.argsort(np.abs(xs - 0.5 * size[0]))[:2]]  # the two planes nearest mid-length
    gauge = np.isin(np.round(x0[:, 0], 9), mid)
    e = units.kpa_to_cgs(cfg.materials.tongue.youngs_modulus_kpa)
    area = size[1] * size[2]
    state = rest_state(model)
    rows = []
    done, ok = 0.0, True
    for fn in sorted(cfg.cuboid.forces_n if forces_n is None else forces_n):
        # load in increments of at most 0.5 N from the last equilibrium (large jumps neck the block)
        for level in np.linspace(done, fn, int(np.ceil((fn - done) / 0.5)) + 1)[1:]:
            f = np.zeros_like(x0)
            f[face, 0] = units.newton_to_dyn(level) * weights
            state, ok = equilibrate(model, state, Control(node_force=f), dt=0.02, tol=1e-3, max_time=10.0)
        done = fn
        x = state.x
        axial = x[face, 0].mean() / size[0] - 1.0
        lat = []
        for ax in (1, 2):
            lo = gauge & np.isclose(x0[:, ax], 0.0)
            hi = gauge & np.isclose(x0[:, ax], size[ax])
            lat.append((x[hi, ax].mean() - x[lo, ax].mean()) / size[ax] - 1.0)
        lateral = float(np.mean(lat))
        rows.append(CuboidRow(
            force_n=float(fn), axial_strain=float(axial), lateral_strain=lateral,
            poisson_ratio=float(-lateral / axial) if axial != 0 else float("nan"),
            poisson_ratio_log=float(-np.log1p(lateral) / np.log1p(axial)) if axial != 0 else float("nan"),
            volume_change=tongue_volume(model, x) / mesh.volume - 1.0,
            elongation_cm=float(axial * size[0]),
            linear_elongation_cm=float(units.newton_to_dyn(fn) * size[0] / (e * area)),
            converged=ok))
    return rows


def rows_as_dicts(rows: list[CuboidRow]) -> list[dict]:
    return [asdict(r) for r in rows]
