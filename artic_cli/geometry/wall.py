"""The vocal-tract wall as a triangle surface.

Each wall part (palate with velum, posterior pharyngeal wall, lingual
surface of the mandibular symphysis) is given as an outline per sagittal
slice at z >= 0; slices are mirrored to -z, every outline is resampled to the
same number of points by arc length, and neighbouring slices are joined by
triangle strips whose diagonals mirror each other across z = 0.  Normals are
unit vectors pointing *out of the lumen* (into the wall): a tongue point p is
beyond a triangle when (p - q) . n > 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import WallGeometry
from .mesh import resample_polyline

PARTS = ("palate", "pharynx", "mandible")


@dataclass(frozen=True)
class WallSurface:
    vertices: np.ndarray  # (V,3) cm
    triangles: np.ndarray  # (T,3)
    normals: np.ndarray  # (T,3) unit, away from the lumen
    part: np.ndarray  # (T,) index into PARTS

    def part_mask(self, name: str) -> np.ndarray:
        return self.part == PARTS.index(name)


def triangle_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def wall_surface(geo: WallGeometry) -> WallSurface:
    slices = list(geo.slices)
    mirrored = [s for s in reversed(slices) if s.z_cm > 0]
    zs = [-s.z_cm for s in mirrored] + [s.z_cm for s in slices]
    ordered = mirrored + slices
    n = geo.points_per_outline
    verts, tris, parts = [], [], []
    offset = 0
    lumen = np.asarray(geo.lumen_reference_cm, dtype=float)
    for pi, name in enumerate(PARTS):
        grid = np.stack([np.column_stack([resample_polyline(getattr(s, name), n), np.full(n, z)])
                         for s, z in zip(ordered, zs)])  # (nz, n, 3)
        nz = grid.shape[0]
        ids = np.arange(nz * n).reshape(nz, n) + offset
        a, b, c, d = ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]
        # each quad is split along a-c on the +z side and along b-d on the -z side, so that the left half's
        # triangles are the mirror images of the right half's (the body is solved by halves)
        left = (np.asarray(zs[:-1]) < 0)[:, None]
        t = np.concatenate([np.stack([a, b, np.where(left, d, c)], -1).reshape(-1, 3),
                            np.stack([np.where(left, b, a), c, d], -1).reshape(-1, 3)])
        v = grid.reshape(-1, 3)
        nrm = triangle_normals(np.concatenate(verts + [v]) if verts else v, t)
        centre = (np.concatenate(verts + [v]) if verts else v)[t].mean(axis=1)
        if np.mean(np.einsum("ij,ij->i", nrm[:, :2], centre[:, :2] - lumen)) < 0:
            t = t[:, [0, 2, 1]]
        verts.append(v)
        tris.append(t)
        parts.append(np.full(len(t), pi))
        offset += len(v)
    vertices = np.concatenate(verts)
    triangles = np.concatenate(tris)
    return WallSurface(vertices=vertices, triangles=triangles,
                       normals=triangle_normals(vertices, triangles), part=np.concatenate(parts))
