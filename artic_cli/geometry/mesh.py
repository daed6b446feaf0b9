"""The semicontinuum tongue mesh: a radial fan of bricks filled with cylinders.

The tongue is ``radial_sections`` fan sectors (from the genioglossus origin
to the surface) x ``concentric_sections`` x 2 layers between three sagittal
planes.  Every brick is filled with the 28 cylinders joining its 8 corners
(12 edges, 12 face diagonals, 4 body diagonals); cylinders shared by bricks
are merged once.

Cross-sections follow the paper's weighting rule (section II.B.2): a cylinder
shared by n bricks carries weight 1/n in each; brick m is imagined as one
uniform cylinder of length L_m = sum_c l_c / n_c and area A_m = V_m / L_m;
cylinder c gets A_c = sum_{m owns c} A_m / n_c.  Then
sum_c A_c l_c = sum_m A_m L_m = sum_m V_m: the cylinders fill the tongue.
(The paper's 0.5 and 0.25 are the interior values of n_c = 2 and 4.)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import combinations

import numpy as np

from ..config import TongueGeometry
from .hexahedra import corner_jacobians, volumes

PLANES = 3  # right (-z), midsagittal, left (+z)


@dataclass(frozen=True)
class Mesh:
    """Rest geometry and topology of a brick-and-cylinder body (lengths in cm)."""

    nodes: np.ndarray  # (N,3)
    bricks: np.ndarray  # (B,8) VTK corner order, positive orientation
    cylinders: np.ndarray  # (C,2) node pairs, i < j
    share: np.ndarray  # (C,) number of bricks sharing each cylinder
    areas: np.ndarray  # (C,) rest cross-section, cm^2
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    kind: str = "tongue"
    grid: tuple[int, ...] = ()

    @property
    def rest_lengths(self) -> np.ndarray:
        d = self.nodes[self.cylinders[:, 1]] - self.nodes[self.cylinders[:, 0]]
        return np.linalg.norm(d, axis=1)

    @property
    def volume(self) -> float:
        return float(volumes(self.nodes, self.bricks).sum())

    @property
    def cylinder_volume(self) -> float:
        return float((self.areas * self.rest_lengths).sum())


def resample_polyline(points: np.ndarray, n: int) -> np.ndarray:
    """``n`` points evenly spaced in arc length along a polyline."""
    p = np.asarray(points, dtype=float)
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(t, s, p[:, k]) for k in range(p.shape[1])])


def brick_cylinders(bricks: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unique corner pairs of all bricks, their share counts, and the map
    ``owner`` (B, 28) from each brick's pair slot to the unique cylinder."""
    pairs = np.array(list(combinations(range(8), 2)))  # 28 pairs
    allp = np.sort(bricks[:, pairs], axis=2).reshape(-1, 2)
    uniq, inverse, counts = np.unique(allp, axis=0, return_inverse=True, return_counts=True)
    return uniq, counts, inverse.reshape(bricks.shape[0], len(pairs))


def cylinder_areas(nodes: np.ndarray, bricks: np.ndarray, owner: np.ndarray,
                   cylinders: np.ndarray, share: np.ndarray) -> np.ndarray:
    """Cross-sections by the paper's weighting rule (see module docstring)."""
    length = np.linalg.norm(nodes[cylinders[:, 1]] - nodes[cylinders[:, 0]], axis=1)
    w = 1.0 / share
    eq_length = (length[owner] * w[owner]).sum(axis=1)  # L_m
    area_m = volumes(nodes, bricks) / eq_length  # A_m
    contrib = (area_m[:, None] * w[owner]).ravel()
    return np.bincount(owner.ravel(), weights=contrib, minlength=len(cylinders))


def _orient(nodes: np.ndarray, bricks: np.ndarray) -> np.ndarray:
    det = corner_jacobians(nodes, bricks)
    flip = det.mean(axis=1) < 0
    out = bricks.copy()
    out[flip] = out[flip][:, [0, 3, 2, 1, 4, 7, 6, 5]]
    return out


def assemble_mesh(nodes: np.ndarray, bricks: np.ndarray, node_sets: dict, kind: str,
                  grid: tuple[int, ...]) -> Mesh:
    bricks = _orient(nodes, bricks)
    if (corner_jacobians(nodes, bricks) <= 0).any():
        from ..errors import ArticError
        raise ArticError(f"{kind} mesh has a degenerate brick at rest; check the outline in the config")
    cyl, share, owner = brick_cylinders(bricks)
    areas = cylinder_areas(nodes, bricks, owner, cyl, share)
    return Mesh(nodes=nodes, bricks=bricks, cylinders=cyl, share=share, areas=areas,
                node_sets={k: np.asarray(v, dtype=np.int64) for k, v in node_sets.items()},
                kind=kind, grid=grid)


def tongue_node_index(k, j, p, n_conc: int):
    """Node number of radial line k, concentric level j, plane p.

    Numbering runs plane fastest, then level, then radial line, so nodes of
    one brick differ by at most 3*(n_conc+1)+4: the stiffness matrix is banded.
    """
    return (np.asarray(k) * (n_conc + 1) + np.asarray(j)) * PLANES + np.asarray(p)


def tongue_mesh(geo: TongueGeometry) -> Mesh:
    nr, nc = geo.radial_sections, geo.concentric_sections
    origin = np.asarray(geo.gg_origin_cm, dtype=float)
    surface = resample_polyline(geo.midsagittal_outline_cm, nr + 1)  # tip first
    levels = np.linspace(geo.inner_fraction, 1.0, nc + 1)
    mid = origin + levels[None, :, None] * (surface[:, None, :] - origin)  # (nr+1, nc+1, 2)
    lateral = origin + (1.0 - geo.parasagittal_shrink) * (mid - origin)
    lateral = lateral - np.array([0.0, geo.parasagittal_drop_cm])
    # the tip is narrower: the lateral planes recede behind it, most at the surface
    taper = np.clip(1.0 - np.arange(nr + 1) / max(geo.tip_taper_sections, 1), 0.0, 1.0)
    depth = (levels - levels[0]) / (levels[-1] - levels[0])
    lateral[..., 0] -= geo.parasagittal_tip_recess_cm * taper[:, None] * depth[None, :]
    w = geo.half_width_cm
    nodes = np.zeros((nr + 1, nc + 1, PLANES, 3))
    for p, (xy, z) in enumerate([(lateral, -w), (mid, 0.0), (lateral, w)]):
        nodes[:, :, p, :2] = xy
        nodes[:, :, p, 2] = z
    nodes = nodes.reshape(-1, 3)

    k, j, p = np.meshgrid(np.arange(nr), np.arange(nc), np.arange(PLANES - 1), indexing="ij")
    k, j, p = k.ravel(), j.ravel(), p.ravel()
    corner = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    # reference axes: xi1 = concentric level (outward), xi2 = radial line, xi3 = plane
    bricks = np.stack([tongue_node_index(k + dk, j + dj, p + dp, nc) for dj, dk, dp in corner], axis=1)

    idx = lambda kk, jj, pp: tongue_node_index(kk, jj, pp, nc)  # noqa: E731
    K, J, P = np.meshgrid(np.arange(nr + 1), np.arange(nc + 1), np.arange(PLANES), indexing="ij")
    sets = {
        "all": np.arange(len(nodes)),
        "anchor": idx(K[:, 0, :], 0, P[:, 0, :]).ravel(),
        "floor": idx(K[-1, :, :], J[-1, :, :], P[-1, :, :]).ravel(),
        "surface": idx(K[:, -1, :], nc, P[:, -1, :]).ravel(),
        "midsagittal_surface": idx(np.arange(nr + 1), nc, 1),
        "midsagittal": idx(K[:, :, 1], J[:, :, 1], 1).ravel(),
        "tip": np.array([idx(0, nc, 1)]),
        "tip_line": idx(np.zeros_like(J[0]), J[0], P[0]).ravel(),
        "dorsum": np.array([idx(min(4, nr), nc, 1)]),
        "blade": idx(K[:3, -1, :], nc, P[:3, -1, :]).ravel(),
        "dorsum_region": idx(K[3:7, -1, :], nc, P[3:7, -1, :]).ravel(),
        "root": idx(K[7:, -1, :], nc, P[7:, -1, :]).ravel(),
        "left": idx(K[:, :, 2], J[:, :, 2], 2).ravel(),
        "right": idx(K[:, :, 0], J[:, :, 0], 0).ravel(),
    }
    return assemble_mesh(nodes, bricks, sets, "tongue", (nr + 1, nc + 1, PLANES))


def _tributary(c: np.ndarray) -> np.ndarray:
    """Length each grid coordinate stands for along one axis (half cells at the ends)."""
    g = np.unique(c)
    half = np.diff(g) / 2.0
    share = np.concatenate([[0.0], half]) + np.concatenate([half, [0.0]])
    return share[np.searchsorted(g, c)]


def face_weights(nodes: np.ndarray, face: np.ndarray) -> np.ndarray:
    """Nodal shares (summing to 1) of a uniform traction on a box face normal to x."""
    w = _tributary(nodes[face, 1]) * _tributary(nodes[face, 2])
    return w / w.sum()


def cuboid_mesh(size_cm, bricks_per_axis) -> Mesh:
    """The paper's test body: a box of ``size_cm`` split into bricks (node numbering x slowest)."""
    nx, ny, nz = bricks_per_axis
    gx, gy, gz = (np.linspace(0, s, n + 1) for s, n in zip(size_cm, bricks_per_axis))
    X, Y, Z = np.meshgrid(gx, gy, gz, indexing="ij")
    nodes = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    idx = lambda i, j, k: (i * (ny + 1) + j) * (nz + 1) + k  # noqa: E731
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"))
    corner = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    bricks = np.stack([idx(i + a, j + b, k + c) for a, b, c in corner], axis=1)
    sets = {
        "all": np.arange(len(nodes)),
        "fixed_end": np.flatnonzero(np.isclose(nodes[:, 0], 0.0)),
        "pulled_end": np.flatnonzero(np.isclose(nodes[:, 0], size_cm[0])),
    }
    return assemble_mesh(nodes, bricks, sets, "cuboid", (nx + 1, ny + 1, nz + 1))
